// WallSession on loopback with client threads: the one scene state (the bugs of the old frame
// loop, issue 17, each reproduced), the tile-owner view, frames at a fraction of the wall.
#include "cli_util.h"
#include "display_test_util.h"
#include "session_test_util.h"

#include <rtwall/cluster_testing.h>
#include <rtwall/wall.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes, as the wall's windows report them

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace rtwall {
namespace {

using test::ctrlClick;
using test::keyPress;

// Two boxes on a floor, lit, a camera looking at them; 96x64 pixels in tiles of 32.
std::string sceneText(double boxX, const char* boxColour = "[0.8, 0.2, 0.2]") {
    char text[2048];
    std::snprintf(text, sizeof text, R"([image]
width = 96
height = 64
tile = 32
[render]
ambient = [0.1, 0.1, 0.1]
[[mesh]]
name = "box"
shape = "box"
[[mesh]]
name = "floor"
shape = "quad"
[[material]]
name = "red"
type = "lambert"
color = %s
[[material]]
name = "grey"
type = "lambert"
color = [0.6, 0.6, 0.6]
[[instance]]
mesh = "box"
material = "red"
translate = [%g, 0.5, 0]
[[instance]]
mesh = "floor"
material = "grey"
scale = 8
[[light]]
position = [2, 6, 4]
intensity = 60
[[camera]]
position = [0, 2, 7]
look_at = [0, 0.5, 0]
fov = 40
)",
                  boxColour, boxX);
    return text;
}

RunConfig sessionConfig(const std::filesystem::path& dir, const std::filesystem::path& scene) {
    RunConfig c = steppedRunConfig(dir);
    c.scene = scene.string();
    c.cluster.async = false;  // each frame shows the state at the time of the call
    return c;
}

// Where the box's centre is seen: its pixel, found by projecting with the session's camera.
std::pair<double, double> pixelOf(const WallSession& s, Float3 p) {
    // Search the image for the pixel whose ray passes closest to p (96 x 64: cheap, and exact enough).
    const SceneDesc& d = s.scene();
    const Camera cam(s.camera(), d.settings.width, d.settings.height);
    double best = 1e30, bx = 0, by = 0;
    for (int y = 0; y < d.settings.height; ++y)
        for (int x = 0; x < d.settings.width; ++x) {
            const Float3 o = cam.origin(), dir = cam.direction(x + 0.5f, y + 0.5f);
            const Float3 v{p.x - o.x, p.y - o.y, p.z - o.z};
            const double dd = double(dir.x) * dir.x + double(dir.y) * dir.y + double(dir.z) * dir.z;
            const double t = (double(v.x) * dir.x + double(v.y) * dir.y + double(v.z) * dir.z) / dd;
            const double ex = v.x - t * dir.x, ey = v.y - t * dir.y, ez = v.z - t * dir.z;
            const double dist = ex * ex + ey * ey + ez * ez;
            if (dist < best) best = dist, bx = x + 0.5, by = y + 0.5;
        }
    return {bx, by};
}

// Issue 17: a --watch edit updated only the loop's copy and the master, so picks went on using
// the transforms the scene was started with.
TEST(WallSession, PickingSeesWhatAnEditMoved) {
    const auto dir = test::scratchDir();
    const auto file = test::writeFile(dir / "scene.toml", sceneText(0.0));
    WallSession s(sessionConfig(dir, file));
    ASSERT_TRUE(s.step());
    const auto [x0, y0] = pixelOf(s, {0, 0.5f, 0});
    ASSERT_TRUE(s.pick(x0, y0));
    EXPECT_EQ(s.pick(x0, y0)->instance, 0u) << "the box, where the file put it";
    const SceneEdit e = s.applyEdit(loadSceneFile(test::writeFile(dir / "scene.toml", sceneText(2.0))));
    EXPECT_EQ(e.transforms.size(), 1u);
    ASSERT_TRUE(s.step());
    const auto p = s.pick(x0, y0);
    EXPECT_TRUE(!p || p->instance != 0u) << "the box is not where it was any more";
    const auto [x1, y1] = pixelOf(s, {2, 0.5f, 0});
    ASSERT_TRUE(s.pick(x1, y1));
    EXPECT_EQ(s.pick(x1, y1)->instance, 0u) << "the box where the edit moved it";
    EXPECT_EQ(test::bytesOffState(s), 0u);
}

// Issue 17: a Ctrl+drag updated only the master and the view's copy, so the loop's state no
// longer matched the clients', and a later --watch edit was diffed against the wrong state.
TEST(WallSession, TheStateItHoldsIsWhatTheClientsRender) {
    const auto dir = test::scratchDir();
    const auto file = test::writeFile(dir / "scene.toml", sceneText(0.0));
    WallSession s(sessionConfig(dir, file));
    ASSERT_TRUE(s.step());
    EXPECT_EQ(test::bytesOffState(s), 0u);
    // A drag (WallInput moves objects through the same call).
    s.setInstanceTransform(0, Transform::translate(-1.5, 0.5, 0.5));
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[0].transform.m[3], -1.5);
    EXPECT_EQ(test::bytesOffState(s), 0u) << "after the drag";
    // The file changes only a colour: the reload puts the box back where the file has it.
    const SceneEdit e = s.applyEdit(loadSceneFile(test::writeFile(dir / "scene.toml", sceneText(0.0, "[0.2, 0.8, 0.2]"))));
    EXPECT_EQ(e.materials.size(), 1u);
    ASSERT_EQ(e.transforms.size(), 1u) << "the dragged box differs from the file";
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[0].transform.m[3], 0.0);
    EXPECT_EQ(test::bytesOffState(s), 0u) << "after the reload";
    // Nothing refused as malformed, unknown, repeated or unexpected. A stale message (a tile
    // request for a frame that has just ended) is normal with two clients and is not counted here.
    const MasterCounters c = s.summary().counters;
    EXPECT_EQ(c.dropped() - c.stale, 0u) << describeCounters(c);
}

