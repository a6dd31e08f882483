// The building blocks of `rtwall bench reproject` (tools/bench/reproject_quality.h): the render
// clock shows frames one to two periods old; an image scored against itself is perfect; the
// centre of a guard-banded render is the screen's render; a frame warped to its own pose scores
// perfect; and on the demo scene a moving head is shown better warped than stale.
#include <reproject_quality.h>

#include <rtwall/tune.h>

#include <gtest/gtest.h>

#include <cmath>

namespace rtwall::bench::reproject {
namespace {

constexpr int kW = 80, kH = 60;

BenchScene demo() {
    BenchScene s = benchScene("demo", RTWALL_SOURCE_DIR "/configs/demo.toml", "", 0);
    s.desc.settings.width = kW;
    s.desc.settings.height = kH;
    s.desc.settings.threads = 2;
    return s;
}

TEST(ReprojectBench, TheNewestCompleteFrameIsOneToTwoPeriodsOld) {
    const RenderClock clock{1.0 / 14, 0.03};
    for (int i = 0; i < 600; ++i) {
        const double t = i / 60.0;
        const int64_t k = clock.newestAt(t);
        const double age = t - clock.start(k);
        EXPECT_GE(age, clock.period - 1e-12) << t;
        EXPECT_LT(age, 2 * clock.period + 1e-12) << t;
        EXPECT_GT(clock.start(k + 1) + clock.period, t) << "frame k + 1 must not be complete at " << t;
    }
}

TEST(ReprojectBench, AnImageScoredAgainstItselfIsPerfectAndAChangedOneIsNot) {
    const BenchScene s = demo();
    const Scene scene(s.desc);
    const Image a = renderFrame(scene, Camera(s.rig.camera(s.rig.viewer, kW, kH), kW, kH), s.desc.settings);
    const std::vector<uint8_t> all(size_t(kW) * kH, 1);
    const Score same = scoreImage(a, a, 0.05, &all);
    EXPECT_EQ(same.psnrDb, kIdenticalPsnr);
    EXPECT_EQ(same.flip, 0.0);
    EXPECT_EQ(same.edgePsnrDb, kIdenticalPsnr);
    EXPECT_EQ(same.maskedFlip, 0.0);
    // One pixel at the left edge changed: the edges score worse than the whole, the centre not at all.
    Image b = a;
    b.pixel(0, kH / 2)[0] ^= 0x80;
    const Score one = scoreImage(b, a, 0.05);
    EXPECT_LT(one.psnrDb, kIdenticalPsnr);
    EXPECT_LT(one.edgePsnrDb, one.psnrDb);
    EXPECT_GT(one.edgeFlip, one.flip);
    EXPECT_TRUE(std::isnan(one.maskedPsnrDb)) << "no mask given: no masked pixels";
}

// The guard band's camera keeps the screen's pixel pitch and centres: the centre of a render
// 10 % wider and higher is the screen's render (to float rounding of the ray directions).
TEST(ReprojectBench, TheCentreOfAGuardBandedRenderIsTheScreensRender) {
    BenchScene s = demo();
    const Scene scene(s.desc);
    const Float3 eye = s.rig.viewer + Float3{0.2f, 0.0f, -0.1f};
    const Image screen = renderFrame(scene, Camera(s.rig.camera(eye, kW, kH), kW, kH), s.desc.settings);
    RenderSettings wide = s.desc.settings;
    wide.width = kW + 8;
    wide.height = kH + 6;
    const Image guarded = renderFrame(scene, Camera(s.rig.camera(eye, kW, kH, 4, 3), wide.width, wide.height), wide);
    const ImageError e = compareImages(cropCentre(guarded, kW, kH), screen);
    EXPECT_GT(e.psnrDb, 45.0);
    EXPECT_LT(e.flip, 0.005);
}

TEST(ReprojectBench, AFrameWarpedToItsOwnPoseScoresPerfect) {
    const BenchScene s = demo();
    const Scene scene(s.desc);
    const CameraDesc camera = s.rig.camera(s.rig.viewer + Float3{-0.3f, 0.1f, 0.0f}, kW, kH);
    const RenderedFrame f = renderFrameWithDepth(scene, Camera(camera, kW, kH), s.desc.settings);
    Reprojector warper;
    WarpOptions warpAnyway;
    warpAnyway.copySamePose = false;
    const WarpedView& view = warper.warp({f.image, f.depth, camera}, camera, nullptr, warpAnyway);
    EXPECT_EQ(holeFraction(view, kW, kH), 0.0);
    const Score score = scoreImage(view.image, f.image, 0.05);
    EXPECT_EQ(score.psnrDb, kIdenticalPsnr);
    EXPECT_EQ(score.flip, 0.0);
}

// A head stepping at 1 m/s before a wall rendered at 5 fps: every shown frame is 0.2-0.4 s old,
// 0.2-0.4 m behind the head. Warped, the demo scene is shown closer to the truth than stale: a
// higher median PSNR, a lower median FLIP, and some holes filled (the newest frame never saw
// everything the moved eye sees). At a fixed seed: the same frames every run.
TEST(ReprojectBench, AMovingHeadIsShownBetterWarpedThanStale) {
    const BenchScene s = demo();
    const Scene scene(s.desc);
    MeasureOptions o;
    o.width = kW;
    o.height = kH;
    o.seconds = 0.25;
    o.seed = 7;
    const std::vector<Series> series = measure(scene, s.desc.settings, s.rig, 1.0, {{5.0, 0.0}}, o);
    ASSERT_EQ(series.size(), 1u);
    const Series& m = series.front();
    ASSERT_EQ(m.warped.size(), 15u);
    ASSERT_EQ(m.stale.size(), 15u);
    std::vector<double> warpedPsnr, stalePsnr, warpedFlip, staleFlip;
    for (size_t i = 0; i < m.warped.size(); ++i) {
        warpedPsnr.push_back(m.warped[i].psnrDb);
        stalePsnr.push_back(m.stale[i].psnrDb);
        warpedFlip.push_back(m.warped[i].flip);
        staleFlip.push_back(m.stale[i].flip);
        EXPECT_GE(m.ageSeconds[i], 0.2 - 1e-9);
        EXPECT_LT(m.ageSeconds[i], 0.4);
    }
    EXPECT_GT(median(warpedPsnr), median(stalePsnr) + 3.0);
    EXPECT_LT(median(warpedFlip), 0.7 * median(staleFlip));
    EXPECT_GT(median(m.holes), 0.0);
    EXPECT_LT(median(m.holes), 0.2);
}

}  // namespace
}  // namespace rtwall::bench::reproject
