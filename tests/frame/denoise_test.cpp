// The denoiser (issue 28, rtwall/denoise.h) on frames made by hand, where the right answer is
// known: a constant passes unchanged, an edge in depth, normal or object is not blurred across,
// a poisoned sample never spreads, history goes on a new state or a cut, a still view's
// temporal mean is the plain mean, and any number of threads gives the same bytes.
#include <rtwall/denoise.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

namespace rtwall {
namespace {

// A frame of a plane facing the camera (depth 5, normal +z towards the camera, one object),
// colour and albedo as the test sets them.
struct Frame {
    int w, h;
    std::vector<float> rgb, depth, albedo, normal;
    std::vector<uint32_t> id;
    CameraDesc camera;
    uint32_t state = 0;

    Frame(int width, int height, float value = 0.5f) : w(width), h(height) {
        const size_t n = size_t(w) * size_t(h);
        rgb.assign(n * 3, value);
        depth.assign(n, 5.0f);
        albedo.assign(n * 3, 0.8f);
        normal.resize(n * 3);
        for (size_t i = 0; i < n; ++i) normal[3 * i] = 0, normal[3 * i + 1] = 0, normal[3 * i + 2] = 1;
        id.assign(n, 1u);
        camera.position = {0, 0, 5};
        camera.lookAt = {0, 0, 0};
    }
    size_t at(int x, int y) const { return size_t(y) * size_t(w) + size_t(x); }
    void set(int x, int y, float r, float g, float b) {
        float* p = &rgb[3 * at(x, y)];
        p[0] = r, p[1] = g, p[2] = b;
    }
    DenoiseInput input() const {
        DenoiseInput in;
        in.width = w, in.height = h;
        in.linear = rgb, in.depth = depth, in.albedo = albedo, in.normal = normal, in.id = id;
        in.camera = camera;
        in.stateSeq = state;
        return in;
    }
};

DenoiseSettings mode(DenoiseSettings::Mode m, int levels = 5) {
    DenoiseSettings s;
    s.mode = m;
    s.levels = levels;
    return s;
}

// Adds uniform noise of amplitude `a` around each value (seeded: the test is repeatable).
void addNoise(Frame& f, float a, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-a, a);
    for (float& v : f.rgb) v = std::max(0.0f, v + u(rng));
}

TEST(Denoiser, AConstantImagePassesEveryLevelUnchanged) {
    for (int levels : {1, 3, 5, 10})
        for (auto m : {DenoiseSettings::Mode::Temporal, DenoiseSettings::Mode::Svgf}) {
            Frame f(40, 30, 0.37f);
            Denoiser d;
            const std::span<const float> out = d.denoise(f.input(), mode(m, levels), 2);
            for (size_t i = 0; i < out.size(); ++i) ASSERT_NEAR(out[i], 0.37f, 1e-6f) << "levels " << levels << " value " << i;
        }
}

// Left half near, right half far (or turned away, or another object), each noisy around its own
// colour: the filter smooths each side and mixes nothing across the edge.
void expectEdgeKept(const char* what, void (*makeEdge)(Frame&, int x)) {
    Frame f(64, 48);
    for (int y = 0; y < f.h; ++y)
        for (int x = 0; x < f.w; ++x) {
            const float v = x < 32 ? 0.2f : 0.8f;
            f.set(x, y, v, v, v);
            if (x >= 32) makeEdge(f, x + y * f.w);
        }
    addNoise(f, 0.15f, 7);
    Denoiser d;
    const std::span<const float> out = d.denoise(f.input(), mode(DenoiseSettings::Mode::Svgf), 2);
    double noisyError = 0, filteredError = 0;
    for (int y = 4; y < f.h - 4; ++y)
        for (int x : {30, 31, 32, 33}) {
            const float want = x < 32 ? 0.2f : 0.8f;
            const float got = out[3 * f.at(x, y)];
            EXPECT_NEAR(got, want, 0.06f) << what << ": pixel " << x << "," << y << " mixed across the edge";
            filteredError += std::fabs(got - want);
            noisyError += std::fabs(f.rgb[3 * f.at(x, y)] - want);
        }
    EXPECT_LT(filteredError, 0.4 * noisyError) << what << ": the filter should still smooth each side";
}

TEST(Denoiser, AStepInDepthIsNotBlurredAcross) {
    expectEdgeKept("depth", [](Frame& f, int i) { f.depth[size_t(i)] = 9.0f; });
}

TEST(Denoiser, AStepInNormalIsNotBlurredAcross) {
    expectEdgeKept("normal", [](Frame& f, int i) {
        f.normal[3 * size_t(i)] = 1.0f;  // turned 90 degrees
        f.normal[3 * size_t(i) + 2] = 0.0f;
    });
}

TEST(Denoiser, AnotherObjectIsNotBlurredInto) {
    expectEdgeKept("id", [](Frame& f, int i) { f.id[size_t(i)] = 2; });
}

TEST(Denoiser, APoisonedSampleNeverSpreads) {
    for (float poison : {NAN, INFINITY, -INFINITY})
        for (auto m : {DenoiseSettings::Mode::Temporal, DenoiseSettings::Mode::Svgf}) {
            Frame f(32, 24, 0.4f);
            addNoise(f, 0.1f, 3);
            Frame clean = f;
            f.set(10, 10, poison, 0.4f, 0.4f);
            Denoiser d;
            const std::span<const float> o = d.denoise(f.input(), mode(m), 2);
            const std::vector<float> out(o.begin(), o.end());
            EXPECT_EQ(d.stats().invalid, 1u);
            for (float v : out) ASSERT_TRUE(std::isfinite(v)) << "poison " << poison;
            // The poisoned pixel has no history either: the filter gives it its neighbours' value.
            const float* p = &out[3 * f.at(10, 10)];
            if (m == DenoiseSettings::Mode::Svgf) {
                EXPECT_NEAR(p[0], 0.4f, 0.1f);
            }
            // A pixel two away shows what it shows without the poison, to the filter's rounding.
            Denoiser c;
            const std::span<const float> ref = c.denoise(clean.input(), mode(m), 2);
            EXPECT_NEAR(out[3 * f.at(12, 10)], ref[3 * f.at(12, 10)], 0.02f);
        }
}

TEST(Denoiser, APoisonedSampleKeepsItsHistory) {
    Frame f(16, 16, 0.25f);
    Denoiser d;
    d.denoise(f.input(), mode(DenoiseSettings::Mode::Temporal), 1);
    f.set(3, 3, NAN, NAN, NAN);
    const std::span<const float> out = d.denoise(f.input(), mode(DenoiseSettings::Mode::Temporal), 1);
    EXPECT_FLOAT_EQ(out[3 * f.at(3, 3)], 0.25f);
}

TEST(Denoiser, AStillViewAveragesEveryFrameAsTheAccumulatorDoes) {
    Frame f(24, 16);
    Denoiser d;
    std::vector<double> sum(f.rgb.size(), 0.0);
    std::span<const float> out;
    const int frames = 300;  // beyond `history`: a still view's average has no cap
    for (int k = 0; k < frames; ++k) {
        Frame g = f;
        for (size_t i = 0; i < g.rgb.size(); ++i) g.rgb[i] = float((i * 37 + size_t(k) * 101) % 97) / 97.0f;
        for (size_t i = 0; i < g.rgb.size(); ++i) sum[i] += g.rgb[i];
        out = d.denoise(g.input(), mode(DenoiseSettings::Mode::Temporal), 2);
        EXPECT_EQ(d.stats().still, k > 0);
    }
    EXPECT_EQ(d.stats().maxHistory, frames);
    for (size_t i = 0; i < sum.size(); ++i) ASSERT_NEAR(out[i], sum[i] / frames, 2e-5) << i;
}

// A silhouette (a leaf's edge, alpha-masked foliage): a pixel whose sample falls on the surface in
// some frames and on the background in others. A still view averages all of its samples, hits
// and misses alike, as the Accumulator does; before, a miss restarted its history, and a still
// view of foliage stayed at 37 dB (speed-accuracy.md, "Denoising on the GI scenes").
TEST(Denoiser, AStillSilhouetteAveragesItsHitsAndMisses) {
    for (auto m : {DenoiseSettings::Mode::Temporal, DenoiseSettings::Mode::Svgf}) {
        Frame f(24, 16);
        Denoiser d;
        std::vector<double> sum(f.rgb.size(), 0.0);
        std::span<const float> out;
        const int frames = 200;
        for (int k = 0; k < frames; ++k) {
            Frame g = f;
            for (int y = 0; y < g.h; ++y)
                for (int x = 8; x < 16; ++x)
                    if ((x + y + k) % 3 == 0) g.depth[g.at(x, y)] = kBackgroundDepth;  // a miss: the sky
            for (size_t i = 0; i < g.rgb.size(); ++i) g.rgb[i] = g.depth[i / 3] == kBackgroundDepth ? 0.9f : 0.2f;
            for (size_t i = 0; i < g.rgb.size(); ++i) sum[i] += g.rgb[i];
            out = d.denoise(g.input(), mode(m), 2);
        }
        EXPECT_EQ(d.stats().maxHistory, frames);
        for (int y = 0; y < f.h; ++y)
            for (int x = 0; x < f.w; ++x) {
                const size_t i = 3 * f.at(x, y);
                // Temporal: the plain mean. Svgf: the mean within its own noise (samples 0.2 and
                // 0.9: the mean's deviation after 200 frames is about 0.02), the filter having
                // faded; before, a silhouette pixel was off by 0.2 to 0.5.
                ASSERT_NEAR(out[i], sum[i] / frames, m == DenoiseSettings::Mode::Temporal ? 2e-5 : 1e-2)
                    << denoiseModeName(m) << " at " << x << "," << y;
            }
    }
}

TEST(Denoiser, AMovingViewAveragesAtMostItsHistory) {
    Frame f(24, 16, 0.5f);
    Denoiser d;
    DenoiseSettings s = mode(DenoiseSettings::Mode::Temporal);
    s.history = 8;
    for (int k = 0; k < 20; ++k) {
        f.camera.position.x = 1e-4f * float(k);  // a tiny move: every pixel keeps its history
        f.camera.lookAt.x = f.camera.position.x;
        d.denoise(f.input(), s, 1);
    }
    EXPECT_FALSE(d.stats().still);
    EXPECT_EQ(d.stats().maxHistory, 8);
    EXPECT_EQ(d.stats().reused, size_t(f.w) * size_t(f.h)) << "a move of a hundredth of a pixel keeps every history";
}

TEST(Denoiser, HistoryIsDiscardedOnAStateChangeAndACut) {
    for (int how : {0, 1}) {
        Frame f(16, 12, 0.2f);
        Denoiser d;
        for (int k = 0; k < 5; ++k) d.denoise(f.input(), mode(DenoiseSettings::Mode::Temporal), 1);
        std::fill(f.rgb.begin(), f.rgb.end(), 0.9f);
        if (how == 0) ++f.state;  // a part moved, a section plane, a material: the master's state
        else d.reset();           // a camera cut
        const std::span<const float> out = d.denoise(f.input(), mode(DenoiseSettings::Mode::Temporal), 1);
        EXPECT_TRUE(d.stats().restarted);
        for (float v : out) ASSERT_EQ(v, 0.9f) << (how == 0 ? "state change" : "cut");
    }
}

TEST(Denoiser, HistoryOfAnotherSurfaceIsRejected) {
    // Frame 1 sees a plane at depth 5; frame 2 (same camera, same state: history would be kept
    // by a still view) is moved a hair and now sees a nearer plane: the old depth disagrees.
    Frame f(16, 12, 0.2f);
    Denoiser d;
    d.denoise(f.input(), mode(DenoiseSettings::Mode::Temporal), 1);
    f.camera.position.y += 1e-4f;
    f.camera.lookAt.y += 1e-4f;
    std::fill(f.depth.begin(), f.depth.end(), 3.0f);
    std::fill(f.rgb.begin(), f.rgb.end(), 0.7f);
    const std::span<const float> out = d.denoise(f.input(), mode(DenoiseSettings::Mode::Temporal), 1);
    EXPECT_EQ(d.stats().reused, 0u);
    EXPECT_EQ(d.stats().rejected, size_t(f.w) * size_t(f.h));
    for (float v : out) ASSERT_EQ(v, 0.7f);
}

TEST(Denoiser, AnyNumberOfThreadsGivesTheSameBytes) {
    std::vector<float> first;
    for (int threads : {1, 2, 3, 7}) {
        Frame f(50, 37, 0.5f);
        Denoiser d;
        std::vector<float> out;
        for (int k = 0; k < 3; ++k) {
            addNoise(f, 0.3f, uint32_t(k + 1));
            for (int y = 0; y < f.h; ++y)
                for (int x = 20; x < f.w; ++x) f.depth[f.at(x, y)] = 5.0f + 0.1f * float(x - 20);
            f.camera.position.x += 0.01f;
            const std::span<const float> o = d.denoise(f.input(), mode(DenoiseSettings::Mode::Svgf), threads);
            out.assign(o.begin(), o.end());
        }
        if (first.empty()) first = out;
        else EXPECT_EQ(0, std::memcmp(first.data(), out.data(), out.size() * sizeof(float))) << threads << " threads";
    }
}

TEST(Denoiser, SaysWhichBufferIsTheWrongSize) {
    Frame f(8, 8);
    f.albedo.pop_back();
    Denoiser d;
    try {
        d.denoise(f.input(), mode(DenoiseSettings::Mode::Svgf));
        FAIL() << "no error";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "Denoiser: the albedo has 191 values, not 192");
    }
}

}  // namespace
}  // namespace rtwall