// Issue 17: the tile-owner view (key T) drew the tile grid the run started with, whatever the
// tile control or a [render] edit set since.
TEST(WallSession, TheTileOwnerViewFollowsTheTileSize) {
    const auto dir = test::scratchDir();
    WallSession s(sessionConfig(dir, test::writeFile(dir / "scene.toml", sceneText(0.0))));
    s.showTileOwners(true);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.lastFrame().tileSize, 32);
    EXPECT_EQ(s.lastFrame().tileOwners.size(), 3u * 2u);
    RenderSettings smaller = s.scene().settings;
    smaller.tileSize = 16;
    s.setRenderSettings(smaller);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.lastFrame().tileSize, 16);
    EXPECT_EQ(s.lastFrame().tileOwners.size(), 6u * 4u);
    for (uint32_t owner : s.lastFrame().tileOwners) EXPECT_NE(owner, UINT32_MAX) << "every tile has its client";
}

// Issue 17: the scale control renders a smaller frame, which the presenters refused (they threw
// for a frame that is not the wall's size), so an operating point with a scale below 1 ended the
// run. The wall shows it upscaled; the screens get their full size.
TEST(WallSession, AFrameAtAFractionOfTheWallIsShownUpscaled) {
    const auto dir = test::scratchDir();
    const auto wall = test::writeFile(dir / "wall.toml", R"([wall]
name = "pair"
[grid]
columns = 2
rows = 1
screen_width = 48
screen_height = 64
[headless]
write_every = 1
)");
    const auto front = test::writeFile(dir / "front.toml", R"([[point]]
name = "half"
frame_s = 0.001
error = 0.5
[point.controls]
scale = 0.5
tile = 16
)");
    RunConfig c = sessionConfig(dir, test::writeFile(dir / "scene.toml", sceneText(0.0)));
    c.wall = wall;
    c.targetFps = 10;
    c.front = front;
    c.writeEvery = 1;
    WallSession s(c);
    s.showTileOwners(true);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.lastFrame().left.width, 48) << "rendered at half the wall's resolution";
    EXPECT_EQ(s.lastFrame().tileSize, 16);
    const uint32_t n = s.lastReport().frame;
    char name[64];
    std::snprintf(name, sizeof name, "frame_%06u", n);
    EXPECT_EQ(readPng(dir / (std::string(name) + ".png")).width, 96) << "the file is the wall's size";
    for (const char* screen : {"_c0r0.png", "_c1r0.png"}) {
        const Image img = readPng(dir / (std::string(name) + screen));
        EXPECT_EQ(img.width, 48) << screen;
        EXPECT_EQ(img.height, 64) << screen;
    }
}

// The wall's keys and mouse, as its windows would report them (injected: the same code path,
// headless): Ctrl+drag moves an object through the one state, a drag orbits the camera, R records
// a camera path that replays, Esc ends the run.
TEST(WallSession, KeysAndMouseChangeTheSceneThroughItsOneState) {
    const auto dir = test::scratchDir();
    WallSession s(sessionConfig(dir, test::writeFile(dir / "scene.toml", sceneText(0.0))));
    ASSERT_TRUE(s.step());
    // Ctrl+click on the box, then drag it 20 pixels to the right.
    const auto [x, y] = pixelOf(s, {0, 0.5f, 0});
    InputState press;
    press.leftPressed = press.leftDown = true;
    press.clickMods = GLFW_MOD_CONTROL;
    press.wallX = x;
    press.wallY = y;
    InputState drag = press;
    drag.leftPressed = false;
    drag.wallX = x + 20;
    s.inject(press);
    s.inject(drag);
    ASSERT_TRUE(s.step());
    EXPECT_GT(s.scene().instances[0].transform.m[3], 0.1) << "the box moved right";
    EXPECT_EQ(test::bytesOffState(s), 0u) << "and the clients render it there";
    // Release, then R, an orbiting drag, R: a recorded camera path.
    InputState release;
    s.inject(release);
    s.inject(keyPress(GLFW_KEY_R));
    InputState orbit;
    orbit.leftDown = true;
    orbit.mouseDx = 40;
    s.inject(orbit);
    s.inject(orbit);
    s.inject(keyPress(GLFW_KEY_R));
    const CameraDesc before = s.camera();
    ASSERT_TRUE(s.step());
    EXPECT_NE(s.camera().position.x, before.position.x) << "the drag orbited the camera";
    EXPECT_EQ(s.scene().cameras.front().position.x, s.camera().position.x) << "the state holds the camera the wall shows";
    const std::vector<CameraKey> path = readCameraPath(dir / "camera_path_1.toml", s.scene().origin);
    ASSERT_GE(path.size(), 2u);
    EXPECT_EQ(path.back().camera.position.x, s.camera().position.x);
    // Esc ends the run before another frame.
    InputState esc;
    esc.keyDown[GLFW_KEY_ESCAPE] = true;
    s.inject(esc);
    EXPECT_FALSE(s.step());
}

