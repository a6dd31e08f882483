// The denoiser on frames the engine renders (issue 28): a still view of a path-traced room
// converges to the plain accumulated mean (the filter fades as the mean's noise falls), and a
// hard shadow's edge stays where a converged render has it, within a pixel, from the first frame.
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/denoise.h>
#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace rtwall {
namespace {

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

}  // namespace
}  // namespace rtwall
