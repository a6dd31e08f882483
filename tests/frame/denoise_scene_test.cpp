// The denoiser on frames the engine renders (issue 28): a still view of a path-traced room
// converges to the plain accumulated mean (the filter fades as the mean's noise falls), and a
// hard shadow's edge stays where a converged render has it, within a pixel, from the first frame.
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/denoise.h>
#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace rtwall {
namespace {

// Pixels [x0, x0 + ww) x [y0, y0 + wh) of a frame's features (a display node's screen), kept for
// the DenoiseInput of that window.
struct FeatureWindow {
    std::vector<float> linear, depth, albedo, normal;
    std::vector<uint32_t> id;
    int ww, wh;

    FeatureWindow(const FeatureFrame& f, int w, int x0, int y0, int ww_, int wh_) : ww(ww_), wh(wh_) {
        auto cut = [&](const auto& v, size_t c, auto& out) {
            for (int y = y0; y < y0 + wh; ++y)
                out.insert(out.end(), v.begin() + long((size_t(y) * size_t(w) + size_t(x0)) * c),
                           v.begin() + long((size_t(y) * size_t(w) + size_t(x0 + ww)) * c));
        };
        cut(f.linear, 3, linear), cut(f.depth, 1, depth), cut(f.albedo, 3, albedo), cut(f.normal, 3, normal);
        cut(f.id, 1, id);
    }
    // Without a place (frameWidth 0), the window is taken for a whole frame.
    DenoiseInput input(const CameraDesc& cam) const { return {ww, wh, linear, depth, albedo, normal, id, cam, 0}; }
};

double rms(const std::vector<double>& a, std::span<const float> b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += (a[i] - double(b[i])) * (a[i] - double(b[i]));
    return std::sqrt(s / double(a.size()));
}

// A white room lit through GI, seen still: the denoised image converges to the frames' plain
// mean. The filter removes noise, so it differs from the mean by about the mean's own noise (its
// standard error, measured against a second, independent mean), no more; that difference falls
// as the mean converges; and the denoised image is nearer the independent mean than the plain
// mean is (it removed noise and added no bias that outweighs it).
TEST(DenoiserOnRenders, AStillViewConvergesToTheAccumulatedMean) {
    SceneDesc d = loadSceneFile(test::sourceDir() / "tests/data/scenes/gi_room.toml");
    d.settings.threads = 2;
    const Scene scene(d);
    const CameraDesc cam = d.cameras.front();
    const Camera camera(cam, d.settings.width, d.settings.height);
    DenoiseSettings s;
    s.mode = DenoiseSettings::Mode::Svgf;
    Denoiser dn;
    const size_t values = size_t(d.settings.width) * size_t(d.settings.height) * 3;
    std::vector<double> sum(values, 0.0), other(values, 0.0);
    double early = 0, late = 0, noise = 0, filteredToOther = 0, meanToOther = 0;
    const int frames = 256;
    for (int k = 1; k <= frames; ++k) {
        FeatureFrame f = renderFrameFeatures(scene, camera, d.settings, uint32_t(k));
        quantiseAsSent(f, kFeatureAll);
        for (size_t i = 0; i < values; ++i) sum[i] += f.linear[i];
        const std::vector<float> independent = renderFrameLinear(scene, camera, d.settings, uint32_t(100000 + k));
        for (size_t i = 0; i < values; ++i) other[i] += independent[i];
        const std::span<const float> out =
            dn.denoise({d.settings.width, d.settings.height, f.linear, f.depth, f.albedo, f.normal, f.id, cam, 0}, s, 2);
        if (k != 16 && k != frames) continue;
        std::vector<double> mean(values);
        std::vector<float> mean2(values);
        for (size_t i = 0; i < values; ++i) mean[i] = sum[i] / k, mean2[i] = float(other[i] / k);
        (k == 16 ? early : late) = rms(mean, out);
        if (k == frames) {
            meanToOther = rms(mean, mean2);
            noise = meanToOther / std::sqrt(2.0);  // one mean's standard error
            std::vector<double> o(out.begin(), out.end());
            filteredToOther = rms(o, mean2);
        }
    }
    EXPECT_TRUE(dn.stats().still);
    EXPECT_EQ(dn.stats().maxHistory, frames);
    EXPECT_GT(noise, 0.0);
    EXPECT_LT(late, 1.5 * noise) << "after " << frames << " frames the filter moves the mean by " << late
                                 << ", more than its noise, " << noise;
    EXPECT_LT(late, 0.5 * early) << "the filter's change should fall as the mean converges";
    EXPECT_LT(filteredToOther, meanToOther) << "the denoised image should be nearer an independent mean than the plain mean";
}

// A floor under a box lit by a low sun: the shadow's side edge runs along the image's rows (the
// camera looks straight down). In each column of the shadow, the row where the luminance crosses
// halfway between lit and shadowed is found in a converged render and in the first denoised frame
// (one GI sample a pixel): they agree within one pixel.
TEST(DenoiserOnRenders, AHardShadowKeepsItsEdgeWithinAPixel) {
    SceneDesc d;
    test::addQuadAndBox(d);
    d.materials.push_back(test::material("floor", MaterialType::Lambert, {0.8f, 0.8f, 0.8f}));
    Transform floor;
    floor.m = {4, 0, 0, 0, 0, 1, 0, 0, 0, 0, 4, 0};
    d.instances.push_back({0, 0, floor});
    Transform box;
    box.m = {0.3, 0, 0, -1.2, 0, 0.6, 0, 0.6, 0, 0, 0.52, 0};
    d.instances.push_back({1, 0, box});
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {1.0f, -0.6f, 0.0f};  // the shadow falls along +x, its edges at z = +-0.52
    d.lights.push_back(sun);
    d.cameras.push_back(test::cameraAt({0.6f, 6, 0.0f}, {0.6f, 0, 0.0f}, 30.0f, {0, 0, -1}));
    test::setImage(d.settings, 64, 48, 16);
    d.settings.gi = true;
    d.settings.threads = 2;
    d.settings.background = {0.3f, 0.3f, 0.35f};
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 64, 48);
    RenderSettings ref = d.settings;
    ref.samples = 1024;
    const std::vector<float> truth = renderFrameLinear(scene, camera, ref, 77);
    FeatureFrame f = renderFrameFeatures(scene, camera, d.settings, 1);
    quantiseAsSent(f, kFeatureAll);
    DenoiseSettings s;
    s.mode = DenoiseSettings::Mode::Svgf;
    Denoiser dn;
    const std::span<const float> out = dn.denoise({64, 48, f.linear, f.depth, f.albedo, f.normal, f.id, d.cameras.front(), 0}, s, 2);
    auto lum = [](std::span<const float> img, int x, int y) {
        const float* p = &img[(size_t(y) * 64 + size_t(x)) * 3];
        return 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
    };
    // The lower edge (z = +0.52, below the image's centre row): rows 24..47 of columns where the
    // shadow lies (x from -0.9 to 1.1 in the world: image columns 10 .. 39).
    auto crossing = [&](std::span<const float> img, int x, float half) {
        for (int y = 25; y < 47; ++y) {
            const float a = lum(img, x, y - 1), b = lum(img, x, y);
            if ((a - half) * (b - half) <= 0.0f && a != b) return float(y - 1) + (half - a) / (b - a);
        }
        return -100.0f;
    };
    int columns = 0;
    for (int x = 14; x < 36; ++x) {
        const float inside = lum(truth, x, 26), outside = lum(truth, x, 46);
        if (!(outside > 1.3f * inside)) continue;  // not a shadow column (in it: sky and bounced light)
        const float half = 0.5f * (inside + outside);
        const float want = crossing(truth, x, half), got = crossing(out, x, half);
        ASSERT_GT(want, 0.0f) << "column " << x << ": no edge in the reference";
        EXPECT_NEAR(got, want, 1.0f) << "column " << x;
        // Not blurred across: two rows to either side, the denoised image is as lit or as dark
        // as the reference, to a fifth of the step (a blur keeps the crossing, not these).
        const int edge = int(std::lround(want));
        for (int y : {edge - 2, edge + 3})
            EXPECT_NEAR(lum(out, x, y), lum(truth, x, y), 0.2f * (outside - inside)) << "column " << x << ", row " << y;
        ++columns;
    }
    EXPECT_GE(columns, 10) << "the shadow should cross most of these columns";
}