// Issue 17: a tile a render client fails is one line of the session's log with the command that
// renders just that tile again (the frame's camera, here not the scene file's, its settings and
// the client's packet width); run, the command gives the pixels the frame should have had there.
TEST(WallSession, AFailedTileIsOneLineWithTheCommandThatReplaysIt) {
    const auto dir = test::scratchDir();
    const std::filesystem::path scene = test::writeFile(dir / "scene.toml", sceneText(0.0));
    RunConfig c = sessionConfig(dir, scene);
    c.cluster.localClients = 1;
    c.cluster.timeoutMs = 500;  // the frame fails soon once its only client has left
    // Frame 2, in the tile of pixels 32,0 to 64,32.
    c.clientFaults = std::make_shared<const ClientFaults>(ClientFaults{.tileFault = InjectedTileFault{2, 40, 20}});
    std::vector<std::string> lines;
    c.log = [&](const std::string& line) { lines.push_back(line); };
    WallSession s(c);
    ASSERT_TRUE(s.step());
    ASSERT_EQ(s.lastReport().frame, 1u);
    CameraDesc moved = s.camera();
    moved.position = {1.5f, 2.5f, 6.0f};
    s.setCamera(moved);
    lines.clear();
    try {
        s.step();
    } catch (const std::exception&) {
        // The frame may fail: its only client left.
    }
    std::vector<std::string> failed;
    for (const std::string& line : lines)
        if (line.find("failed frame") != std::string::npos) failed.push_back(line);
    ASSERT_EQ(failed.size(), 1u) << "one line for the one failed tile";
    const std::string& line = failed.front();
    const std::string head = "client 1 failed frame 2, tile 32,0,64,32: injected fault at pixel 40,20 (replay: ";
    ASSERT_TRUE(line.starts_with(head) && line.ends_with(")")) << line;
    const std::string command = line.substr(head.size(), line.size() - head.size() - 1);

    const SceneDesc loaded = loadScene(scene.string());
    TileReplay expected;
    expected.scene = scene.string();
    expected.origin = loaded.origin;
    expected.camera = moved;
    expected.settings = loaded.settings;
    expected.trace.packetWidth = packetWidth();  // the client's: this CPU's widest
    expected.trace.clientId = 1;
    expected.frame = 2;
    expected.rect = {32, 0, 64, 32};
    EXPECT_EQ(command, replayCommand(expected));

    // Run, it renders that tile alone: the pixels of frame 2 there, nothing elsewhere.
    const std::string tail = " --out tile.png";
    ASSERT_TRUE(command.starts_with("rtwall render ") && command.ends_with(tail)) << command;
    const std::filesystem::path out = dir / "replayed.png";
    const test::CliResult r =
        test::runCli(RTWALL_EXE, command.substr(7, command.size() - 7 - tail.size()) + " --out " + out.string());
    ASSERT_EQ(r.status, 0) << command << "\n" << r.output;
    const Image replayed = readPng(out);
    const Image frame2 = renderFrame(Scene(loaded), Camera(moved, loaded.settings.width, loaded.settings.height),
                                     loaded.settings, 2);
    ASSERT_EQ(replayed.width, frame2.width);
    ASSERT_EQ(replayed.height, frame2.height);
    size_t differing = 0, lit = 0;
    for (int y = 0; y < frame2.height; ++y)
        for (int x = 0; x < frame2.width; ++x)
            for (int k = 0; k < 3; ++k) {
                const bool inTile = x >= 32 && x < 64 && y < 32;
                if (inTile) differing += replayed.pixel(x, y)[k] != frame2.pixel(x, y)[k];
                else lit += replayed.pixel(x, y)[k] != 0;
            }
    EXPECT_EQ(differing, 0u) << "the replayed tile differs from frame 2's";
    EXPECT_EQ(lit, 0u) << "the replay renders that tile alone";
}

