// Denoising on the wall (issue 28): a scene whose [denoise] asks for svgf (or --denoise) makes the
// session ask its clients for features and show denoised frames, the same bytes on 1, 2 and 3
// clients, and a compositor's own denoising of the frames (what one machine does); off shows the
// frames as ever; a [denoise] edit that needs more features than the clients send says so; an
// operating point of a front switches the filter.
#include "display_test_util.h"
#include "image_compare.h"
#include "scratch.h"
#include "test_util.h"

#include <rtwall/cluster.h>
#include <rtwall/denoise.h>
#include <rtwall/frame.h>
#include <rtwall/wall.h>

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

namespace rtwall {
namespace {

// A small path-traced room (tests/data/scenes/gi_room.toml) with `denoise` as its [denoise].
std::filesystem::path roomWith(const std::filesystem::path& dir, const std::string& denoise) {
    std::string text = test::sceneText("gi_room");
    if (!denoise.empty()) text += "\n[denoise]\n" + denoise + "\n";
    return test::writeFile(dir / "room.toml", text);
}

RunConfig config(const std::filesystem::path& dir, const std::filesystem::path& scene, int clients,
                 std::shared_ptr<std::vector<std::string>> lines = nullptr) {
    RunConfig c = steppedRunConfig(dir, clients);
    c.scene = scene.string();
    c.cluster.async = false;
    if (lines) c.log = [lines](const std::string& l) { lines->push_back(l); };
    return c;
}

// Frames 1..3 of a still camera, then three of a moving one: the wall's frames are one machine's
// compositor's on the same frames (quantised as a cluster sends them), on any number of clients.
TEST(DenoiseSession, TheWallShowsOneMachinesDenoisedFramesOnAnyNumberOfClients) {
    const auto dir = test::scratchDir();
    const auto scene = roomWith(dir, "mode = \"svgf\"\nlevels = 3");
    const SceneDesc desc = loadSceneFile(scene);
    const Scene engine(desc);
    // One machine: the frames through the compositor, as `rtwall render` makes them.
    std::vector<Image> want;
    std::vector<CameraDesc> cameras;
    {
        Compositor comp;
        for (int k = 0; k < 6; ++k) {
            CameraDesc cam = desc.cameras.front();
            if (k >= 3) cam.position.x += 0.05f * float(k - 2);
            cameras.push_back(cam);
            FeatureFrame f = renderFrameFeatures(engine, Camera(cam, desc.settings.width, desc.settings.height), desc.settings,
                                                 uint32_t(k + 1));
            quantiseAsSent(f, kFeatureAll);
            std::vector<std::vector<float>> linear{f.linear}, depth{f.depth};
            std::vector<FeatureImages> features{{f.albedo, f.normal, f.id}};
            ComposeFrame cf;
            cf.stochastic = cf.linear = true;
            cf.denoise = desc.denoise;
            cf.depth = depth;
            cf.features = features;
            cf.camera = cam;
            cf.keepForWarp = false;
            std::vector<Image> img(1);
            img[0].width = desc.settings.width;
            img[0].height = desc.settings.height;
            img[0].rgb.resize(size_t(img[0].width) * size_t(img[0].height) * 3);
            want.push_back(comp.compose(cf, std::move(img), linear).left);
        }
        ASSERT_EQ(comp.denoisedFrames(), 6);
    }
    for (int clients : {1, 2, 3}) {
        auto lines = std::make_shared<std::vector<std::string>>();
        WallSession s(config(dir, scene, clients, lines));
        EXPECT_TRUE(test::logged(*lines, "denoise: svgf (3 levels, history 32)")) << clients << " clients";
        for (int k = 0; k < 6; ++k) {
            if (k >= 3) s.setCamera(cameras[size_t(k)]);
            ASSERT_TRUE(s.step());
            EXPECT_EQ(s.lastReport().features, kFeatureAll);
            EXPECT_EQ(test::differingBytes(s.lastFrame().left, want[size_t(k)]), 0u) << clients << " clients, frame " << k;
        }
    }
}

// Off (the default): no features are asked for, and the frames are accumulated as before.
TEST(DenoiseSession, OffAsksForNothingAndAccumulatesAsBefore) {
    const auto dir = test::scratchDir();
    WallSession plain(config(dir, roomWith(dir, ""), 2));
    auto lines = std::make_shared<std::vector<std::string>>();
    RunConfig c = config(dir, roomWith(dir, "mode = \"svgf\""), 2, lines);
    c.denoise = DenoiseSettings::Mode::Off;  // --denoise off over the scene's svgf
    WallSession off(c);
    EXPECT_FALSE(test::logged(*lines, "denoise:"));
    for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(plain.step());
        ASSERT_TRUE(off.step());
        EXPECT_EQ(off.lastReport().features, 0);
        EXPECT_FALSE(off.lastReport().depth);
        EXPECT_EQ(test::differingBytes(off.lastFrame().left, plain.lastFrame().left), 0u) << "frame " << k;
    }
}

// A [denoise] edit: svgf -> temporal needs no more features (applied at once); temporal -> svgf
// needs the albedo the clients do not send (one line: restart).
TEST(DenoiseSession, AnEditNeedingMoreFeaturesSaysRestart) {
    const auto dir = test::scratchDir();
    auto lines = std::make_shared<std::vector<std::string>>();
    const auto scene = roomWith(dir, "mode = \"temporal\"");
    WallSession s(config(dir, scene, 1, lines));
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.lastReport().features, featureBitsFor(DenoiseSettings::Mode::Temporal));
    SceneDesc edited = s.scene();
    edited.denoise.mode = DenoiseSettings::Mode::Svgf;
    const SceneEdit e = s.applyEdit(edited);
    EXPECT_TRUE(e.denoise);
    EXPECT_TRUE(test::logged(*lines, "room.toml: [denoise] mode svgf needs a restart (the clients send the features of temporal)"));
    edited.denoise.mode = DenoiseSettings::Mode::Off;
    s.applyEdit(edited);
    EXPECT_TRUE(test::logged(*lines, "denoise: off"));
    ASSERT_TRUE(s.step());
}