// A window of the frame (a display node's screen and its ring): for its pixels farther than the
// filter's reach (denoiseRing) from where it was cut out of the frame, the window's denoiser
// gives the whole frame's bytes: on the first frame and after the camera moved (the history
// re-projected through the whole frame's camera, the window's place subtracted). Placed wrongly
// (the window taken for the whole frame), the moved frame differs.
TEST(DenoiserOnRenders, AWindowFiltersItsInnerPixelsAsTheWholeFrame) {
    SceneDesc d = loadSceneFile(test::sourceDir() / "tests/data/scenes/gi_room.toml");
    d.settings.width = 160;
    d.settings.height = 120;
    d.settings.threads = 2;
    const Scene scene(d);
    DenoiseSettings s;
    s.mode = DenoiseSettings::Mode::Svgf;
    s.levels = 3;
    const int ring = denoiseRing(s);
    ASSERT_EQ(ring, 2 * 7 + 3 + 4 + 8);
    const int w = d.settings.width, h = d.settings.height;
    const int x0 = 30, y0 = 20, ww = 110, wh = 100;  // cut on the left, top and right; the bottom is the frame's
    ASSERT_EQ(y0 + wh, h);
    Denoiser whole, window, misplaced;
    size_t compared = 0;
    for (int k = 1; k <= 3; ++k) {
        CameraDesc cam = d.cameras.front();
        cam.position.x += 0.01f * float(k - 1);  // a move of a pixel or two a frame
        FeatureFrame f = renderFrameFeatures(scene, Camera(cam, w, h), d.settings, uint32_t(k));
        quantiseAsSent(f, kFeatureAll);
        const std::span<const float> a0 = whole.denoise({w, h, f.linear, f.depth, f.albedo, f.normal, f.id, cam, 0}, s, 2);
        const std::vector<float> all(a0.begin(), a0.end());
        // The window's pixels, cut out.
        const FeatureWindow cut(f, w, x0, y0, ww, wh);
        DenoiseInput in = cut.input(cam);
        const DenoiseInput unplaced = in;
        in.x0 = x0, in.y0 = y0, in.frameWidth = w, in.frameHeight = h;
        const std::span<const float> p0 = window.denoise(in, s, 2);
        const std::vector<float> part(p0.begin(), p0.end());
        const std::span<const float> q0 = misplaced.denoise(unplaced, s, 2);
        const std::vector<float> wrong(q0.begin(), q0.end());
        size_t differ = 0, wrongDiffer = 0;
        for (int y = y0 + ring; y < y0 + wh; ++y)
            for (int x = x0 + ring; x < x0 + ww - ring; ++x)
                for (int c = 0; c < 3; ++c) {
                    const float a = all[(size_t(y) * size_t(w) + size_t(x)) * 3 + size_t(c)];
                    const size_t j = (size_t(y - y0) * size_t(ww) + size_t(x - x0)) * 3 + size_t(c);
                    differ += std::memcmp(&a, &part[j], sizeof a) != 0;
                    wrongDiffer += std::memcmp(&a, &wrong[j], sizeof a) != 0;
                    ++compared;
                }
        EXPECT_EQ(differ, 0u) << "frame " << k;
        if (k == 1) EXPECT_EQ(wrongDiffer, 0u) << "frame 1 has no history: the place does not matter yet";
        else EXPECT_GT(wrongDiffer, 100u) << "frame " << k << ": history re-projected without the window's place";
    }
    EXPECT_GT(compared, size_t(3 * 3 * 40 * 60));
    // A window that does not lie inside its frame is refused.
    FeatureFrame f = renderFrameFeatures(scene, Camera(d.cameras.front(), w, h), d.settings, 1);
    DenoiseInput in{w, h, f.linear, f.depth, f.albedo, f.normal, f.id, d.cameras.front(), 0};
    in.x0 = 1, in.frameWidth = w, in.frameHeight = h;
    EXPECT_THROW(window.denoise(in, s, 1), std::invalid_argument);
}