// Issue 20: picking an object of an assembly names its part (the glTF node path), so that a
// reviewer on the wall can say which part is meant.
TEST(WallSession, PickingAnAssemblyNamesThePart) {
    const auto dir = test::scratchDir();
    const std::string cmd = "python3 " + (std::filesystem::path(RTWALL_SOURCE_DIR) / "tools" / "gltf_testgen.py").string() +
                            " --out " + dir.string();
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    RunConfig c = sessionConfig(dir, dir / "binary.glb");
    auto lines = std::make_shared<std::vector<std::string>>();
    c.log = [lines](const std::string& line) { lines->push_back(line); };
    WallSession s(c);
    ASSERT_TRUE(s.step());
    ASSERT_FALSE(s.scene().parts.empty());
    // box_a's top face centre, (-2, 1, 0) in the file.
    const auto [x, y] = pixelOf(s, {-2.0f, 1.0f, 0.0f});
    InputState press;
    press.leftPressed = press.leftDown = true;
    press.clickMods = GLFW_MOD_CONTROL;
    press.wallX = x;
    press.wallY = y;
    s.inject(press);
    ASSERT_TRUE(s.step());
    bool named = false;
    for (const std::string& l : *lines) named = named || (l.find("picked instance") != std::string::npos && l.find("part 'root/box_a'") != std::string::npos);
    EXPECT_TRUE(named) << (lines->empty() ? std::string("no log lines") : lines->back());
}

// ---- Measuring (issue 20) ------------------------------------------------------------------------

// A part with a slot of known width: two boxes ([-1, 1]^3) whose inner faces lie kSlot apart along x
// (x = -kSlot/2 and +kSlot/2 around `at`), seen from between them; no floor, so the top of the
// image between them is background.
constexpr double kSlot = 2.5;
std::string slotSceneText(const std::array<double, 3>& at) {
    char text[2048];
    std::snprintf(text, sizeof text, R"([image]
width = 192
height = 128
tile = 32
[render]
ambient = [0.1, 0.1, 0.1]
[[mesh]]
name = "box"
shape = "box"
[[material]]
name = "red"
type = "lambert"
color = [0.8, 0.2, 0.2]
[[instance]]
mesh = "box"
material = "red"
translate = [%.17g, %.17g, %.17g]
[[instance]]
mesh = "box"
material = "red"
translate = [%.17g, %.17g, %.17g]
[[light]]
position = [%.17g, %.17g, %.17g]
intensity = 30
[[camera]]
position = [%.17g, %.17g, %.17g]
look_at = [%.17g, %.17g, %.17g]
fov = 70
)",
                  at[0] - kSlot / 2 - 1, at[1], at[2], at[0] + kSlot / 2 + 1, at[1], at[2], at[0], at[1] + 4, at[2] + 4,
                  at[0], at[1], at[2] + 2.5, at[0], at[1], at[2]);
    return text;
}

// The wall position whose ray passes through p (file coordinates): direction(px, py) is
// corner + px du + py dv, so p - eye = t corner + (t px) du + (t py) dv is solved for t, px, py.
// Aiming through the point itself (not the nearest pixel centre) keeps the pixel footprint out
// of the measured distance: what is left is single-precision rounding.
std::pair<double, double> wallPositionOf(const WallSession& s, const std::array<double, 3>& p) {
    const SceneDesc& d = s.scene();
    const Camera cam(s.camera(), d.settings.width, d.settings.height);
    // du and dv from the image's far edges: a difference over one pixel would keep only a few
    // significant digits of the float directions.
    const float w1 = float(d.settings.width), h1 = float(d.settings.height);
    const Float3 o = cam.origin(), c = cam.direction(0, 0), x1 = cam.direction(w1, 0), y1 = cam.direction(0, h1);
    const std::array<double, 3> u{(double(x1.x) - c.x) / w1, (double(x1.y) - c.y) / w1, (double(x1.z) - c.z) / w1};
    const std::array<double, 3> v{(double(y1.x) - c.x) / h1, (double(y1.y) - c.y) / h1, (double(y1.z) - c.z) / h1};
    const std::array<double, 3> w{double(c.x), double(c.y), double(c.z)};
    const std::array<double, 3> r{p[0] - d.origin[0] - o.x, p[1] - d.origin[1] - o.y, p[2] - d.origin[2] - o.z};
    auto det = [](const std::array<double, 3>& a, const std::array<double, 3>& b, const std::array<double, 3>& e) {
        return a[0] * (b[1] * e[2] - b[2] * e[1]) - a[1] * (b[0] * e[2] - b[2] * e[0]) + a[2] * (b[0] * e[1] - b[1] * e[0]);
    };
    const double dd = det(w, u, v), t = det(r, u, v) / dd;
    return {det(w, r, v) / dd / t, det(w, u, r) / dd / t};
}

