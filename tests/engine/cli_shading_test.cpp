// The shading commands as a user meets them: `rtwall gen` writes demos that render (also
// through local client processes, to the same bytes), and bad shading arguments end with one line.
#include "test_util.h"
#include "cli_util.h"

#include <rtwall/engine.h>
#include <rtwall/image.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <sys/wait.h>

namespace rtwall {
namespace {

using Result = test::CliResult;

Result run(const std::string& args) { return test::runCli(RTWALL_EXE, args, 300); }

TEST(CliShading, GeneratedDemosRenderAndTheClusterGivesTheSameBytes) {
    const auto dir = test::scratchDir();
    ASSERT_EQ(run("gen office --out " + (dir / "office").string()).status, 0);
    ASSERT_EQ(run("gen headlight --out " + (dir / "headlight").string()).status, 0);
    const std::string office = (dir / "office/office.toml").string();
    Result r = run("render " + office + " --width 64 --height 48 --gi --frames 2 --out " + (dir / "a.png").string());
    ASSERT_EQ(r.status, 0) << r.output;
    r = run("render " + office + " --width 64 --height 48 --gi --frames 2 --clients 2 --out " + (dir / "b.png").string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(readPng(dir / "a.png").rgb, readPng(dir / "b.png").rgb);
    r = run("render " + (dir / "headlight/headlight.toml").string() +
            " --width 32 --height 24 --prune 0.05 --view depth --out " + (dir / "h.png").string());
    EXPECT_EQ(r.status, 0) << r.output;
}

// Stated error of ray-tree pruning at the default threshold on deep glass (issue 7: "at the
// default it stays within a stated error of the unpruned image"): the headlight demo, small,
// at the default 0.002 against threshold 1e-4 (unpruned, the headlight's ray tree grows as
// 2^depth and does not finish; 1e-4 traces about 4x the rays of the default and its own
// roulette noise is about a twentieth of the default's). Stated: PSNR >= 40 dB over the image
// (measured 41.1 dB at 96x72, 41.2 at 160x120), at under 40% of the reference's rays. No GI,
// so the roulette coins are fixed per pixel and the images deterministic.
TEST(CliShading, HeadlightAtTheDefaultThresholdWithin40DbOfUnpruned) {
    const auto dir = test::scratchDir();
    ASSERT_EQ(run("gen headlight --out " + (dir / "headlight").string()).status, 0);
    const std::string scene = (dir / "headlight/headlight.toml").string();
    auto rays = [](const std::string& output) {
        const size_t at = output.find(" rays + ");
        const size_t open = output.rfind('(', at);
        return at == std::string::npos || open == std::string::npos ? -1.0 : std::stod(output.substr(open + 1, at - open - 1));
    };
    Result r = run("render " + scene + " --width 96 --height 72 --out " + (dir / "default.png").string());
    ASSERT_EQ(r.status, 0) << r.output;
    const double defaultRays = rays(r.output);
    r = run("render " + scene + " --width 96 --height 72 --prune 0.0001 --out " + (dir / "reference.png").string());
    ASSERT_EQ(r.status, 0) << r.output;
    const double referenceRays = rays(r.output);
    const Image a = readPng(dir / "default.png"), b = readPng(dir / "reference.png");
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    double se = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) se += (double(a.rgb[i]) - b.rgb[i]) * (double(a.rgb[i]) - b.rgb[i]);
    const double db = se == 0 ? 999.0 : 10.0 * std::log10(255.0 * 255.0 / (se / double(a.rgb.size())));
    std::printf("headlight 96x72: default %.1f rays per pixel, 1e-4 %.1f; PSNR %.2f dB\n", defaultRays, referenceRays, db);
    EXPECT_GE(db, 40.0);
    ASSERT_GT(defaultRays, 0.0) << r.output;
    EXPECT_LT(defaultRays, 0.4 * referenceRays);
}

// `rtwall render --frames N` averages in linear light, on one machine and over the cluster
// (`--clients`), as `rtwall run` does. The scene: a closed room lit only by a small emissive panel
// under the ceiling, path traced: a bounce that finds the panel carries radiance far above 1, so
// each frame is noise with values above 1.0 that 8-bit frames clip (averaging them kept 17% of
// the light). Expected: the frames' linear mean, computed here from renderFrameLinear
// (independently of the command's accumulation), which the written PNG must equal to within its
// quantisation; and bit for bit Accumulator::addLinear's mean of those frames, on both paths.
TEST(CliShading, FramesAverageInLinearLightOnOneMachineAndTheCluster) {
    const auto dir = test::scratchDir();
    const auto file = test::writeFile(dir / "room.toml", test::sceneText("gi_room"));
    const int frames = 8;
    Result r = run("render " + file.string() + " --frames " + std::to_string(frames) + " --out " + (dir / "one.png").string());
    ASSERT_EQ(r.status, 0) << r.output;
    r = run("render " + file.string() + " --frames " + std::to_string(frames) + " --clients 2 --out " +
            (dir / "cluster.png").string());
    ASSERT_EQ(r.status, 0) << r.output;

    const SceneDesc desc = loadSceneFile(file);
    const Scene scene(desc);
    const RenderSettings& s = desc.settings;
    const Camera camera(desc.cameras.front(), s.width, s.height);
    const size_t n = size_t(s.width) * s.height * 3;
    std::vector<double> sum(n, 0.0);
    Accumulator linear, eightBit;
    size_t above = 0;
    for (int f = 1; f <= frames; ++f) {  // the command numbers its frames from 1
        const std::vector<float> img = renderFrameLinear(scene, camera, s, uint32_t(f));
        for (size_t i = 0; i < n; ++i) {
            sum[i] += img[i];
            above += img[i] > 1.0f;
        }
        linear.addLinear(img.data(), s.width, s.height);
        Image q;
        q.width = s.width;
        q.height = s.height;
        q.rgb.resize(n);
        linearToSrgb8(img.data(), n, q.rgb.data());
        eightBit.add(q);
    }
    // The test means something only where frames exceed 1.0.
    ASSERT_GT(above, n * frames / 100) << "too few frame values above 1.0";
    double expected = 0;  // what a display shows of the linear mean: each value up to 1.0
    for (double v : sum) expected += std::min(1.0, v / frames);
    expected /= double(n);
    auto meanOf = [](const Image& img) {
        double m = 0;
        for (uint8_t b : img.rgb) {
            const double c = b / 255.0;
            m += c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
        }
        return m / double(img.rgb.size());
    };
    const Image one = readPng(dir / "one.png"), cluster = readPng(dir / "cluster.png");
    std::printf("frame values above 1.0: %.1f%%; mean: linear %.5f, rtwall render %.5f, 8-bit frames averaged %.5f\n",
                100.0 * double(above) / double(n * frames), expected, meanOf(one), meanOf(eightBit.resolve()));
    EXPECT_NEAR(meanOf(one), expected, 0.005 * expected);
    EXPECT_EQ(one.rgb, linear.resolve().rgb);
    EXPECT_EQ(cluster.rgb, one.rgb);
}

TEST(CliShading, BadArgumentsEndWithOneLine) {
    for (const char* args : {"render x.toml --out y.png --view xray", "render x.toml --out y.png --prune 2",
                             "render x.toml --out y.png --samples 0", "gen garden --out /tmp/x", "gen office"}) {
        const Result r = run(args);
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
    }
}

}  // namespace
}  // namespace rtwall
