// The denoiser's a-trous tap loop (denoise.cpp's filter, rtwall/denoise.h), once per instruction
// set: the loop is inlined into a function per ISA and vectorised there. Included by
// denoise.cpp alone, whose compile options (-O3, no FP contraction, no trapping maths) make every
// width give the same bytes.
#pragma once

#include <rtwall/denoise.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace rtwall::denoise_detail {

// e^x for x <= 0 (what the edge stops need), to 2e-6 relative: 2^(x log2 e) as the exponent
// bits of its whole part times a degree-7 polynomial of its fraction. Branch-free and the same
// bits on every thread and CPU (no libm, whose vector and scalar forms may differ); several
// times cheaper than expf, which was a third of the filter's time.
inline float expNegative(float x) {
    const float t = std::max(x, -87.0f) * 1.44269504088896f + 127.0f;  // in (1.4, 127]
    const int whole = int(t);                                        // floor: t > 0
    const float f = t - float(whole);
    const float p =
        1.0f + f * (0.693147181f + f * (0.240226507f + f * (0.0555041087f + f * (0.00961812911f +
        f * (0.00133335581f + f * (0.000154035304f + f * 0.0000152527338f))))));
    return p * std::bit_cast<float>(uint32_t(whole) << 23);
}

// The B3 spline's taps, -2..2.
constexpr float kB3[5] = {1.0f / 16, 1.0f / 4, 3.0f / 8, 1.0f / 4, 1.0f / 16};

// One a-trous tap for a row: the centre pixels' and the neighbours' planes at the tap's offset.
struct TapRow {
    const float *rc, *gc, *bc, *rq, *gq, *bq, *zc, *zq, *invL, *nxc, *nyc, *nzc, *nxq, *nyq, *nzq, *vq;
    const uint32_t *kc, *kq;
    const float *gx, *gy, *eps;  // the depth stop: sigma_depth times the gradient, and its floor
    float ox, oy;                // the tap's offset in pixels
};

// Adds the tap's weighted neighbours of pixels [xa, xb) to the sums. Restrict-qualified sums
// and no trapping maths (denoise.cpp's compile options) let the compiler vectorise it: without
// them it has too many pointers to check for overlap, and a conversion that may trap. Inlined
// into one function per instruction set (below), vectorised there at that width.
template <class Power>
[[gnu::always_inline]] inline void tapLoop(const TapRow& t, int xa, int xb, float b3, Power power, float* __restrict sumW,
                                           float* __restrict sr, float* __restrict sg, float* __restrict sb,
                                           float* __restrict sv) {
    const float *rc = t.rc, *gc = t.gc, *bc = t.bc, *rq = t.rq, *gq = t.gq, *bq = t.bq;
    for (int x = xa; x < xb; ++x) {
        const float lc = 0.2126f * rc[x] + 0.7152f * gc[x] + 0.0722f * bc[x];
        const float lq = 0.2126f * rq[x] + 0.7152f * gq[x] + 0.0722f * bq[x];
        const float phiZ = std::fabs(t.gx[x] * t.ox + t.gy[x] * t.oy) + t.eps[x];
        const float logW = std::fabs(t.zq[x] - t.zc[x]) / phiZ + std::fabs(lq - lc) * t.invL[x];
        const float cn = power(std::max(0.0f, t.nxc[x] * t.nxq[x] + t.nyc[x] * t.nyq[x] + t.nzc[x] * t.nzq[x]));
        const float wt = float(t.kq[x] == t.kc[x]) * (b3 * cn * expNegative(-logW));
        sumW[x] += wt;
        sr[x] += wt * rq[x];
        sg[x] += wt * gq[x];
        sb[x] += wt * bq[x];
        sv[x] += wt * wt * t.vq[x];
    }
}

// The tap loop for each instruction set: 4 lanes (SSE2, the baseline), 8 (AVX2), 16 (AVX-512).
// Each lane does the scalar rule's operations in its order (no FMA contraction: -ffp-contract=off,
// no approximate division or square root), so every width gives the same bytes.
#define RTWALL_TAPS_ARGS                                                                                        \
    const TapRow &t, int xa, int xb, float b3, Power power, float *__restrict sumW, float *__restrict sr, \
        float *__restrict sg, float *__restrict sb, float *__restrict sv
template <class Power> void tapsSse2(RTWALL_TAPS_ARGS) { tapLoop(t, xa, xb, b3, power, sumW, sr, sg, sb, sv); }
template <class Power> [[gnu::target("avx2")]] void tapsAvx2(RTWALL_TAPS_ARGS) {
    tapLoop(t, xa, xb, b3, power, sumW, sr, sg, sb, sv);
}
template <class Power> [[gnu::target("avx512f,avx512vl,prefer-vector-width=512")]] void tapsAvx512(RTWALL_TAPS_ARGS) {
    tapLoop(t, xa, xb, b3, power, sumW, sr, sg, sb, sv);
}
template <class Power> void accumulateTaps(DenoiseIsa isa, RTWALL_TAPS_ARGS) {
    switch (isa) {
    case DenoiseIsa::Avx512: return tapsAvx512(t, xa, xb, b3, power, sumW, sr, sg, sb, sv);
    case DenoiseIsa::Avx2: return tapsAvx2(t, xa, xb, b3, power, sumW, sr, sg, sb, sv);
    default: return tapsSse2(t, xa, xb, b3, power, sumW, sr, sg, sb, sv);
    }
}
#undef RTWALL_TAPS_ARGS

}  // namespace rtwall::denoise_detail