// Esc as GLFW reports a press: pressed since the last poll, and down.
InputState escapePress() {
    InputState in = keyPress(GLFW_KEY_ESCAPE);
    in.keyDown[GLFW_KEY_ESCAPE] = true;
    return in;
}

// Both points lie on faces the camera sees at ~2.6 units and at least ~60 degrees from the
// normal (cos >= 0.47); the hit t and the ray are single precision (a few ulps of 2^-24 of the
// distance), so each point is off by < 16 * 6e-8 * 2.6 / 0.47 ~ 5e-6, the distance by twice that.
// The origin of the far scene is added in double (1e6 * 2^-53 ~ 1e-10): the same budget.
constexpr double kMeasureTolerance = 1e-5;

struct MeasuredSlot {
    Measurement m;
    std::vector<std::string> lines;
};
MeasuredSlot measureSlot(const std::array<double, 3>& at) {
    const auto dir = test::scratchDir();
    const auto file = test::writeFile(dir / "slot.toml", slotSceneText(at));
    RunConfig c = sessionConfig(dir, file);
    auto lines = std::make_shared<std::vector<std::string>>();
    c.log = [lines](const std::string& line) { lines->push_back(line); };
    WallSession s(c);
    EXPECT_TRUE(s.step());
    // Points on the two inner faces, at the same height and depth: kSlot apart.
    const std::array<double, 3> a{at[0] - kSlot / 2, at[1] + 0.1, at[2] + 0.2}, b{at[0] + kSlot / 2, at[1] + 0.1, at[2] + 0.2};
    s.inject(keyPress(GLFW_KEY_M));
    s.inject(ctrlClick(wallPositionOf(s, a)));
    s.inject(ctrlClick(wallPositionOf(s, b)));
    EXPECT_TRUE(s.step());
    EXPECT_TRUE(s.measuring());
    MeasuredSlot r;
    if (s.measurement()) r.m = *s.measurement();
    r.lines = *lines;
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(r.m.a[i], a[i], kMeasureTolerance / 2) << "A[" << i << "]";
        if (r.m.b) {
            EXPECT_NEAR((*r.m.b)[i], b[i], kMeasureTolerance / 2) << "B[" << i << "]";
        }
    }
    return r;
}

// The line the log got for a finished measurement, read back.
std::optional<Measurement> parseMeasureLine(const std::vector<std::string>& lines) {
    for (const std::string& l : lines) {
        Measurement m;
        std::array<double, 3> b{};
        if (std::sscanf(l.c_str(), "measure: A (%lf, %lf, %lf) to B (%lf, %lf, %lf): %lf scene units", &m.a[0], &m.a[1], &m.a[2],
                        &b[0], &b[1], &b[2], &m.distance) == 7) {
            m.b = b;
            return m;
        }
    }
    return std::nullopt;
}

TEST(WallSession, MeasuringASlotGivesItsWidth) {
    const MeasuredSlot r = measureSlot({0, 0, 0});
    ASSERT_TRUE(r.m.b) << (r.lines.empty() ? "no log lines" : r.lines.back());
    EXPECT_NEAR(r.m.distance, kSlot, kMeasureTolerance);
    const auto printed = parseMeasureLine(r.lines);
    ASSERT_TRUE(printed) << r.lines.back();
    EXPECT_NEAR(printed->distance, kSlot, kMeasureTolerance);
}

// A CAD model 1e6 units from the file's origin is rebased on load; the measurement is in the
// file's coordinates and as precise as at the origin (in float, 1e6 is 0.0625 from its neighbour).
TEST(WallSession, MeasuringFarFromTheOriginIsAsPrecise) {
    const std::array<double, 3> at{1000000.375, 250.5, -1000000.25};
    const MeasuredSlot r = measureSlot(at);
    ASSERT_TRUE(r.m.b) << (r.lines.empty() ? "no log lines" : r.lines.back());
    EXPECT_NEAR(r.m.distance, kSlot, kMeasureTolerance);
    const auto printed = parseMeasureLine(r.lines);
    ASSERT_TRUE(printed) << r.lines.back();
    EXPECT_NEAR(printed->distance, kSlot, kMeasureTolerance);
    EXPECT_NEAR(printed->a[0], at[0] - kSlot / 2, 1e-5) << "the file's coordinates, printed";
    EXPECT_NEAR(printed->a[2], at[2] + 0.2, 1e-5);
    EXPECT_NEAR((*printed->b)[0], at[0] + kSlot / 2, 1e-5);
}

