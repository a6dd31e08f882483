// A tile that fails (issue 17): the engine says which tile of which frame failed (TileError),
// and the command line replayCommand() builds renders exactly that tile again, through the
// rtwall executable, also for path-traced frames other than the first, cameras that are not in
// the scene file, scenes far from the origin and settings that differ from the scene file's.
#include "test_util.h"
#include "cli_util.h"

#include <rtwall/engine.h>
#include <rtwall/engine_testing.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

namespace rtwall {
namespace {

test::CliResult run(const std::string& args) { return test::runCli(RTWALL_EXE, args, 120); }

// The pixels of `rect` in `img`, row by row.
std::vector<uint8_t> pixelsOf(const Image& img, const TileRect& rect) {
    std::vector<uint8_t> px;
    for (int y = rect.y0; y < rect.y1; ++y)
        px.insert(px.end(), img.pixel(rect.x0, y), img.pixel(rect.x0, y) + 3 * rect.width());
    return px;
}

bool blackOutside(const Image& img, const TileRect& rect) {
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            if ((x < rect.x0 || x >= rect.x1 || y < rect.y0 || y >= rect.y1) &&
                (img.pixel(x, y)[0] | img.pixel(x, y)[1] | img.pixel(x, y)[2]))
                return false;
    return true;
}

// Runs a replay command (as printed: "rtwall render ... --out tile.png") with the executable,
// writing the tile to `out`; returns the image.
Image runReplay(std::string command, const std::filesystem::path& out) {
    EXPECT_TRUE(command.starts_with("rtwall render ")) << command;
    const std::string tail = " --out tile.png";
    EXPECT_TRUE(command.ends_with(tail)) << command;
    command = command.substr(7, command.size() - 7 - tail.size()) + " --out " + out.string();
    const test::CliResult r = run(command);
    EXPECT_EQ(r.status, 0) << command << "\n" << r.output;
    return readPng(out);
}

// A small stochastic scene far from the origin (rebased on load): an area light, rough metal and
// glass, path traced in the tests below.
std::filesystem::path writeFarScene(const std::filesystem::path& dir) {
    return test::writeFile(dir / "far.toml", test::sceneText("far_stochastic"));
}

TEST(TileError, ATileThatThrowsSaysItsFrameItsPixelsAndWhy) {
    SceneDesc d = builtinScene("knots", 5000);
    test::setImage(d.settings, 96, 64, 32);
    d.settings.threads = 2;
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 96, 64);
    TraceOptions trace;
    trace.fault = injectFault({7, 40, 20});
    auto expectFault = [&](const std::function<void()>& render, const char* what) {
        try {
            render();
            ADD_FAILURE() << what << ": no TileError";
        } catch (const TileError& e) {
            EXPECT_EQ(e.frame(), 7u) << what;
            EXPECT_EQ(e.rect().x0, 32) << what;
            EXPECT_EQ(e.rect().y0, 0) << what;
            EXPECT_EQ(e.rect().x1, 64) << what;
            EXPECT_EQ(e.rect().y1, 32) << what;
            EXPECT_EQ(e.reason(), "injected fault at pixel 40,20") << what;
            EXPECT_EQ(std::string(e.what()), "frame 7, tile 32,0,64,32: injected fault at pixel 40,20") << what;
        }
    };
    expectFault([&] { renderFrame(scene, camera, d.settings, 7, nullptr, trace); }, "renderFrame");
    expectFault([&] { renderFrameLinear(scene, camera, d.settings, 7, nullptr, trace); }, "renderFrameLinear");
    std::vector<uint8_t> px(32 * 32 * 3);
    std::vector<float> linear(32 * 32 * 3);
    expectFault([&] { renderTile(scene, camera, {32, 0, 64, 32}, 7, d.settings, {px.data(), 32 * 3}, trace); }, "renderTile");
    expectFault([&] { renderTileLinear(scene, camera, {32, 0, 64, 32}, 7, d.settings, linear.data(), 32 * 3, trace); },
                "renderTileLinear");
    // Other frames, and the other tiles of frame 7, render (with the fault's option set).
    EXPECT_EQ(renderFrame(scene, camera, d.settings, 6, nullptr, trace).rgb, renderFrame(scene, camera, d.settings, 6).rgb);
    EXPECT_NO_THROW(renderTile(scene, camera, {0, 0, 32, 32}, 7, d.settings, {px.data(), 32 * 3}, trace));
    // What the engine itself throws inside a tile becomes a TileError too.
    TraceOptions bad;
    bad.packetWidth = 12;
    try {
        renderTile(scene, camera, {0, 32, 32, 64}, 3, d.settings, {px.data(), 32 * 3}, bad);
        ADD_FAILURE() << "a packet width of 12 rendered";
    } catch (const TileError& e) {
        EXPECT_EQ(std::string(e.what()), "frame 3, tile 0,32,32,64: packet width 12 is not 0, 4, 8 or 16");
    }
}

// The whole path as a user meets it: `rtwall render --gi --frames 3` fails in frame 3, prints
// one line with the replay command, and that command renders frame 3's pixels of that tile,
// bit for bit (frame 1's differ: the replay does not just render the first frame).
TEST(ReplayCommand, AFailedTileOfAProgressiveGiRenderReplaysBitIdentically) {
    const auto dir = test::scratchDir();
    ASSERT_EQ(run("gen office --out " + dir.string()).status, 0);
    const auto scene = dir / "office.toml";
    const test::CliResult failed =
        run("render " + scene.string() + " --width 96 --height 64 --gi --frames 3 --inject-tile-fault 3,40,20 --out " +
            (dir / "all.png").string());
    EXPECT_EQ(failed.status, 1) << failed.output;
    EXPECT_EQ(std::count(failed.output.begin(), failed.output.end(), '\n'), 1) << failed.output;
    const std::string head = "rtwall: error: frame 3, tile 32,0,64,32: injected fault at pixel 40,20 (replay: ";
    ASSERT_TRUE(failed.output.starts_with(head)) << failed.output;
    const size_t end = failed.output.rfind(')');
    ASSERT_NE(end, std::string::npos);
    const std::string command = failed.output.substr(head.size(), end - head.size());
    EXPECT_NE(command.find("--frame 3"), std::string::npos) << command;

    const Image tile = runReplay(command, dir / "tile.png");
    SceneDesc desc = loadScene(scene.string());
    desc.settings.width = 96;
    desc.settings.height = 64;
    desc.settings.gi = true;
    const Scene s(desc);
    const Camera camera(desc.cameras.front(), 96, 64);
    const TileRect rect{32, 0, 64, 32};
    const Image frame3 = renderFrame(s, camera, desc.settings, 3);
    ASSERT_EQ(tile.width, 96);
    ASSERT_EQ(tile.height, 64);
    EXPECT_EQ(pixelsOf(tile, rect), pixelsOf(frame3, rect));
    EXPECT_TRUE(blackOutside(tile, rect));
    EXPECT_NE(pixelsOf(renderFrame(s, camera, desc.settings, 1), rect), pixelsOf(frame3, rect))
        << "frame 1 and frame 3 draw the same random numbers: the test cannot tell them apart";
}

// A camera that is in no scene file (as a running wall's orbiting or off-axis camera), a scene
// rebased far from the origin, every setting other than the scene file's, each view: the
// replay renders the failed tile's bytes.
TEST(ReplayCommand, ReplaysCamerasAndSettingsThatAreNotTheSceneFiles) {
    const auto dir = test::scratchDir();
    const std::string file = writeFarScene(dir).string();
    const SceneDesc desc = loadScene(file);
    ASSERT_NE(desc.origin[0], 0.0) << "the scene should be rebased";
    const Scene scene(desc);

    CameraDesc orbiting = desc.cameras.front();
    orbiting.name = "not in the file";
    orbiting.position = orbiting.position + Float3{0.3127f, 0.0419f, -0.771f};
    orbiting.lookAt = orbiting.lookAt + Float3{0.0123f, -0.2f, 0.1f};
    orbiting.up = {0.05f, 1.0f, 0.02f};
    orbiting.fovY = 38.5f;
    CameraDesc offAxis = orbiting;
    offAxis.window =
        ProjectionWindow{desc.cameras.front().lookAt + Float3{-1.7f, -0.9f, 0.3f}, {3.1f, 0.0f, -0.2f}, {0.0f, 2.3f, 0.1f}};

    RenderSettings base = desc.settings;
    test::setImage(base, 64, 48, 16);
    base.threads = 2;
    base.gi = true;
    base.samples = 2;
    base.supersample = 2;
    base.maxDepth = 5;
    base.pruneThreshold = 0.0125f;
    base.ambient = {0.01f, 0.02f, 0.03f};
    base.background = {0.2f, 0.3f, 0.4f};
    base.kernel = KernelType::Single;

    struct Variant {
        const char* name;
        CameraDesc camera;
        std::function<void(RenderSettings&, TraceOptions&)> change;
    };
    const std::vector<Variant> variants{
        {"path traced", orbiting, [](RenderSettings&, TraceOptions&) {}},
        {"off-axis window", offAxis, [](RenderSettings&, TraceOptions&) {}},
        {"8-wide packets, no shadows", orbiting,
         [](RenderSettings& s, TraceOptions& t) {
             s.kernel = KernelType::Packet;
             t.packetWidth = 8;
             s.shadows = false;
             s.gi = false;
         }},
        {"eye light", orbiting, [](RenderSettings& s, TraceOptions&) { s.shading = ShadingMode::EyeLight; }},
        {"depth view", orbiting, [](RenderSettings& s, TraceOptions&) { s.view = ViewMode::Depth; }},
        {"client view", orbiting,
         [](RenderSettings& s, TraceOptions& t) {
             s.view = ViewMode::Client;
             t.clientId = 5;
         }},
    };
    for (const Variant& v : variants) {
        RenderSettings s = base;
        TraceOptions trace;
        v.change(s, trace);
        trace.fault = injectFault({9, 20, 30});
        const Camera camera(v.camera, s.width, s.height);
        std::string command;
        try {
            renderFrame(scene, camera, s, 9, nullptr, trace);
            ADD_FAILURE() << v.name << ": the injected fault did not fire";
            continue;
        } catch (const TileError& e) {
            command = replayCommand({file, 3'000'000, desc.origin, v.camera, s, trace, e.frame(), e.rect()});
        }
        const TileRect rect{16, 16, 32, 32};
        const Image tile = runReplay(command, dir / "tile.png");
        trace.fault.reset();
        EXPECT_EQ(pixelsOf(tile, rect), pixelsOf(renderFrame(scene, camera, s, 9, nullptr, trace), rect))
            << v.name << ": " << command;
        EXPECT_TRUE(blackOutside(tile, rect)) << v.name;
    }
}

TEST(ReplayCommand, ABuiltinSceneKeepsItsTriangleCount) {
    TileReplay t;
    t.scene = "builtin:knots";
    t.builtinTriangles = 5000;
    t.settings.width = 96;
    t.settings.height = 64;
    t.camera = builtinScene("knots", 5000).cameras.front();
    t.frame = 2;
    t.rect = {32, 32, 64, 64};
    const std::string command = replayCommand(t);
    EXPECT_NE(command.find("rtwall render builtin:knots --triangles 5000 "), std::string::npos) << command;
    const auto dir = test::scratchDir();
    const Image tile = runReplay(command, dir / "tile.png");
    SceneDesc d = builtinScene("knots", 5000);
    d.settings = t.settings;
    EXPECT_EQ(pixelsOf(tile, t.rect), pixelsOf(renderFrame(Scene(d), Camera(t.camera, 96, 64), d.settings, 2), t.rect));
}

// Paths a shell would split or expand are quoted.
TEST(ReplayCommand, QuotesTheScenePathForTheShell) {
    TileReplay t;
    t.scene = "/tmp/my scenes/it's.toml";
    EXPECT_TRUE(replayCommand(t).starts_with("rtwall render '/tmp/my scenes/it'\\''s.toml' ")) << replayCommand(t);
    t.scene = "/tmp/plain-name_1.toml";
    EXPECT_TRUE(replayCommand(t).starts_with("rtwall render /tmp/plain-name_1.toml ")) << replayCommand(t);
}

// Every input that can change a pixel changes the command. RenderSettings, CameraDesc and
// TraceOptions are checked by size: a new member must be spelled out by replayCommand (or be
// one that never changes a pixel, as threads and tileSize) and then be added here.
TEST(ReplayCommand, SpellsOutEveryInputThatChangesAPixel) {
    EXPECT_EQ(sizeof(RenderSettings), 76u) << "a RenderSettings member was added or removed: does replayCommand say it?";
    EXPECT_EQ(sizeof(CameraDesc), 112u) << "a CameraDesc member was added or removed: does replayCommand say it?";
    EXPECT_EQ(sizeof(TraceOptions), 24u) << "a TraceOptions member was added or removed: does replayCommand say it?";
    TileReplay base;
    base.scene = "scene.toml";
    const std::string baseCommand = replayCommand(base);
    const std::vector<std::pair<const char*, std::function<void(TileReplay&)>>> changes{
        {"scene", [](TileReplay& t) { t.scene = "other.toml"; }},
        {"origin", [](TileReplay& t) { t.origin[1] = 1e5; }},
        {"frame", [](TileReplay& t) { t.frame = 3; }},
        {"rect", [](TileReplay& t) { t.rect.x1 = 7; }},
        {"width", [](TileReplay& t) { t.settings.width = 7; }},
        {"height", [](TileReplay& t) { t.settings.height = 7; }},
        {"kernel", [](TileReplay& t) { t.settings.kernel = KernelType::Single; }},
        {"shading", [](TileReplay& t) { t.settings.shading = ShadingMode::EyeLight; }},
        {"maxDepth", [](TileReplay& t) { t.settings.maxDepth = 3; }},
        {"supersample", [](TileReplay& t) { t.settings.supersample = 3; }},
        {"shadows", [](TileReplay& t) { t.settings.shadows = false; }},
        {"background", [](TileReplay& t) { t.settings.background.z = 0.5f; }},
        {"ambient", [](TileReplay& t) { t.settings.ambient.y = 0.5f; }},
        {"pruneThreshold", [](TileReplay& t) { t.settings.pruneThreshold = 0.5f; }},
        {"gi", [](TileReplay& t) { t.settings.gi = true; }},
        {"samples", [](TileReplay& t) { t.settings.samples = 3; }},
        {"view", [](TileReplay& t) { t.settings.view = ViewMode::Rays; }},
        {"position", [](TileReplay& t) { t.camera.position.x = 0.5f; }},
        {"lookAt", [](TileReplay& t) { t.camera.lookAt.y = 0.5f; }},
        {"up", [](TileReplay& t) { t.camera.up.z = 0.5f; }},
        {"fovY", [](TileReplay& t) { t.camera.fovY = 20.0f; }},
        {"window", [](TileReplay& t) { t.camera.window = ProjectionWindow{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}; }},
        {"packetWidth", [](TileReplay& t) { t.trace.packetWidth = packetWidth() == 4 ? 8 : 4; }},
    };
    for (const auto& [name, change] : changes) {
        TileReplay t = base;
        change(t);
        EXPECT_NE(replayCommand(t), baseCommand) << name;
    }
    // The client id shows in the client view only.
    TileReplay client = base;
    client.settings.view = ViewMode::Client;
    TileReplay other = client;
    other.trace.clientId = 3;
    EXPECT_NE(replayCommand(client), replayCommand(other));
    // The injected fault is not replayed: the replay is to render the tile.
    TileReplay faulty = base;
    faulty.trace.fault = injectFault({0, 0, 0});
    EXPECT_EQ(replayCommand(faulty), baseCommand);
}

}  // namespace
}  // namespace rtwall
