// The denoiser's loops that vectorise (denoise.cpp's filter, rtwall/denoise.h), once per
// instruction set: the a-trous tap loop and the temporal phase's arithmetic of a row. Each is
// inlined into a function per ISA and vectorised there. Included by denoise.cpp alone, whose
// compile options (-O3, no FP contraction, no trapping maths, no errno) make every width give the
// same bytes as the scalar rule.
#pragma once

#include <rtwall/denoise.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace rtwall::denoise_detail {

constexpr float kAlbedoFloor = 1e-3f;  // below this a channel is not divided (nor multiplied back)
inline float demodulator(float albedo) { return albedo > kAlbedoFloor ? albedo : 1.0f; }
// A depth on a surface: positive and below kBackgroundDepth (so finite: NaN and infinity fail
// both). Bitwise, so that it vectorises.
[[gnu::always_inline]] inline bool isSurface(float z) { return (z > 0.0f) & (z < kBackgroundDepth); }

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

// The temporal phase's arithmetic for one row of the window, everything in it that does not
// depend on the history: the pixels' depth gradients and where their surface points lie in the
// previous frame. Branch-free, so that it vectorises (doubles: 2, 4 or 8 lanes); the
// per-pixel part that reads the history (four taps, each refused or kept) stays scalar.
struct TemporalRow {
    int w;
    const float *z, *zUp, *zDown;            // the row's depths and its neighbours' (zUp/zDown: this row if none)
    const uint32_t *id, *idUp, *idDown;      // their ids
    const float* normal;                     // the row's normals, 3 a pixel
    bool up, down;                           // whether the rows above and below are in the window
    bool reproject;                          // a moving view with a history: where its points were
    float cornerX, cornerY, cornerZ, duX, duY, duZ, dvX, dvY, dvZ;  // this camera (Camera::flatDirection)
    float py;                                // the row's image position, float(wy + y) + 0.5f
    int wx, wy;                              // the window's place in its frame
    double origin[3];                        // this camera's origin
    double prevOrigin[3], inv[3][3];         // the previous camera (ImageProjection)
};

// The depth gradient of pixel x of a row (below): its neighbours before and after along x exist
// where hasBefore/hasAfter (the row's ends), above and below where the row says. Bitwise logic,
// unconditional loads and selects: no control flow, so that the loop vectorises.
[[gnu::always_inline]] inline void rowGradient(const TemporalRow& r, int x, bool hasBefore, bool hasAfter, float* __restrict gx,
                                               float* __restrict gy, float* __restrict gradient) {
    const float* z = r.z;
    const uint32_t* id = r.id;
    const float zc = z[x];
    const uint32_t ic = id[x];
    const int xl = hasBefore ? x - 1 : x, xr = hasAfter ? x + 1 : x;
    const bool okL = hasBefore & (id[xl] == ic) & isSurface(z[xl]);
    const bool okR = hasAfter & (id[xr] == ic) & isSurface(z[xr]);
    const float dL = -1.0f * (z[xl] - zc), dR = 1.0f * (z[xr] - zc);
    const float bl = okL ? dL : INFINITY;
    const float bx = okR & (std::fabs(dR) < std::fabs(bl)) ? dR : bl;
    const bool okU = r.up & (r.idUp[x] == ic) & isSurface(r.zUp[x]);
    const bool okD = r.down & (r.idDown[x] == ic) & isSurface(r.zDown[x]);
    const float dU = -1.0f * (r.zUp[x] - zc), dD = 1.0f * (r.zDown[x] - zc);
    const float bu = okU ? dU : INFINITY;
    const float by = okD & (std::fabs(dD) < std::fabs(bu)) ? dD : bu;
    const bool surface = isSurface(zc);
    const float g0 = surface & (bx != INFINITY) ? bx : 0.0f, g1 = surface & (by != INFINITY) ? by : 0.0f;
    gx[x] = g0;
    gy[x] = g1;
    gradient[x] = std::max(std::fabs(g0), std::fabs(g1));
}