TEST(WallSession, MeasureModeKeys) {
    const auto dir = test::scratchDir();
    const auto file = test::writeFile(dir / "slot.toml", slotSceneText({0, 0, 0}));
    RunConfig c = sessionConfig(dir, file);
    auto lines = std::make_shared<std::vector<std::string>>();
    c.log = [lines](const std::string& line) { lines->push_back(line); };
    WallSession s(c);
    ASSERT_TRUE(s.step());
    const auto a = wallPositionOf(s, {-kSlot / 2, 0.1, 0.2}), b = wallPositionOf(s, {kSlot / 2, 0.1, 0.2});
    const Transform before = s.scene().instances[0].transform;

    // Off: Ctrl+click picks (and a drag would move), nothing is measured.
    s.inject(ctrlClick(a));
    ASSERT_TRUE(s.step());
    EXPECT_FALSE(s.measuring());
    EXPECT_FALSE(s.measurement());

    s.inject(keyPress(GLFW_KEY_M));
    ASSERT_TRUE(s.step());
    EXPECT_TRUE(s.measuring());
    EXPECT_FALSE(s.measurement()) << "a new mode starts without points";
    s.inject(ctrlClick(a));
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.measurement());
    EXPECT_FALSE(s.measurement()->b);
    // A drag with Ctrl held after the click moves nothing while measuring.
    InputState drag = ctrlClick(b);
    drag.leftPressed = false;
    s.inject(drag);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[0].transform.m, before.m) << "measuring moved the part";
    s.inject(ctrlClick(b));
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.measurement() && s.measurement()->b);
    EXPECT_NEAR(s.measurement()->distance, kSlot, kMeasureTolerance);

    // A third pick starts a new measurement at that point.
    s.inject(ctrlClick(b));
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.measurement());
    EXPECT_FALSE(s.measurement()->b);
    EXPECT_NEAR(s.measurement()->a[0], kSlot / 2, kMeasureTolerance);
    // ... and the next ends it: across the slot and along the faces, all three axes count.
    s.inject(ctrlClick(wallPositionOf(s, {-kSlot / 2, -0.3, -0.4})));
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.measurement() && s.measurement()->b);
    EXPECT_NEAR(s.measurement()->distance, std::sqrt(kSlot * kSlot + 0.4 * 0.4 + 0.6 * 0.6), kMeasureTolerance);

    // M leaves the mode and forgets the points.
    s.inject(keyPress(GLFW_KEY_M));
    ASSERT_TRUE(s.step());
    EXPECT_FALSE(s.measuring());
    EXPECT_FALSE(s.measurement());

    // Esc leaves it too, and does not close the wall, also while it is held on.
    s.inject(keyPress(GLFW_KEY_M));
    s.inject(ctrlClick(a));
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.measurement());
    s.inject(escapePress());
    ASSERT_TRUE(s.step()) << "the Esc that leaves measure mode closed the wall";
    EXPECT_FALSE(s.measuring());
    EXPECT_FALSE(s.measurement());
    InputState held;
    held.keyDown[GLFW_KEY_ESCAPE] = true;
    s.inject(held);
    ASSERT_TRUE(s.step()) << "holding that Esc closed the wall";
    s.inject(InputState{});  // released
    ASSERT_TRUE(s.step());
    s.inject(escapePress());
    EXPECT_FALSE(s.step()) << "out of measure mode, Esc closes the wall as before";

    bool on = false, off = false;
    for (const std::string& l : *lines) on = on || l.rfind("measure: on", 0) == 0, off = off || l == "measure: off";
    EXPECT_TRUE(on && off);
}

TEST(WallSession, MeasuringTheBackgroundSetsNoPoint) {
    const auto dir = test::scratchDir();
    const auto file = test::writeFile(dir / "slot.toml", slotSceneText({0, 0, 0}));
    RunConfig c = sessionConfig(dir, file);
    auto lines = std::make_shared<std::vector<std::string>>();
    c.log = [lines](const std::string& line) { lines->push_back(line); };
    WallSession s(c);
    ASSERT_TRUE(s.step());
    ASSERT_FALSE(s.pick(96, 1)) << "the top centre must be background";
    EXPECT_FALSE(s.measurePick(wallPositionOf(s, {-kSlot / 2, 0.1, 0.2}).first, 60)) << "not measuring";
    s.setMeasuring(true);
    s.inject(ctrlClick({96, 1}));
    ASSERT_TRUE(s.step());
    EXPECT_FALSE(s.measurement()) << "a miss set point A";
    auto said = [&](const std::string& line) { return std::find(lines->begin(), lines->end(), line) != lines->end(); };
    EXPECT_TRUE(said("measure: nothing under the cursor, point A not set"));
    EXPECT_TRUE(s.measurePick(wallPositionOf(s, {-kSlot / 2, 0.1, 0.2}).first, wallPositionOf(s, {-kSlot / 2, 0.1, 0.2}).second));
    EXPECT_FALSE(s.measurePick(96, 1));
    ASSERT_TRUE(s.measurement());
    EXPECT_FALSE(s.measurement()->b) << "a miss set point B";
    EXPECT_TRUE(said("measure: nothing under the cursor, point B not set"));
}

}  // namespace
}  // namespace rtwall

// ---- Section planes (issue 20) --------------------------------------------------------------------