// Every instruction set of the filter's vectorised loops this CPU has (SSE2 4 lanes, AVX2 8,
// AVX-512 16: the a-trous tap loop, temporal reuse's row pass and its luminances) gives the same
// bytes, frame after frame with a moving camera, for the normal stop's three code paths (a power
// of two: squarings; another whole exponent; any other: pow) and for a window of a larger frame
// (a display node's screen: the re-projection's place). An instruction set this CPU lacks is
// refused in one line.
TEST(DenoiserOnRenders, EveryInstructionSetGivesTheSameBytes) {
    SceneDesc d = loadSceneFile(test::sourceDir() / "tests/data/scenes/gi_room.toml");
    d.settings.width = 96;
    d.settings.height = 72;
    const Scene scene(d);
    const DenoiseIsa before = denoiseIsa();
    std::vector<std::string> ran;
    for (float sigmaNormal : {128.0f, 100.0f, 64.5f, 0.0f}) {
        const bool window = sigmaNormal == 0.0f;  // then the default stop, on a window
        DenoiseSettings s;
        s.mode = DenoiseSettings::Mode::Svgf;
        if (!window) s.sigmaNormal = sigmaNormal;
        std::vector<float> want;
        for (DenoiseIsa isa : {DenoiseIsa::Sse2, DenoiseIsa::Avx2, DenoiseIsa::Avx512}) {
            if (!denoiseIsaSupported(isa)) {
                EXPECT_THROW(setDenoiseIsa(isa), InputError);
                continue;
            }
            setDenoiseIsa(isa);
            if (sigmaNormal == 128.0f) ran.push_back(denoiseIsaName(isa));
            Denoiser dn;
            std::vector<float> got;
            for (int k = 1; k <= 3; ++k) {
                CameraDesc cam = d.cameras.front();
                cam.position.x += 0.02f * float(k);
                FeatureFrame f = renderFrameFeatures(scene, Camera(cam, d.settings.width, d.settings.height), d.settings, uint32_t(k));
                DenoiseInput in{d.settings.width, d.settings.height, f.linear, f.depth, f.albedo, f.normal, f.id, cam, 0};
                const FeatureWindow cut(f, d.settings.width, 10, 8, 60, 50);
                if (window) {
                    in = cut.input(cam);
                    in.x0 = 10, in.y0 = 8, in.frameWidth = d.settings.width, in.frameHeight = d.settings.height;
                }
                const std::span<const float> out = dn.denoise(in, s, 2);
                got.insert(got.end(), out.begin(), out.end());
            }
            EXPECT_EQ(dn.stats().isa, isa);
            if (want.empty()) want = got;
            else EXPECT_EQ(0, std::memcmp(want.data(), got.data(), got.size() * sizeof(float)))
                     << denoiseIsaName(isa) << ", sigma_normal " << sigmaNormal;
        }
    }
    setDenoiseIsa(before);
    std::string list;
    for (const std::string& r : ran) list += " " + r;
    std::printf("instruction sets compared on this CPU:%s\n", list.c_str());
    EXPECT_GE(ran.size(), 1u);
    EXPECT_EQ(denoiseIsaFromName("avx2"), DenoiseIsa::Avx2);
    EXPECT_THROW(denoiseIsaFromName("neon"), InputError);
}

}  // namespace
}  // namespace rtwall

