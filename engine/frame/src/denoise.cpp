// Denoiser (rtwall/denoise.h): temporal reuse by re-projection and the edge-avoiding a-trous
// wavelet filter of SVGF (Schied et al., HPG 2017; Dammertz et al., HPG 2010), on the CPU, row
// parallel. Every phase reads only what the phases before it wrote, and each pixel's value
// depends only on its inputs, never on the order or thread it was computed in.
#include <rtwall/denoise.h>

#include "denoise_taps.h"
#include "denoise_workers.h"
#include <rtwall/depth_codec.h>
#include <rtwall/warp.h>

#include <algorithm>
#include <barrier>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace rtwall {

namespace {

using denoise_detail::demodulator;
using denoise_detail::isSurface;

using namespace denoise_detail;

constexpr float kNormalCosine = 0.906f;   // history from a normal within 25 degrees
constexpr float kDepthTolerance = 0.02f;  // history from a depth within 2 % (+ 1.5 pixel steps of depth)
constexpr float kTapWeightFloor = 0.01f;  // less bilinear weight than this in agreeing taps: no history
constexpr uint32_t kBackgroundKey = 0xFFFFFFFDu;  // centre_ of a pixel the filter passes through
constexpr uint32_t kNoKey = 0xFFFFFFFCu;          // key_ of a pixel that is no one's neighbour
constexpr int kShortHistory = 4;          // fewer frames: the variance is estimated over 7x7 neighbours
// Fireflies: while the view moves and a pixel's history is shorter than `history` frames, a new
// sample brighter than this many times the brighter of its history's mean and its 3x3
// neighbours' mean (same object) is scaled down to that (a rare path that found the light would
// otherwise shine for `history` frames and spread through the filter). A still view's frames go
// in as they are: its mean is the Accumulator's, which converges to the unbiased one.
constexpr float kFireflyRatio = 8.0f;

inline float luminance(const float* c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }



std::pair<int, int> rowsOf(int n, int threads, int i) {
    return {int(int64_t(n) * i / threads), int(int64_t(n) * (i + 1) / threads)};
}

void checkSpan(size_t got, size_t want, const char* what) {
    if (got != want)
        throw std::invalid_argument(std::string("Denoiser: ") + what + " has " + std::to_string(got) + " values, not " +
                                    std::to_string(want));
}

}  // namespace

void quantiseAsSent(FeatureFrame& f, uint8_t bits) {
    std::vector<uint16_t> halfs(f.linear.size());
    halfFromFloat(f.linear.data(), f.linear.size(), halfs.data());
    floatFromHalf(halfs.data(), halfs.size(), f.linear.data());
    for (float& d : f.depth) d = decodeDepth(encodeDepth(d));
    if (!(bits & kFeatureAlbedo)) f.albedo.clear();
    if (!(bits & kFeatureNormal)) f.normal.clear();
    if (!(bits & kFeatureId)) f.id.clear();
    quantiseFeatures(bits & (kFeatureAlbedo | kFeatureNormal), f.albedo.data(), f.normal.data(), f.depth.size());
}

int denoiseRing(const DenoiseSettings& settings) {
    if (settings.mode == DenoiseSettings::Mode::Off) return 0;
    constexpr int kMargin = 8, kNeighbourhood = 1 + 3;  // 3x3 firefly and gradient, 7x7 short history
    if (settings.mode == DenoiseSettings::Mode::Temporal) return kNeighbourhood + kMargin;
    const int levels = std::clamp(settings.levels, 1, 10);
    return 2 * ((1 << levels) - 1) + levels + kNeighbourhood + kMargin;
}

void Denoiser::resize(int w, int h) {
    const size_t n = size_t(w) * size_t(h);
    for (auto* v : {&colour_, &colourPrev_, &albedo_, &albedoPrev_, &normalPrev_, &filtered_, &filteredB_,
                    &unit_, &out_})
        v->resize(n * 3);
    for (auto* v : {&moments_, &momentsPrev_}) v->resize(n * 2);
    for (auto* v : {&length_, &lengthPrev_, &depthPrev_, &variance_, &varianceB_, &gradient_, &zf_, &gx_, &gy_}) v->resize(n);
    idPrev_.resize(n);
    valid_.resize(n);
    known_.resize(n);
    key_.resize(n);
    centre_.resize(n);
    if (w != width_ || h != height_) hasPrevious_ = false;
    width_ = w;
    height_ = h;
}