// Per pixel x: nx, ny, nz (its unit normal, zero without one); gx, gy (signed depth change per step along x and y: per axis the smaller
// one-sided difference to a neighbour of the same object, the one before on a tie), gradient
// (the larger size; all three 0 off a surface); px, py (its point's place in the previous
// frame's window, -1e9 behind that camera) and expected (its distance from that camera), where
// r.reproject; pixels off a surface get px, py and expected of no meaning.
[[gnu::always_inline]] inline void temporalRowLoop(const TemporalRow& r, float* __restrict nx, float* __restrict ny,
                                                   float* __restrict nz, float* __restrict gx, float* __restrict gy,
                                                   float* __restrict gradient, double* __restrict px,
                                                   double* __restrict py, float* __restrict expected) {
    const int w = r.w;
    const float* n = r.normal;
    for (int x = 0; x < w; ++x) {
        const float a = n[3 * x], b = n[3 * x + 1], c = n[3 * x + 2];
        const float l = std::sqrt(a * a + b * b + c * c);
        const float inv = 1.0f / l;
        const float s = (l > 0.0f) & (l < INFINITY) ? inv : 0.0f;  // l is never negative: finite and positive
        nx[x] = a * s, ny[x] = b * s, nz[x] = c * s;
    }
    rowGradient(r, 0, false, w > 1, gx, gy, gradient);
    for (int x = 1; x < w - 1; ++x) rowGradient(r, x, true, true, gx, gy, gradient);
    if (w > 1) rowGradient(r, w - 1, true, false, gx, gy, gradient);
    if (!r.reproject) return;
    // The surface point: along the pixel's ray at its depth (Camera::flatDirection's sums in
    // their order), solved for the previous camera's image (ImageProjection::solve).
    const float* z = r.z;
    const float ux = r.duX, uy = r.duY, uz = r.duZ, vx = r.dvX * r.py, vy = r.dvY * r.py, vz = r.dvZ * r.py;
    const float ox = r.cornerX, oy = r.cornerY, oz = r.cornerZ;
    const double o0 = r.origin[0], o1 = r.origin[1], o2 = r.origin[2];
    const double p0 = r.prevOrigin[0], p1 = r.prevOrigin[1], p2 = r.prevOrigin[2];
    const double m00 = r.inv[0][0], m01 = r.inv[0][1], m02 = r.inv[0][2], m10 = r.inv[1][0], m11 = r.inv[1][1],
                 m12 = r.inv[1][2], m20 = r.inv[2][0], m21 = r.inv[2][1], m22 = r.inv[2][2];
    const double wxD = r.wx, wyD = r.wy;
    const int wx = r.wx;
    for (int x = 0; x < w; ++x) {
        const float fx = float(wx + x) + 0.5f;
        const float dx = ox + ux * fx + vx, dy = oy + uy * fx + vy, dz = oz + uz * fx + vz;
        const double dl = std::sqrt(double(dx) * dx + double(dy) * dy + double(dz) * dz);
        const double s = double(z[x]) / dl;
        const double v0 = o0 + double(dx) * s - p0;
        const double v1 = o1 + double(dy) * s - p1;
        const double v2 = o2 + double(dz) * s - p2;
        const double a = m00 * v0 + m01 * v1 + m02 * v2;
        const double b = m10 * v0 + m11 * v1 + m12 * v2;
        const double c = m20 * v0 + m21 * v1 + m22 * v2;
        const double qa = a / c, qb = b / c;
        px[x] = c > 0.0 ? qa - 0.5 - wxD : -1e9;
        py[x] = c > 0.0 ? qb - 0.5 - wyD : -1e9;
        expected[x] = float(std::sqrt(v0 * v0 + v1 * v1 + v2 * v2));
    }
}

#define RTWALL_ROW_ARGS                                                                                 \
    const TemporalRow &r, float *__restrict nx, float *__restrict ny, float *__restrict nz, float *__restrict gx, float *__restrict gy, float *__restrict gradient, \
        double *__restrict px, double *__restrict py, float *__restrict expected