namespace rtwall {
namespace {

double dot3(const Float3& a, const Float3& b) { return double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z; }
Float3 unit3(const Float3& v) {
    const float l = std::sqrt(float(dot3(v, v)));
    return {v.x / l, v.y / l, v.z / l};
}

// The section keys and WallSession::setSection change the one state: the clients render each
// step exactly as one machine renders that state (differential updates), and the planes do what
// the keys say.
TEST(WallSession, SectionKeysAndSetSectionCutTheScene) {
    const auto dir = test::scratchDir();
    RunConfig c = sessionConfig(dir, test::writeFile(dir / "scene.toml", sceneText(0.0)));
    auto lines = std::make_shared<std::vector<std::string>>();
    c.log = [lines](const std::string& line) { lines->push_back(line); };
    WallSession s(c);
    ASSERT_TRUE(s.step());
    const Image uncut = s.lastFrame().left;
    EXPECT_EQ(s.activeSection(), -1);

    // C: a plane through the point looked at, facing along the view: the box's front is cut away.
    s.inject(keyPress(GLFW_KEY_C));
    ASSERT_TRUE(s.step());
    ASSERT_EQ(s.activeSection(), 0);
    const SectionPlane added = s.scene().sections[0];
    EXPECT_TRUE(added.enabled);
    const CameraDesc cam = s.camera();
    EXPECT_EQ(added.point, cam.lookAt);
    const Float3 view = unit3({cam.lookAt.x - cam.position.x, cam.lookAt.y - cam.position.y, cam.lookAt.z - cam.position.z});
    EXPECT_NEAR(dot3(unit3(added.normal), view), 1.0, 1e-6);
    EXPECT_GT(test::differingBytes(s.lastFrame().left, uncut), 0u) << "the cut shows";
    EXPECT_EQ(test::bytesOffState(s), 0u) << "and the clients render the state";
    ASSERT_FALSE(lines->empty());
    EXPECT_NE(lines->back().find("section 0: on"), std::string::npos) << lines->back();

    // PageUp moves it along its normal by 1/100 of the scene's size (the floor's diagonal: 8 x 8
    // units and the box's 2 units of height), Shift+PageDown ten times that back.
    s.inject(keyPress(GLFW_KEY_PAGE_UP));
    ASSERT_TRUE(s.step());
    const SectionPlane moved = s.scene().sections[0];
    const Float3 step{moved.point.x - added.point.x, moved.point.y - added.point.y, moved.point.z - added.point.z};
    EXPECT_NEAR(dot3(step, unit3(added.normal)), std::sqrt(16.0 * 16.0 + 16.0 * 16.0 + 2.0 * 2.0) / 100.0, 1e-4);
    s.inject(keyPress(GLFW_KEY_PAGE_DOWN, GLFW_MOD_SHIFT));
    ASSERT_TRUE(s.step());
    const Float3 back{s.scene().sections[0].point.x - moved.point.x, s.scene().sections[0].point.y - moved.point.y,
                      s.scene().sections[0].point.z - moved.point.z};
    EXPECT_NEAR(dot3(back, unit3(added.normal)), -10.0 * std::sqrt(16.0 * 16.0 + 16.0 * 16.0 + 2.0 * 2.0) / 100.0, 1e-3);
    EXPECT_EQ(test::bytesOffState(s), 0u);

    // Left turns the normal 5 degrees about the view's up axis; F flips it; V turns it off.
    const Float3 n0 = unit3(s.scene().sections[0].normal);
    s.inject(keyPress(GLFW_KEY_LEFT));
    ASSERT_TRUE(s.step());
    const Float3 n1 = unit3(s.scene().sections[0].normal);
    const Float3 up = unit3(s.camera().up);
    EXPECT_NEAR(dot3(n0, up), dot3(n1, up), 1e-6) << "turned about the up axis";
    auto flat = [&](const Float3& n) {
        const double u = dot3(n, up);
        return Float3{float(n.x - u * up.x), float(n.y - u * up.y), float(n.z - u * up.z)};
    };
    EXPECT_NEAR(std::acos(std::min(1.0, dot3(unit3(flat(n0)), unit3(flat(n1))))) * 180.0 / 3.14159265358979, 5.0, 0.01);
    s.inject(keyPress(GLFW_KEY_F));
    ASSERT_TRUE(s.step());
    EXPECT_NEAR(dot3(unit3(s.scene().sections[0].normal), n1), -1.0, 1e-6);
    EXPECT_EQ(test::bytesOffState(s), 0u);
    s.inject(keyPress(GLFW_KEY_V));
    ASSERT_TRUE(s.step());
    EXPECT_FALSE(s.scene().sections[0].enabled);
    EXPECT_EQ(test::differingBytes(s.lastFrame().left, uncut), 0u) << "a plane turned off cuts nothing";

    // The API a wand calls: any slot, in the scene's coordinates; it becomes the active plane.
    SectionPlane p;
    p.enabled = true;
    p.point = {0, 0.5f, 0};
    p.normal = {1, 0, 0};
    p.capColor = {0.1f, 0.2f, 0.9f};
    s.setSection(3, p);
    EXPECT_EQ(s.activeSection(), 3);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().sections[3], p);
    EXPECT_EQ(test::bytesOffState(s), 0u);
    EXPECT_THROW(s.setSection(uint32_t(kMaxSections), p), std::out_of_range);
    SectionPlane zero = p;
    zero.normal = {0, 0, 0};
    EXPECT_THROW(s.setSection(1, zero), std::invalid_argument);
    EXPECT_EQ(s.scene().sections[1], SectionPlane{}) << "a refused plane changes nothing";