// An operating point naming the denoise control (`rtwall run --target-fps --front`): the scene
// asks for none, the clients send svgf's features from the start, and the point's svgf shows the
// very frames the scene's own [denoise] svgf would.
TEST(DenoiseSession, AFrontsPointSwitchesTheFilter) {
    const auto dir = test::scratchDir();
    const auto front = test::writeFile(dir / "front.toml", R"([[point]]
name = "svgf"
frame_s = 0.001
error = 0.5
controls = { denoise = 2 }
)");
    auto lines = std::make_shared<std::vector<std::string>>();
    RunConfig c = config(dir, roomWith(dir, ""), 2, lines);
    c.targetFps = 1;
    c.front = front;
    WallSession byPoint(c);
    EXPECT_TRUE(test::logged(*lines, "denoise: off now; the operating points may switch it up to svgf"));
    EXPECT_TRUE(test::logged(*lines, "denoise: svgf"));
    std::filesystem::create_directories(dir / "svgf");
    WallSession byScene(config(dir, roomWith(dir / "svgf", "mode = \"svgf\""), 2));
    for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(byPoint.step());
        ASSERT_TRUE(byScene.step());
        EXPECT_EQ(byPoint.lastReport().features, kFeatureAll);
        EXPECT_EQ(test::differingBytes(byPoint.lastFrame().left, byScene.lastFrame().left), 0u) << "frame " << k;
    }
    // Without linear tiles there is nothing to filter: said at the start, and the point's mode is
    // refused with the reason.
    lines->clear();
    c.cluster.wideAccumulation = false;
    WallSession narrow(c);
    EXPECT_TRUE(test::logged(*lines, "denoise: off: it needs linear tiles (the cluster's wide accumulation; the front asks for svgf)"));
    EXPECT_TRUE(test::logged(*lines, "operating point: denoise mode svgf: not applied: it needs linear tiles"));
    ASSERT_TRUE(narrow.step());
    EXPECT_EQ(narrow.lastReport().features, 0);
}

}  // namespace
}  // namespace rtwall