std::span<const float> Denoiser::denoise(const DenoiseInput& in, const DenoiseSettings& settings, int threadCount) {
    const int w = in.width, h = in.height;
    if (w <= 0 || h <= 0) throw std::invalid_argument("Denoiser: empty frame " + std::to_string(w) + "x" + std::to_string(h));
    const size_t n = size_t(w) * size_t(h);
    checkSpan(in.linear.size(), n * 3, "the colour");
    checkSpan(in.depth.size(), n, "the depth");
    const bool filter = settings.mode == DenoiseSettings::Mode::Svgf;
    if (filter || !in.albedo.empty()) checkSpan(in.albedo.size(), n * 3, "the albedo");  // temporal: none is white
    checkSpan(in.normal.size(), n * 3, "the normal");
    checkSpan(in.id.size(), n, "the id");
    const int fw = in.frameWidth > 0 ? in.frameWidth : w, fh = in.frameWidth > 0 ? in.frameHeight : h;
    const int wx = in.frameWidth > 0 ? in.x0 : 0, wy = in.frameWidth > 0 ? in.y0 : 0;
    if (wx < 0 || wy < 0 || wx + w > fw || wy + h > fh)
        throw std::invalid_argument("Denoiser: a window of " + std::to_string(w) + "x" + std::to_string(h) + " at (" +
                                    std::to_string(wx) + ", " + std::to_string(wy) + ") is not inside its " +
                                    std::to_string(fw) + "x" + std::to_string(fh) + " frame");
    resize(w, h);
    if (wx != x0_ || wy != y0_ || fw != frameWidth_ || fh != frameHeight_) hasPrevious_ = false;
    x0_ = wx, y0_ = wy, frameWidth_ = fw, frameHeight_ = fh;

    const bool restart = !hasPrevious_ || in.stateSeq != previousState_;
    const bool still = !restart && samePose(in.camera, previousCamera_);
    const int levels = filter ? std::clamp(settings.levels, 1, 10) : 0;
    const float cap = still ? INFINITY : float(std::max(1, settings.history));
    const float sigmaZ = std::isfinite(settings.sigmaDepth) && settings.sigmaDepth > 0 ? settings.sigmaDepth : 1.0f;
    const float sigmaN = std::isfinite(settings.sigmaNormal) && settings.sigmaNormal >= 0 ? settings.sigmaNormal : 128.0f;
    const float sigmaL = std::isfinite(settings.sigmaLuminance) && settings.sigmaLuminance > 0 ? settings.sigmaLuminance : 4.0f;

    // The camera's geometry is the whole frame's; pixel (x, y) of the window is its (wx + x, wy + y).
    const Camera camera(in.camera, fw, fh);
    const Float3 origin = camera.origin();
    const ImageProjection previous(previousCamera_, fw, fh);

    const DenoiseIsa isa = resolvedDenoiseIsa(denoiseIsa());
    const int hardware = int(std::max(1u, std::thread::hardware_concurrency()));
    const int threads = std::clamp(threadCount > 0 ? threadCount : hardware, 1, h);
    partStats_.assign(size_t(threads), DenoiseStats{});
    rowScratch_.resize(size_t(threads) * 9 * size_t(w));
    if (!pool_.workers || pool_.workers->threads() != threads) pool_.workers = std::make_unique<DenoiseWorkers>(threads);
    std::barrier<>& sync = pool_.workers->sync();

    const float* rgb = in.linear.data();
    const float* depth = in.depth.data();
    const float* albedo = in.albedo.empty() ? nullptr : in.albedo.data();
    static constexpr float kWhite[3] = {1.0f, 1.0f, 1.0f};
    const float* normal = in.normal.data();
    const uint32_t* id = in.id.data();

    // The history (colour, albedo, luminance moments) joined by a sample with weight a.
    auto blend = [](const float* hc, const float* ha, const float* hm, const float* c, const float* al, float l, float a,
                    float* co, float* ao, float* mo) {
        for (int k = 0; k < 3; ++k) {
            co[k] = hc[k] + (c[k] - hc[k]) * a;
            ao[k] = ha[k] + (al[k] - ha[k]) * a;
        }
        mo[0] = hm[0] + (l - hm[0]) * a;
        mo[1] = hm[1] + (l * l - hm[1]) * a;
    };

    // Phase 1: re-project the history (colour, albedo, luminance moments), average.
    // The rows' arithmetic that does not read the history (depth gradients; where each point
    // lies in the previous frame) comes first, vectorised per instruction set
    // (denoise_detail::temporalRow); the per-pixel rest is scalar.
    const bool reproject = !still && !restart;
    denoise_detail::TemporalRow rowIn{};
    rowIn.w = w;
    rowIn.reproject = reproject;
    rowIn.cornerX = camera.corner().x, rowIn.cornerY = camera.corner().y, rowIn.cornerZ = camera.corner().z;
    rowIn.duX = camera.du().x, rowIn.duY = camera.du().y, rowIn.duZ = camera.du().z;
    rowIn.dvX = camera.dv().x, rowIn.dvY = camera.dv().y, rowIn.dvZ = camera.dv().z;
    rowIn.wx = wx, rowIn.wy = wy;
    rowIn.origin[0] = double(origin.x), rowIn.origin[1] = double(origin.y), rowIn.origin[2] = double(origin.z);
    for (int k = 0; k < 3; ++k) {
        rowIn.prevOrigin[k] = previous.origin[k];
        for (int j = 0; j < 3; ++j) rowIn.inv[k][j] = previous.inv[k][j];
    }
    reprojected_.resize(size_t(threads) * 2 * size_t(w));

    auto temporal = [&](int y0, int y1, DenoiseStats& st, int part) {
        // Plain pointers: a store through valid_ (bytes may alias anything) would otherwise make
        // the compiler load every vector's data pointer again.
        const float* const colourPrevP = colourPrev_.data();
        const float* const albedoPrevP = albedoPrev_.data();
        const float* const momentsPrevP = momentsPrev_.data();
        const float* const lengthPrevP = lengthPrev_.data();
        const uint32_t* const idPrevP = idPrev_.data();
        const float* const normalPrevP = normalPrev_.data();
        const float* const depthPrevP = depthPrev_.data();
        float* const colourP = colour_.data();
        float* const albedoP = albedo_.data();
        float* const momentsP = moments_.data();
        float* const lengthP = length_.data();
        uint8_t* const validP = valid_.data();
        float* const unitP = unit_.data();
        float* const gradientP = gradient_.data();
        double* pxRow = &reprojected_[size_t(part) * 2 * size_t(w)];
        double* pyRow = pxRow + w;
        float* expectedRow = &rowScratch_[size_t(part) * 9 * size_t(w)];
        // Rows y - 1, y and y + 1's demodulated luminances (and whether each pixel has one) for
        // the firefly clamp of a moving view: row r in slot r % 3.
        float* lumRing = expectedRow + w;
        float* okRing = expectedRow + 4 * size_t(w);
        auto luminances = [&](int yy) {
            const size_t row = size_t(yy) * size_t(w), slot = size_t(yy % 3) * size_t(w);
            denoise_detail::luminanceRow(isa, w, rgb + 3 * row, albedo ? albedo + 3 * row : nullptr, depth + row,
                                         lumRing + slot, okRing + slot);
        };
        if (!still)
            for (int yy = std::max(0, y0 - 1); yy <= y0 && yy < y1; ++yy) luminances(yy);
        // The mean demodulated luminance of (x, y)'s 3x3 neighbours of the same object with a
        // finite sample (0: none).
        auto neighbourMean = [&](int x, int y) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            float sum = 0.0f;
            int count = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int qx = x + dx, qy = y + dy;
                    if ((dx == 0 && dy == 0) || qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
                    const size_t q = size_t(qy) * size_t(w) + size_t(qx), slot = size_t(qy % 3) * size_t(w) + size_t(qx);
                    if (id[q] != id[i] || okRing[slot] == 0.0f) continue;
                    sum += lumRing[slot];
                    ++count;
                }
            return count ? sum / float(count) : 0.0f;
        };
        for (int y = y0; y < y1; ++y) {
            const size_t row = size_t(y) * size_t(w);
            denoise_detail::TemporalRow tr = rowIn;
            tr.z = depth + row, tr.id = id + row;
            tr.up = y > 0, tr.down = y + 1 < h;
            tr.zUp = tr.up ? tr.z - w : tr.z, tr.idUp = tr.up ? tr.id - w : tr.id;
            tr.zDown = tr.down ? tr.z + w : tr.z, tr.idDown = tr.down ? tr.id + w : tr.id;
            tr.py = float(wy + y) + 0.5f;
            tr.normal = normal + 3 * row;
            if (!still && y + 1 < h) luminances(y + 1);
            denoise_detail::temporalRow(isa, tr, &unitP[row], &unitP[n + row], &unitP[2 * n + row], &gx_[row], &gy_[row],
                                        &gradientP[row], pxRow, pyRow, expectedRow);
            for (int x = 0; x < w; ++x) {
                const size_t i = size_t(y) * size_t(w) + size_t(x);
                const float* c = rgb + 3 * i;
                const float* al = albedo ? albedo + 3 * i : kWhite;
                const bool finite = std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
                if (!finite) ++st.invalid;
                float* co = &colourP[3 * i];
                float* ao = &albedoP[3 * i];
                float* mo = &momentsP[2 * i];
                for (int k = 0; k < 3; ++k) ao[k] = al[k];
                if (!isSurface(depth[i])) {  // background (or no depth)
                    // A still view averages it as every pixel: a pixel whose samples fall on a
                    // leaf in some frames and on the sky in others (a silhouette) converges to
                    // the plain mean of all of them, as with the Accumulator. Moving: shown as
                    // it came.
                    if (still && lengthPrevP[i] > 0.0f) {
                        const float* hc = &colourPrevP[3 * i];
                        const float* ha = &albedoPrevP[3 * i];
                        const float* hm = &momentsPrevP[2 * i];
                        validP[i] = 1;
                        if (!finite) {  // nothing new: the history as it was
                            lengthP[i] = lengthPrevP[i];
                            for (int k = 0; k < 3; ++k) co[k] = hc[k], ao[k] = ha[k];
                            mo[0] = hm[0], mo[1] = hm[1];
                            continue;
                        }
                        const float len = lengthPrevP[i] + 1.0f, a = 1.0f / len;
                        float il[3];
                        for (int k = 0; k < 3; ++k) il[k] = c[k] / demodulator(al[k]);
                        const float l = luminance(il);
                        blend(hc, ha, hm, c, al, l, a, co, ao, mo);
                        lengthP[i] = len;
                        ++st.reused;
                        st.maxHistory = std::max(st.maxHistory, int(std::min(len, 1e9f)));
                        continue;
                    }
                    validP[i] = finite;
                    lengthP[i] = finite ? 1.0f : 0.0f;
                    for (int k = 0; k < 3; ++k) co[k] = finite ? c[k] : 0.0f;
                    mo[0] = mo[1] = 0.0f;
                    continue;
                }
                // The history: this pixel's own when still, else bilinear at the point's place in
                // the previous frame, over the taps that saw the same surface.
                float hist[3] = {0, 0, 0}, histAl[3] = {0, 0, 0}, histMo[2] = {0, 0}, histLen = 0.0f;
                auto take = [&](size_t q, float wt) {
                    for (int k = 0; k < 3; ++k) {
                        hist[k] += wt * colourPrevP[3 * q + k];
                        histAl[k] += wt * albedoPrevP[3 * q + k];
                    }
                    histMo[0] += wt * momentsPrevP[2 * q];
                    histMo[1] += wt * momentsPrevP[2 * q + 1];
                    histLen += wt * lengthPrevP[q];
                };
                if (still) {
                    if (lengthPrevP[i] > 0.0f) take(i, 1.0f);
                } else if (!restart) {
                    const double px = pxRow[x], py = pyRow[x];
                    if (px > -2.0 && py > -2.0 && px < double(w) + 1.0 && py < double(h) + 1.0) {
                        const float expected = expectedRow[x];
                        const float tolerance = kDepthTolerance * expected + 1.5f * gradientP[i];
                        const float un[3] = {unitP[i], unitP[n + i], unitP[2 * n + i]};
                        const int x0 = int(std::floor(px)), yy0 = int(std::floor(py));
                        const float tx = float(px - x0), ty = float(py - yy0);
                        float sumW = 0.0f;
                        for (int t = 0; t < 4; ++t) {
                            const int qx = x0 + (t & 1), qy = yy0 + (t >> 1);
                            if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
                            const size_t q = size_t(qy) * size_t(w) + size_t(qx);
                            if (lengthPrevP[q] <= 0.0f || idPrevP[q] != id[i]) continue;
                            const float* pn = &normalPrevP[3 * q];
                            if (pn[0] * un[0] + pn[1] * un[1] + pn[2] * un[2] < kNormalCosine) continue;
                            if (!(std::fabs(depthPrevP[q] - expected) <= tolerance)) continue;
                            const float wt = ((t & 1) ? tx : 1.0f - tx) * ((t >> 1) ? ty : 1.0f - ty);
                            if (!(wt > 0.0f)) continue;
                            sumW += wt;
                            take(q, wt);
                        }
                        if (sumW >= kTapWeightFloor) {
                            const float r = 1.0f / sumW;
                            for (int k = 0; k < 3; ++k) hist[k] *= r, histAl[k] *= r;
                            histMo[0] *= r, histMo[1] *= r;
                            histLen *= r;
                        } else {
                            histLen = 0.0f;
                        }
                    }
                    if (histLen <= 0.0f) ++st.rejected;
                }
                if (histLen > 0.0f) ++st.reused;
                if (!finite) {  // nothing new: the history as it was (or nothing)
                    validP[i] = histLen > 0.0f;
                    lengthP[i] = histLen;
                    for (int k = 0; k < 3; ++k) co[k] = hist[k];
                    if (histLen > 0.0f)
                        for (int k = 0; k < 3; ++k) ao[k] = histAl[k];
                    mo[0] = histMo[0], mo[1] = histMo[1];
                    continue;
                }
                float il[3];
                for (int k = 0; k < 3; ++k) il[k] = c[k] / demodulator(al[k]);
                float l = luminance(il);
                float scaled[3] = {c[0], c[1], c[2]};
                if (!still && histLen < float(settings.history)) {
                    const float limit = kFireflyRatio * std::max(histLen > 0.0f ? histMo[0] : 0.0f, neighbourMean(x, y));
                    if (l > limit && limit > 0.0f) {
                        const float scale = limit / l;
                        for (int k = 0; k < 3; ++k) scaled[k] *= scale, il[k] *= scale;
                        l = limit;
                        ++st.clamped;
                    }
                }
                c = scaled;
                validP[i] = 1;
                if (histLen > 0.0f) {
                    const float len = std::min(histLen + 1.0f, std::max(cap, 1.0f));
                    const float a = 1.0f / len;
                    blend(hist, histAl, histMo, c, al, l, a, co, ao, mo);
                    lengthP[i] = len;
                } else {
                    for (int k = 0; k < 3; ++k) co[k] = c[k];
                    mo[0] = l, mo[1] = l * l;
                    lengthP[i] = 1.0f;
                }
                st.maxHistory = std::max(st.maxHistory, int(std::min(lengthP[i], 1e9f)));
            }
        }
    };

    // The edge stops between pixel i and neighbour q at `reach` pixel steps (depth, normal, id).
    // cosine^sigmaN: by squarings when the exponent is a whole number (128: seven), else pow.
    const bool wholeExponent = sigmaN == std::floor(sigmaN) && sigmaN <= 65536.0f;
    const uint32_t exponent = wholeExponent ? uint32_t(sigmaN) : 0;
    const bool powerOfTwo = wholeExponent && exponent > 0 && std::has_single_bit(exponent);
    const int squarings = powerOfTwo ? std::countr_zero(exponent) : 0;
    auto normalPower = [&](float c) {
        if (powerOfTwo) {
            for (int k = 0; k < squarings; ++k) c *= c;
            return c;
        }
        if (!wholeExponent) return std::pow(c, sigmaN);
        float r = 1.0f, b = c;
        for (uint32_t e = exponent; e; e >>= 1, b *= b)
            if (e & 1) r *= b;
        return r;
    };
    // The edge stops between pixel i and neighbour q at `reach` pixel steps: false where q is no
    // neighbour (another object, background, no value); else the depth stop as the exponent of
    // its weight (`logW`, to add the luminance stop's to before one exp) and the normal stop.
    // The depth stop's scale for an offset (ox, oy) pixels: the change the gradient predicts
    // there times sigma_depth, plus 0.1 % of the depth (curvature, and a ray's distance is not
    // linear across a plane).
    auto phiZ = [&](size_t i, float ox, float oy) {
        return sigmaZ * std::fabs(gx_[i] * ox + gy_[i] * oy) + 1e-3f * depth[i];
    };
    auto stops = [&](size_t i, size_t q, float invPhiZ, const float* ni, float& logW, float& wn) {
        if (id[q] != id[i] || !isSurface(depth[q]) || !valid_[q]) return false;
        logW = std::fabs(depth[q] - depth[i]) * invPhiZ;
        const float* nq = &normalPrev_[3 * q];  // this frame's unit normals (written after phase 1)
        wn = normalPower(std::max(0.0f, ni[0] * nq[0] + ni[1] * nq[1] + ni[2] * nq[2]));
        return wn > 0.0f;
    };
    auto geometryWeight = [&](size_t i, size_t q, float ox, float oy, const float* ni) {
        float logW, wn;
        return stops(i, q, 1.0f / phiZ(i, ox, oy), ni, logW, wn) ? wn * expNegative(-logW) : 0.0f;
    };

    // Phase 2: each pixel's noise: the variance of its mean's luminance.
    auto variance = [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = size_t(y) * size_t(w) + size_t(x);
                variance_[i] = 0.0f;
                if (!isSurface(depth[i]) || !valid_[i]) continue;
                const float len = std::max(1.0f, length_[i]);
                float m1 = moments_[2 * i], m2 = moments_[2 * i + 1];
                if (len < float(kShortHistory)) {  // too few frames: the neighbours' spread
                    const float* ni = &normalPrev_[3 * i];
                    float sumW = 0.0f, s1 = 0.0f, s2 = 0.0f;
                    for (int dy = -3; dy <= 3; ++dy)
                        for (int dx = -3; dx <= 3; ++dx) {
                            const int qx = x + dx, qy = y + dy;
                            if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
                            const size_t q = size_t(qy) * size_t(w) + size_t(qx);
                            const float wt = q == i ? 1.0f : geometryWeight(i, q, float(dx), float(dy), ni);
                            sumW += wt;
                            s1 += wt * moments_[2 * q];
                            s2 += wt * moments_[2 * q + 1];
                        }
                    m1 = s1 / sumW, m2 = s2 / sumW;
                }
                variance_[i] = std::max(0.0f, m2 - m1 * m1) / len;
            }
    };

    // Phase 3: one a-trous level from (c, v) into (dc, dv), colour planar (all red, all green,
    // all blue). Row by row, tap by tap: for one tap every pixel of the row reads the neighbour
    // at the same offset, so the loop over the row has contiguous loads and no branches and the
    // compiler vectorises it. A neighbour that is no neighbour (another object, background, no
    // value, outside) weighs zero through its key; the weights are the scalar rule's exactly.
    auto atrous = [&](int y0, int y1, int step, const float* c, const float* v, float* dc, float* dv, float* scratch) {
        float* sumW = scratch;
        float* sr = scratch + w;
        float* sg = scratch + 2 * w;
        float* sb = scratch + 3 * w;
        float* sv = scratch + 4 * w;
        float* invL = scratch + 5 * w;
        float* gxs = scratch + 6 * w;
        float* gys = scratch + 7 * w;
        float* eps = scratch + 8 * w;
        const float *cr = c, *cg = c + n, *cb = c + 2 * n;
        const float *nx = unit_.data(), *ny = nx + n, *nz = nx + 2 * n;
        const uint32_t* key = key_.data();
        const uint32_t* centre = centre_.data();
        for (int y = y0; y < y1; ++y) {
            const size_t row = size_t(y) * size_t(w);
            // Per pixel: the luminance stop's scale (the noise's deviation: its variance blurred
            // 3x3 over the same object's pixels with a value) and the depth stop's at one and two
            // steps.
            for (int x = 0; x < w; ++x) {
                const size_t i = row + size_t(x);
                float gv = 0.0f, gw = 0.0f;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int qx = x + dx, qy = y + dy;
                        if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
                        const size_t q = size_t(qy) * size_t(w) + size_t(qx);
                        if (key[q] != centre[i]) continue;
                        const float k = (dx == 0 ? 0.5f : 0.25f) * (dy == 0 ? 0.5f : 0.25f);
                        gv += k * v[q];
                        gw += k;
                    }
                const float phiL = sigmaL * std::sqrt(gw > 0.0f ? gv / gw : 0.0f);
                // No value of its own: no luminance to compare with (0); no noise: only equal
                // luminance passes (a huge factor).
                invL[x] = !valid_[i] ? 0.0f : phiL > 0.0f ? 1.0f / phiL : 1e30f;
                gxs[x] = sigmaZ * gx_[i];
                gys[x] = sigmaZ * gy_[i];
                eps[x] = 1e-3f * zf_[i] + 1e-30f;  // never 0: a masked tap divides by it too
                const float self = key[i] == centre[i] ? kB3[2] * kB3[2] : 0.0f;  // the centre: a value of its own
                sumW[x] = self;
                sr[x] = self * cr[i];
                sg[x] = self * cg[i];
                sb[x] = self * cb[i];
                sv[x] = self * self * v[i];
            }
            for (int dy = -2; dy <= 2; ++dy) {
                const int qy = y + dy * step;
                if (qy < 0 || qy >= h) continue;
                const size_t qrow = size_t(qy) * size_t(w);
                for (int dx = -2; dx <= 2; ++dx) {
                    if (dx == 0 && dy == 0) continue;
                    const int off = dx * step;
                    const int xa = std::max(0, -off), xb = std::min(w, w - off);
                    const float b3 = kB3[dx + 2] * kB3[dy + 2];
                    const float* zc = zf_.data() + row;  // finite everywhere: a masked tap stays 0, never NaN
                    const float* zq = zf_.data() + qrow + off;
                    const float *nxc = nx + row, *nyc = ny + row, *nzc = nz + row;
                    const float *nxq = nx + qrow + off, *nyq = ny + qrow + off, *nzq = nz + qrow + off;
                    const float *rc = cr + row, *gc = cg + row, *bc = cb + row;
                    const float *rq = cr + qrow + off, *gq = cg + qrow + off, *bq = cb + qrow + off;
                    const float* vq = v + qrow + off;
                    const uint32_t* kq = key + qrow + off;
                    const uint32_t* kc = centre + row;
                    const TapRow t{rc,  gc,  bc,  rq,  gq,  bq, zc, zq, invL, nxc, nyc, nzc, nxq, nyq, nzq, vq, kc, kq,
                                   gxs, gys, eps, float(off), float(dy * step)};
                    // The normal stop inline for exponents 2^0 .. 2^10 (128, the default: seven
                    // squarings), so that the loop vectorises; any other exponent through pow.
                    auto squared = [&]<int S>(std::integral_constant<int, S>) {
                        accumulateTaps(isa, t, xa, xb, b3, [](float cn) {
                            for (int k = 0; k < S; ++k) cn *= cn;
                            return cn;
                        }, sumW, sr, sg, sb, sv);
                    };
                    if (!powerOfTwo) accumulateTaps(isa, t, xa, xb, b3, normalPower, sumW, sr, sg, sb, sv);
                    else switch (squarings) {
                        case 0: squared(std::integral_constant<int, 0>{}); break;
                        case 1: squared(std::integral_constant<int, 1>{}); break;
                        case 2: squared(std::integral_constant<int, 2>{}); break;
                        case 3: squared(std::integral_constant<int, 3>{}); break;
                        case 4: squared(std::integral_constant<int, 4>{}); break;
                        case 5: squared(std::integral_constant<int, 5>{}); break;
                        case 6: squared(std::integral_constant<int, 6>{}); break;
                        case 7: squared(std::integral_constant<int, 7>{}); break;
                        case 8: squared(std::integral_constant<int, 8>{}); break;
                        case 9: squared(std::integral_constant<int, 9>{}); break;
                        case 10: squared(std::integral_constant<int, 10>{}); break;
                        default: accumulateTaps(isa, t, xa, xb, b3, normalPower, sumW, sr, sg, sb, sv);
                    }
                }
            }
            for (int x = 0; x < w; ++x) {
                const size_t i = row + size_t(x);
                const bool give = centre[i] != kBackgroundKey && sumW[x] > 0.0f;
                const float r = give ? 1.0f / sumW[x] : 0.0f;
                dc[i] = give ? sr[x] * r : cr[i];
                dc[n + i] = give ? sg[x] * r : cg[i];
                dc[2 * n + i] = give ? sb[x] * r : cb[i];
                dv[i] = give ? sv[x] * r * r : v[i];
                if (give) known_[i] = 1;
            }
        }
    };

    // Phase 4: remodulate; keep this frame's features for the next.
    auto finish = [&](int y0, int y1, const float* c) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = size_t(y) * size_t(w) + size_t(x);
                float* o = &out_[3 * i];
                const bool surface = isSurface(depth[i]);
                // The mean colour; filtered, the mean illumination remodulated by the mean albedo
                // (this frame's alone would alias: one sample a pixel).
                if (!filter || !surface) {
                    for (int k = 0; k < 3; ++k) o[k] = colour_[3 * i + k];
                } else {
                    for (int k = 0; k < 3; ++k)
                        o[k] = known_[i] ? c[size_t(k) * n + i] * demodulator(albedo_[3 * i + k]) : 0.0f;
                }
                depthPrev_[i] = surface ? depth[i] : NAN;
                idPrev_[i] = id[i];
            }
    };

    // Where the time goes (DenoiseStats::seconds): the first part's clock after each barrier,
    // when every part has finished the phase.
    using Clock = std::chrono::steady_clock;
    std::array<double, 5> phaseSeconds{};
    Clock::time_point phaseStart = Clock::now();
    auto lap = [&](int part, size_t phase) {
        if (part != 0) return;
        const Clock::time_point now = Clock::now();
        phaseSeconds[phase] += std::chrono::duration<double>(now - phaseStart).count();
        phaseStart = now;
    };
    auto work = [&](int part) {
        auto [y0, y1] = rowsOf(h, threads, part);
        temporal(y0, y1, partStats_[size_t(part)], part);
        sync.arrive_and_wait();
        lap(part, 0);
        // The previous frame's normals were read by phase 1 only: now they become this frame's
        // (unit length, made by phase 1 in unit_'s planes), and the filter's input is the
        // averaged colour over the averaged albedo.
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = size_t(y) * size_t(w) + size_t(x);
                for (int k = 0; k < 3; ++k) normalPrev_[3 * i + k] = unit_[size_t(k) * n + i];
                known_[i] = valid_[i];
                if (!filter) continue;
                const bool surface = isSurface(depth[i]);
                centre_[i] = surface ? id[i] : kBackgroundKey;
                zf_[i] = surface ? depth[i] : 0.0f;
                key_[i] = surface && valid_[i] ? id[i] : kNoKey;
                for (int k = 0; k < 3; ++k) filtered_[size_t(k) * n + i] = colour_[3 * i + k] / demodulator(albedo_[3 * i + k]);
            }
        sync.arrive_and_wait();
        lap(part, 1);
        const float* c = filtered_.data();
        if (filter) {
            variance(y0, y1);
            sync.arrive_and_wait();
            lap(part, 2);
            const float* v = variance_.data();
            for (int level = 0; level < levels; ++level) {
                // filtered_ -> filteredB_ -> filtered_ ...; variance_ -> varianceB_ -> variance_ ...
                float* dc = (level & 1) ? filtered_.data() : filteredB_.data();
                float* dv = (level & 1) ? variance_.data() : varianceB_.data();
                atrous(y0, y1, 1 << level, c, v, dc, dv, &rowScratch_[size_t(part) * 9 * size_t(w)]);
                // The history stays the plain (re-projected) mean, moving or still: SVGF feeds the
                // first level's result back as the next frame's history, but over a history of up
                // to 32 frames that blur compounds frame after frame (on the demo with GI it cost
                // 1.8 dB against no feedback, 37.3 against 39.1; on the office 0.2 dB).
                sync.arrive_and_wait();
                lap(part, 3);
                c = dc;
                v = dv;
            }
        }
        finish(y0, y1, c);
    };
    pool_.workers->run([](void* job, int part) { (*static_cast<decltype(work)*>(job))(part); }, &work);
    lap(0, 4);

    stats_ = DenoiseStats{};
    stats_.still = still;
    stats_.restarted = restart;
    stats_.isa = isa;
    stats_.seconds = {phaseSeconds[0], phaseSeconds[1], phaseSeconds[2], phaseSeconds[3], phaseSeconds[4]};
    for (const DenoiseStats& s : partStats_) {
        stats_.reused += s.reused;
        stats_.rejected += s.rejected;
        stats_.invalid += s.invalid;
        stats_.clamped += s.clamped;
        stats_.maxHistory = std::max(stats_.maxHistory, s.maxHistory);
    }
    std::swap(colour_, colourPrev_);
    std::swap(albedo_, albedoPrev_);
    std::swap(moments_, momentsPrev_);
    std::swap(length_, lengthPrev_);
    previousCamera_ = in.camera;
    previousState_ = in.stateSeq;
    hasPrevious_ = true;
    return out_;
}

}  // namespace rtwall