    // Shift+C selects the next plane in use (slot 0 is off but in use), then none; Del removes one.
    s.inject(keyPress(GLFW_KEY_C, GLFW_MOD_SHIFT));
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.activeSection(), -1) << "after slot 3, the last in use: none";
    s.inject(keyPress(GLFW_KEY_C, GLFW_MOD_SHIFT));
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.activeSection(), 0);
    s.inject(keyPress(GLFW_KEY_DELETE));
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.activeSection(), -1);
    EXPECT_EQ(s.scene().sections[0], SectionPlane{});
    EXPECT_TRUE(s.scene().sections[3].enabled) << "the other plane stays";
    EXPECT_EQ(test::bytesOffState(s), 0u);
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// Issue 19: a wall whose screens name display nodes. The session starts them (threads here,
// processes in `rtwall run`), the master holds no pixels, and each node shows its screens of the
// single-PC frame exactly, every frame.
TEST(WallSession, AWallOnDisplayNodesShowsItsScreensOnTheNodes) {
    const auto dir = test::scratchDir();
    const auto scene = test::writeFile(dir / "scene.toml", sceneText(0.0));
    const auto wall = test::writeFile(dir / "wall.toml", "[wall]\nname = \"pair\"\n[grid]\ncolumns = 2\nrows = 1\nscreen_width = 48\n"
                                                         "screen_height = 64\n[[node]]\nname = \"a\"\ncolumns = [0, 0]\n[[node]]\n"
                                                         "name = \"b\"\ncolumns = [1, 1]\n[headless]\nwrite_every = 1\n");
    RunConfig c = sessionConfig(dir / "out", scene);
    c.wall = wall;
    c.frames = 3;
    c.framesGiven = true;
    std::vector<std::string> lines;
    c.log = [&lines](const std::string& l) { lines.push_back(l); };
    SceneDesc desc = loadSceneFile(scene);
    {
        WallSession s(c);
        while (s.step()) {
        }
        EXPECT_TRUE(s.lastFrame().left.rgb.empty()) << "the master holds no pixels";
        EXPECT_EQ(s.lastReport().displayNodes, 2u);
        EXPECT_GE(s.lastReport().swapsReleased, 2u);
        EXPECT_EQ(s.summary().frames, 3u);
    }
    std::string log;
    for (const std::string& l : lines) log += l + "\n";
    EXPECT_NE(log.find("display nodes: all 2 joined (a, b)"), std::string::npos) << log;

    WallFrame one;
    one.left = test::renderFirstCamera(desc);
    one.number = 1;
    HeadlessPresenter(loadWallConfig(wall), dir / "one").present(one);
    for (const auto& [node, screen] : std::vector<std::pair<std::string, std::string>>{{"a", "c0r0"}, {"b", "c1r0"}})
        for (int frame = 1; frame <= 3; ++frame) {
            char name[64];
            std::snprintf(name, sizeof name, "frame_%06d_%s.png", frame, screen.c_str());
            const std::filesystem::path shown = dir / "out" / node / name;
            ASSERT_TRUE(std::filesystem::exists(shown)) << shown << "\n" << log;
            EXPECT_EQ(test::differingBytes(readPng(shown), readPng(dir / "one" / ("frame_000001_" + screen + ".png"))), 0u) << shown;
        }
}

TEST(WallSession, ATargetFrameRateOnDisplayNodesNeedsAFront) {
    const auto dir = test::scratchDir();
    const auto scene = test::writeFile(dir / "scene.toml", sceneText(0.0));
    const auto wall = test::writeFile(dir / "wall.toml", "[wall]\n[grid]\ncolumns = 2\nrows = 1\nscreen_width = 48\nscreen_height = 64\n"
                                                         "[[node]]\nname = \"a\"\ncolumns = [0, 0]\n[[node]]\nname = \"b\"\ncolumns = [1, 1]\n");
    RunConfig c = sessionConfig(dir, scene);
    c.wall = wall;
    c.targetFps = 30;
    try {
        WallSession s(c);
        ADD_FAILURE() << "a calibration without pixels was started";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "--target-fps on a wall of display nodes needs --front: the master holds no pixels to calibrate with");
    }
}

}  // namespace
}  // namespace rtwall