inline void temporalRowSse2(RTWALL_ROW_ARGS) { temporalRowLoop(r, nx, ny, nz, gx, gy, gradient, px, py, expected); }
[[gnu::target("avx2")]] inline void temporalRowAvx2(RTWALL_ROW_ARGS) {
    temporalRowLoop(r, nx, ny, nz, gx, gy, gradient, px, py, expected);
}
[[gnu::target("avx512f,avx512vl,prefer-vector-width=512")]] inline void temporalRowAvx512(RTWALL_ROW_ARGS) {
    temporalRowLoop(r, nx, ny, nz, gx, gy, gradient, px, py, expected);
}
inline void temporalRow(DenoiseIsa isa, RTWALL_ROW_ARGS) {
    switch (isa) {
    case DenoiseIsa::Avx512: return temporalRowAvx512(r, nx, ny, nz, gx, gy, gradient, px, py, expected);
    case DenoiseIsa::Avx2: return temporalRowAvx2(r, nx, ny, nz, gx, gy, gradient, px, py, expected);
    default: return temporalRowSse2(r, nx, ny, nz, gx, gy, gradient, px, py, expected);
    }
}
#undef RTWALL_ROW_ARGS

// The demodulated luminance of each pixel of a row (lum) and whether it has one (ok, 1 or 0: a
// finite sample on a surface): what the firefly clamp's mean of the 3x3 neighbours sums.
// albedo: the row's (3 a pixel), or null for white. Vectorised per instruction set as above.
[[gnu::always_inline]] inline void luminanceRowLoop(int w, const float* rgb, const float* albedo, const float* z,
                                                    float* __restrict lum, float* __restrict ok) {
    for (int x = 0; x < w; ++x) {
        const float r = rgb[3 * x], g = rgb[3 * x + 1], b = rgb[3 * x + 2];
        const bool finite = (std::fabs(r) < INFINITY) & (std::fabs(g) < INFINITY) & (std::fabs(b) < INFINITY);
        const float ar = albedo ? albedo[3 * x] : 1.0f, ag = albedo ? albedo[3 * x + 1] : 1.0f,
                    ab = albedo ? albedo[3 * x + 2] : 1.0f;
        lum[x] = 0.2126f * (r / demodulator(ar)) + 0.7152f * (g / demodulator(ag)) + 0.0722f * (b / demodulator(ab));
        ok[x] = finite & isSurface(z[x]) ? 1.0f : 0.0f;
    }
}
#define RTWALL_LUM_ARGS int w, const float *rgb, const float *albedo, const float *z, float *__restrict lum, float *__restrict ok
inline void luminanceRowSse2(RTWALL_LUM_ARGS) {
    if (albedo) luminanceRowLoop(w, rgb, albedo, z, lum, ok);
    else luminanceRowLoop(w, rgb, nullptr, z, lum, ok);
}
[[gnu::target("avx2")]] inline void luminanceRowAvx2(RTWALL_LUM_ARGS) {
    if (albedo) luminanceRowLoop(w, rgb, albedo, z, lum, ok);
    else luminanceRowLoop(w, rgb, nullptr, z, lum, ok);
}
[[gnu::target("avx512f,avx512vl,prefer-vector-width=512")]] inline void luminanceRowAvx512(RTWALL_LUM_ARGS) {
    if (albedo) luminanceRowLoop(w, rgb, albedo, z, lum, ok);
    else luminanceRowLoop(w, rgb, nullptr, z, lum, ok);
}
inline void luminanceRow(DenoiseIsa isa, RTWALL_LUM_ARGS) {
    switch (isa) {
    case DenoiseIsa::Avx512: return luminanceRowAvx512(w, rgb, albedo, z, lum, ok);
    case DenoiseIsa::Avx2: return luminanceRowAvx2(w, rgb, albedo, z, lum, ok);
    default: return luminanceRowSse2(w, rgb, albedo, z, lum, ok);
    }
}
#undef RTWALL_LUM_ARGS

}  // namespace rtwall::denoise_detail
