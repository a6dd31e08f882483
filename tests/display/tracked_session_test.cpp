// A tracked wall end to end in one process (loopback, client threads): DTrack datagrams for a
// head at the config's viewer give the very bytes of the static render with that viewer, on a
// flat 2x2 stereo wall and on a three-wall CAVE; a tilted or moved head changes the eye images.
#include "display_test_util.h"
#include "session_tracker.h"
#include "test_util.h"

#include <rtwall/wall.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

namespace rtwall {
namespace {

const std::string kScene = test::sceneText("tracked_boxes");

// The shipped walls' geometry at a few pixels per screen. `viewer` is [stereo]'s.
std::string flatWall(const char* viewer, bool tracked) {
    std::string t = R"([wall]
vsync = false
[grid]
columns = 2
rows = 2
screen_width = 24
screen_height = 16
[stereo]
mode = "passive"
eye_separation = 0.065
viewer = )" + std::string(viewer) + R"(
lower_left = [-1.6, -1.2, 0.0]
lower_right = [1.6, -1.2, 0.0]
upper_left = [-1.6, 1.2, 0.0]
[headless]
write_every = 0
)";
    if (tracked)
        t += "[tracking]\nsource = \"dtrack://127.0.0.1:0\"\nroom_rotate = [-90, 0, 0]\nroom_translate = [0, -1.5, 2.5]\ntimeout_ms = 60000\n";
    return t;
}

std::string caveWall(const char* viewer, bool tracked) {
    std::string t = R"([wall]
width = 96
height = 24
vsync = false
[stereo]
mode = "passive"
viewer = )" + std::string(viewer) + R"(
lower_left = [-1.5, 0.0, -1.5]
lower_right = [1.5, 0.0, -1.5]
upper_left = [-1.5, 2.25, -1.5]
[headless]
write_every = 0
)";
    const char* walls[3][4] = {{"left", "[-1.5, 0, 1.5]", "[-1.5, 0, -1.5]", "[-1.5, 2.25, 1.5]"},
                               {"front", "[-1.5, 0, -1.5]", "[1.5, 0, -1.5]", "[-1.5, 2.25, -1.5]"},
                               {"right", "[1.5, 0, -1.5]", "[1.5, 0, 1.5]", "[1.5, 2.25, -1.5]"}};
    for (const char* eye : {"left", "right"})
        for (int i = 0; i < 3; ++i)
            t += "[[screen]]\nname = \"" + std::string(walls[i][0]) + "-" + eye + "\"\nviewport = [" + std::to_string(32 * i) +
                 ", 0, 32, 24]\neye = \"" + eye + "\"\nlower_left = " + walls[i][1] + "\nlower_right = " + walls[i][2] +
                 "\nupper_left = " + walls[i][3] + "\n";
    if (tracked)
        t += "[tracking]\nsource = \"dtrack://127.0.0.1:0\"\nroom_rotate = [-90, 0, 0]\ntimeout_ms = 60000\n";
    return t;
}

RunConfig config(const std::filesystem::path& dir, const std::string& wallText, const char* name) {
    RunConfig c = steppedRunConfig(dir);
    c.scene = test::writeFile(dir / "scene.toml", kScene).string();
    c.wall = test::writeFile(dir / name, wallText);
    c.cluster.async = false;
    return c;
}

// A head at wall position (x, y, z) as the shipped rooms' DTrack sends it (z up, y towards the
// front screen), rolled `roll` degrees about the viewing direction.
void sendHead(WallSession& s, const TrackingConfig& t, Float3 p, double roll, uint64_t frame) {
    DTrackFrame f;
    f.frame = frame;
    DTrackBody b;
    b.quality = 1;
    b.position = {std::round((p.x - t.roomTranslate[0]) * 1e3), std::round(-(p.z - t.roomTranslate[2]) * 1e3),
                  std::round((p.y - t.roomTranslate[1]) * 1e3)};
    const double r = roll * 3.14159265358979 / 180, c = std::cos(r), sn = std::sin(r);
    // About the room's y axis (the viewing direction): x tips up towards z (room up).
    b.rotation = {c, 0, -sn, 0, 1, 0, sn, 0, c};
    f.bodies.push_back(b);
    test::sendToSession(s, f, frame);
}

bool sameBytes(const WallFrame& a, const WallFrame& b) {
    return a.left.width == b.left.width && a.left.rgb == b.left.rgb && a.right.rgb == b.right.rgb && !a.left.rgb.empty() &&
           !a.right.rgb.empty();
}

void checkTrackedEqualsStatic(const std::filesystem::path& dir, std::string (*wall)(const char*, bool), const char* viewer, Float3 at) {
    WallSession fixed(config(dir, wall(viewer, false), "static.toml"));
    ASSERT_TRUE(fixed.step());
    const WallFrame want = fixed.lastFrame();
    EXPECT_FALSE(fixed.tracker().has_value());

    WallSession tracked(config(dir, wall(viewer, true), "tracked.toml"));
    const TrackingConfig t = loadWallConfig(dir / "tracked.toml").tracking;
    ASSERT_GT(tracked.trackerPort(), 0);
    // Before the first datagram: the config's viewer.
    ASSERT_TRUE(tracked.step());
    EXPECT_TRUE(sameBytes(tracked.lastFrame(), want));
    // The head at the viewer: the same bytes, through datagram, parser and room transform.
    sendHead(tracked, t, at, 0, 1);
    ASSERT_TRUE(tracked.step());
    EXPECT_EQ(tracked.lastHead().position.y, at.y);
    EXPECT_TRUE(tracked.tracker()->seen);
    EXPECT_TRUE(sameBytes(tracked.lastFrame(), want)) << "the tracked head at the viewer must render what the static viewer does";
    // Tilted: the eyes move (one up, one down), so the eye images change.
    sendHead(tracked, t, at, 30, 2);
    ASSERT_TRUE(tracked.step());
    EXPECT_NEAR(tracked.lastHead().right.y, 0.5, 1e-6);
    EXPECT_NE(tracked.lastFrame().left.rgb, want.left.rgb);
    EXPECT_NE(tracked.lastFrame().right.rgb, want.right.rgb);
    // Moved 0.4 m to the right: the images follow the head.
    sendHead(tracked, t, {at.x + 0.4f, at.y, at.z}, 0, 3);
    ASSERT_TRUE(tracked.step());
    EXPECT_NEAR(tracked.lastHead().position.x, at.x + 0.4f, 1e-6);
    EXPECT_NE(tracked.lastFrame().left.rgb, want.left.rgb);
    // Back at the viewer: the static bytes again.
    sendHead(tracked, t, at, 0, 4);
    ASSERT_TRUE(tracked.step());
    EXPECT_TRUE(sameBytes(tracked.lastFrame(), want));
}

TEST(TrackedSession, FlatStereoWallTrackedHeadGivesTheStaticRender) {
    const auto dir = test::scratchDir();
    checkTrackedEqualsStatic(dir, flatWall, "[0.0, 0.2, 2.5]", {0.0f, 0.2f, 2.5f});
    checkTrackedEqualsStatic(dir, flatWall, "[-0.7, 0.35, 1.8]", {-0.7f, 0.35f, 1.8f});
}

TEST(TrackedSession, CaveTrackedHeadGivesTheStaticRender) {
    const auto dir = test::scratchDir();
    checkTrackedEqualsStatic(dir, caveWall, "[0.0, 1.7, 0.0]", {0.0f, 1.7f, 0.0f});
    checkTrackedEqualsStatic(dir, caveWall, "[0.4, 1.55, 0.6]", {0.4f, 1.55f, 0.6f});
}

// No head for timeout_ms: the last pose is held (not flown off at its last velocity), the log and
// the overlay line say so, and the wall keeps going; the head's return is said too.
TEST(TrackedSession, ALostHeadIsHeldAndSaid) {
    const auto dir = test::scratchDir();
    std::string wall = flatWall("[0.0, 0.2, 2.5]", true);
    wall.replace(wall.find("timeout_ms = 60000"), 18, "timeout_ms = 100\nprediction_ms = 50");
    RunConfig c = config(dir, wall, "tracked.toml");
    std::vector<std::string> lines;
    c.log = [&](const std::string& line) { lines.push_back(line); };
    WallSession s(c);
    const TrackingConfig t = loadWallConfig(dir / "tracked.toml").tracking;
    sendHead(s, t, {0.0f, 0.2f, 2.5f}, 0, 1);
    sendHead(s, t, {0.1f, 0.2f, 2.5f}, 0, 2);  // moving: the prediction has a velocity
    ASSERT_TRUE(s.step());
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.tracker()->stale);
    EXPECT_EQ(s.lastHead().position.x, 0.1f) << "held where it was last seen";
    const auto said = [&](const std::string& what) {
        return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(what) != std::string::npos; });
    };
    EXPECT_TRUE(said("tracker: no head for")) << "the log says the pose is held";
    EXPECT_TRUE(said("holding the last pose"));
    EXPECT_NE(describeTracker(*s.tracker()).find("holding the last pose"), std::string::npos);
    sendHead(s, t, {-0.2f, 0.2f, 2.5f}, 0, 3);
    ASSERT_TRUE(s.step());
    EXPECT_FALSE(s.tracker()->stale);
    EXPECT_TRUE(said("tracker: the head is back"));
}

// Each CAVE wall is seen through its own frustum: a wall's pixels in the composed image are those
// of a render with that wall's view alone (and the walls differ from one flat projection).
TEST(TrackedSession, CaveWallsAreRenderedEachWithItsOwnView) {
    const auto dir = test::scratchDir();
    WallSession cave(config(dir, caveWall("[0.0, 1.7, 0.0]", false), "cave.toml"));
    ASSERT_TRUE(cave.step());
    const WallFrame& f = cave.lastFrame();
    const WallConfig wall = loadWallConfig(dir / "cave.toml");
    const std::vector<WallView> views = wallViews(wall, staticHead(wall.stereo), 0);
    ASSERT_EQ(views.size(), 3u);
    // The same scene on one machine, one render per view; each wall's columns must match.
    const SceneDesc d = cave.scene();
    const Scene scene(d);
    for (const WallView& v : views) {
        CameraDesc cam = cave.camera();
        const EyeWindow w = eyeWindowInWorld(v.window, wall.stereo.viewer, {cam.position, cam.lookAt, cam.up, cam.fovY});
        cam.position = w.eye;
        cam.window = ProjectionWindow{w.lowerLeft, w.right, w.up};
        const Image ref = renderFrame(scene, Camera(cam, d.settings.width, d.settings.height), d.settings);
        const PixelRect& vp = wall.screens[v.screens[0]].viewport;
        for (int y = 0; y < vp.height; ++y)
            for (int x = vp.x; x < vp.x + vp.width; ++x)
                for (int k = 0; k < 3; ++k) ASSERT_EQ(f.left.pixel(x, y)[k], ref.pixel(x, y)[k]) << x << "," << y;
    }
}


// A click on a CAVE wall picks along that wall's view (the left eye's: a wall's pixels in the
// composed image are its view's), not along the wall's plain camera, which only the front wall
// shares.
TEST(TrackedSession, AClickOnACaveWallPicksThroughThatWallsView) {
    const auto dir = test::scratchDir();
    WallSession cave(config(dir, caveWall("[0.0, 1.7, 0.0]", false), "cave.toml"));
    ASSERT_TRUE(cave.step());
    const WallConfig wall = loadWallConfig(dir / "cave.toml");
    const std::vector<WallView> views = wallViews(wall, staticHead(wall.stereo), 0);
    ASSERT_EQ(views.size(), 3u);
    const Camera plain(cave.camera(), wall.width, wall.height);
    size_t hits = 0, plainApart = 0;
    for (const WallView& v : views) {
        CameraDesc cam = cave.camera();
        const EyeWindow w = eyeWindowInWorld(v.window, wall.stereo.viewer, {cam.position, cam.lookAt, cam.up, cam.fovY});
        cam.position = w.eye;
        cam.window = ProjectionWindow{w.lowerLeft, w.right, w.up};
        const Camera view(cam, wall.width, wall.height);
        const PixelRect& vp = wall.screens[v.screens[0]].viewport;
        for (int y = 1; y < vp.height; y += 4)
            for (int x = vp.x + 1; x < vp.x + vp.width; x += 4) {
                const std::optional<PickResult> r = cave.pick(x + 0.5, y + 0.5);
                if (!r) continue;
                ++hits;
                const Float3 got = normalize(r->point - view.origin()), want = normalize(view.direction(x + 0.5f, y + 0.5f));
                EXPECT_LT(length(got - want), 1e-3f) << x << "," << y;
                plainApart += length(normalize(plain.direction(x + 0.5f, y + 0.5f)) - want) > 0.05f;
            }
    }
    EXPECT_GT(hits, 20u);
    EXPECT_GT(plainApart, hits / 4) << "the plain camera would pick alike: the test shows nothing";
}

// ---- The flystick (issue 18): scripted DTrack datagrams of flystick 0 in the shipped room.

// The flystick at wall position p (metres), pointing at the screen turned `yaw` degrees to the
// left about the vertical, with its buttons and joystick.
void sendWand(WallSession& s, const TrackingConfig& t, Float3 p, double yaw, std::vector<bool> buttons,
              std::vector<double> joystick, uint64_t frame) {
    DTrackFrame f;
    f.frame = frame;
    DTrackFlystick w;
    w.pose.id = 0;
    w.pose.quality = 1;
    w.pose.position = {std::round((p.x - t.roomTranslate[0]) * 1e3), std::round(-(p.z - t.roomTranslate[2]) * 1e3),
                       std::round((p.y - t.roomTranslate[1]) * 1e3)};
    // About the room's z (up): Rz(yaw) times "pointing at the screen" (its -z along the room's y).
    const double r = yaw * 3.14159265358979 / 180, c = std::cos(r), sn = std::sin(r);
    const std::array<double, 9> rz{c, -sn, 0, sn, c, 0, 0, 0, 1}, at{1, 0, 0, 0, 0, -1, 0, 1, 0};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            w.pose.rotation[size_t(3 * i + j)] = rz[size_t(3 * i)] * at[size_t(j)] + rz[size_t(3 * i + 1)] * at[size_t(3 + j)] +
                                                 rz[size_t(3 * i + 2)] * at[size_t(6 + j)];
    w.buttons = std::move(buttons);
    w.controllers = std::move(joystick);
    f.definedFlysticks = 1;
    f.flysticks.push_back(w);
    test::sendToSession(s, f, frame);
}

std::string wandWall() { return flatWall("[0.0, 0.2, 2.5]", true) + "flystick = 0\n"; }

// Where a wall point is in the world for the scene's camera (at (0, 1.7, 0) looking down -z, so
// the wall's axes are the world's) and the config's viewer (0, 0.2, 2.5).
Float3 worldOf(Float3 wall) { return {wall.x, wall.y - 0.2f + 1.7f, wall.z - 2.5f}; }

void expectTransform(const Transform& got, const Transform& want, const char* what) {
    for (size_t i = 0; i < 12; ++i) EXPECT_NEAR(got.m[i], want.m[i], 2e-5) << what << ", element " << i;
}

TEST(WandSession, PickAndDragMovesTheInstanceByExactlyTheWandsMotion) {
    const auto dir = test::scratchDir();
    RunConfig c = config(dir, wandWall(), "wand.toml");
    std::vector<std::string> lines;
    c.log = [&](const std::string& line) { lines.push_back(line); };
    WallSession s(c);
    const TrackingConfig t = loadWallConfig(dir / "wand.toml").tracking;
    ASSERT_EQ(t.flystick, 0);
    const Transform start = s.scene().instances[0].transform;  // the red box, centre (0.3, 0.4, -1.5) in the world
    // The wand level with the box's centre, a metre in front of it, pointing at it; trigger down.
    const Float3 p0{0.3f, 0.4f - 1.7f + 0.2f, -0.5f + 2.5f};
    sendWand(s, t, p0, 0, {true}, {0, 0}, 1);
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.wand());
    ASSERT_TRUE(s.wand()->dragging);
    EXPECT_EQ(*s.wand()->dragging, 0u) << "the red box, not the floor behind it";
    EXPECT_NEAR(s.wand()->origin.x, 0.3f, 1e-6);
    EXPECT_NEAR(s.wand()->origin.y, 0.4f, 1e-6);
    EXPECT_NEAR(s.wand()->direction.z, -1.0f, 1e-6);
    expectTransform(s.scene().instances[0].transform, start, "picked, not yet moved");
    // Moved 0.1 m right and 0.05 m up, still held: the box moves by exactly that.
    const Float3 p1{p0.x + 0.1f, p0.y + 0.05f, p0.z};
    sendWand(s, t, p1, 0, {true}, {0, 0}, 2);
    ASSERT_TRUE(s.step());
    expectTransform(s.scene().instances[0].transform, Transform::translate(0.1, 0.05, 0) * start, "moved with the wand");
    // Turned 30 degrees to the left about the vertical: the box turns with it, about the wand.
    sendWand(s, t, p1, 30, {true}, {0, 0}, 3);
    ASSERT_TRUE(s.step());
    const Float3 w0 = worldOf(p0), w1 = worldOf(p1);
    const Transform motion = Transform::translate(w1.x, w1.y, w1.z) * Transform::rotateDegrees(0, 1, 0, 30) *
                             Transform::translate(-w0.x, -w0.y, -w0.z);
    expectTransform(s.scene().instances[0].transform, motion * start, "turned with the wand");
    EXPECT_EQ(s.scene().instances[1].transform, Transform::scale(8, 8, 8)) << "the floor stays";
    // Released: moving the wand no longer moves the box.
    sendWand(s, t, p0, 0, {false}, {0, 0}, 4);
    ASSERT_TRUE(s.step());
    EXPECT_FALSE(s.wand()->dragging);
    const Transform released = s.scene().instances[0].transform;
    expectTransform(released, motion * start, "released where it was");
    sendWand(s, t, {p0.x - 0.3f, p0.y, p0.z}, 0, {false}, {0, 0}, 5);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().instances[0].transform, released);
    const auto said = [&](const std::string& what) {
        return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(what) != std::string::npos; });
    };
    EXPECT_TRUE(said("wand: picked instance 0"));
    EXPECT_TRUE(said("wand: released instance 0"));
}

// With a section plane selected, the trigger holds the plane instead of an object: its point
// moves and its normal turns with the wand, exactly as a dragged object would (issue 20: planes
// movable by the wand); let go, it stays.
TEST(WandSession, TheTriggerMovesTheSelectedSectionPlane) {
    const auto dir = test::scratchDir();
    WallSession s(config(dir, wandWall(), "wand.toml"));
    const TrackingConfig t = loadWallConfig(dir / "wand.toml").tracking;
    const Transform box = s.scene().instances[0].transform;
    SectionPlane plane;
    plane.enabled = true;
    plane.point = {0.3f, 0.4f, -1.0f};
    plane.normal = {0, 0, -1};
    s.setSection(2, plane);
    ASSERT_EQ(s.activeSection(), 2);
    const Float3 p0{0.3f, 0.4f - 1.7f + 0.2f, -0.5f + 2.5f};
    sendWand(s, t, p0, 0, {true}, {0, 0}, 1);
    ASSERT_TRUE(s.step());
    EXPECT_FALSE(s.wand()->dragging) << "the plane is held, not the box";
    EXPECT_EQ(s.scene().sections[2], plane) << "taken, not yet moved";
    const Float3 p1{p0.x + 0.1f, p0.y + 0.05f, p0.z - 0.2f};
    sendWand(s, t, p1, 30, {true}, {0, 0}, 2);
    ASSERT_TRUE(s.step());
    // motion = T(w1) R_y(30) T(-w0) applied to the point, R_y(30) to the normal.
    const Float3 w0 = worldOf(p0), w1 = worldOf(p1);
    const Transform motion = Transform::translate(w1.x, w1.y, w1.z) * Transform::rotateDegrees(0, 1, 0, 30) *
                             Transform::translate(-w0.x, -w0.y, -w0.z);
    const Float3 q = plane.point;
    const SectionPlane& moved = s.scene().sections[2];
    EXPECT_NEAR(moved.point.x, motion.m[0] * q.x + motion.m[1] * q.y + motion.m[2] * q.z + motion.m[3], 2e-5);
    EXPECT_NEAR(moved.point.y, motion.m[4] * q.x + motion.m[5] * q.y + motion.m[6] * q.z + motion.m[7], 2e-5);
    EXPECT_NEAR(moved.point.z, motion.m[8] * q.x + motion.m[9] * q.y + motion.m[10] * q.z + motion.m[11], 2e-5);
    const double a = 30 * 3.14159265358979 / 180;
    EXPECT_NEAR(moved.normal.x, -std::sin(a), 2e-5);
    EXPECT_NEAR(moved.normal.y, 0, 2e-5);
    EXPECT_NEAR(moved.normal.z, -std::cos(a), 2e-5);
    EXPECT_TRUE(moved.enabled);
    EXPECT_EQ(s.scene().instances[0].transform, box) << "the box stays";
    // Released and moved on: the plane stays where it was let go.
    const SectionPlane released = moved;
    sendWand(s, t, p1, 30, {false}, {0, 0}, 3);
    ASSERT_TRUE(s.step());
    sendWand(s, t, p0, 0, {false}, {0, 0}, 4);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.scene().sections[2], released);
}

// In measure mode the trigger sets the points where the wand's ray hits, and moves nothing.
TEST(WandSession, TheTriggerMeasuresInMeasureMode) {
    const auto dir = test::scratchDir();
    WallSession s(config(dir, wandWall(), "wand.toml"));
    const TrackingConfig t = loadWallConfig(dir / "wand.toml").tracking;
    const Transform start = s.scene().instances[0].transform;
    s.setMeasuring(true);
    // Level with the red box's centre (world (0.3, 0.4, -1.5)), a metre in front: A on its face.
    sendWand(s, t, {0.3f, 0.4f - 1.7f + 0.2f, -0.5f + 2.5f}, 0, {true}, {0, 0}, 1);
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.measurement());
    EXPECT_NEAR(s.measurement()->a[0], 0.3, 1e-5);
    EXPECT_NEAR(s.measurement()->a[1], 0.4, 1e-5);
    const double face = s.measurement()->a[2];
    EXPECT_GT(face, -1.5);
    EXPECT_LT(face, -0.5);
    // Released, moved 0.1 m up and pressed again: B, 0.1 from A on the same face.
    sendWand(s, t, {0.3f, 0.5f - 1.7f + 0.2f, -0.5f + 2.5f}, 0, {false}, {0, 0}, 2);
    ASSERT_TRUE(s.step());
    sendWand(s, t, {0.3f, 0.5f - 1.7f + 0.2f, -0.5f + 2.5f}, 0, {true}, {0, 0}, 3);
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.measurement()->b);
    EXPECT_NEAR(s.measurement()->distance, 0.1, 1e-4);
    EXPECT_NEAR((*s.measurement()->b)[2], face, 1e-5);
    EXPECT_EQ(s.scene().instances[0].transform, start) << "measuring moves nothing";
    EXPECT_FALSE(s.wand()->dragging);
}

TEST(WandSession, JoystickFliesTheCameraAlongTheWandAndHomeReturns) {
    const auto dir = test::scratchDir();
    // Each step moves by the speed times the previous frame's time, the first frame's counted
    // from the session's start: all of it lies after t0.
    const auto t0 = std::chrono::steady_clock::now();
    WallSession s(config(dir, wandWall(), "wand.toml"));
    const TrackingConfig t = loadWallConfig(dir / "wand.toml").tracking;
    const CameraDesc start = s.camera();
    // Pointing 90 degrees to the left (world -x), joystick full forward.
    sendWand(s, t, {0, -0.5f, 1.5f}, 90, {}, {0, 1}, 1);
    for (int i = 0; i < 4; ++i) ASSERT_TRUE(s.step());
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const CameraDesc moved = s.camera();
    const float dx = moved.position.x - start.position.x;
    EXPECT_LT(dx, 0.0f) << "flew to the left, where the wand points";
    EXPECT_LE(-dx, t.flySpeed * elapsed + 1e-4) << "at fly_speed m/s at most";
    EXPECT_NEAR(moved.position.y, start.position.y, 1e-5);
    EXPECT_NEAR(moved.position.z, start.position.z, 1e-4);
    EXPECT_NEAR(moved.lookAt.x - moved.position.x, start.lookAt.x - start.position.x, 1e-4) << "flying does not turn";
    // The joystick at rest inside the dead zone: nothing moves.
    sendWand(s, t, {0, -0.5f, 1.5f}, 90, {}, {0.05, -0.05}, 2);
    ASSERT_TRUE(s.step());
    const CameraDesc still = s.camera();
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.camera().position, still.position);
    // Home (button 2) goes back to the start camera.
    sendWand(s, t, {0, -0.5f, 1.5f}, 90, {false, false, true}, {0, 0}, 3);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(s.camera().position, start.position);
    EXPECT_EQ(s.camera().lookAt, start.lookAt);
    // The mode button: orbit about the scene's centre, whose distance the joystick's x keeps.
    sendWand(s, t, {0, -0.5f, 1.5f}, 90, {false, true}, {0, 0}, 4);
    ASSERT_TRUE(s.step());
    const Bounds3 b = s.scene().worldBounds();
    const Float3 centre{(b.lo.x + b.hi.x) / 2, (b.lo.y + b.hi.y) / 2, (b.lo.z + b.hi.z) / 2};
    auto distance = [&](Float3 p) { return std::hypot(p.x - centre.x, p.y - centre.y, p.z - centre.z); };
    sendWand(s, t, {0, -0.5f, 1.5f}, 90, {false, false}, {1, 0}, 5);
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(s.step());
    // (The camera stands on the centre's vertical, so its position stays; where it looks turns.)
    EXPECT_NE(s.camera().lookAt, start.lookAt) << "turned";
    EXPECT_NEAR(distance(s.camera().lookAt), distance(start.lookAt), 1e-4);
    EXPECT_NEAR(distance(s.camera().position), distance(start.position), 1e-4);
    EXPECT_NEAR(s.camera().position.y, start.position.y, 1e-5) << "about the vertical";
}

TEST(WandSession, TheRayIsDrawnInBothEyesAndOnlyWithAWand) {
    const auto dir = test::scratchDir();
    WallSession s(config(dir, wandWall(), "wand.toml"));
    const TrackingConfig t = loadWallConfig(dir / "wand.toml").tracking;
    auto rayPixels = [](const Image& img) {
        int n = 0;
        for (size_t i = 0; i + 2 < img.rgb.size(); i += 3) n += img.rgb[i] == 255 && img.rgb[i + 1] == 230 && img.rgb[i + 2] == 40;
        return n;
    };
    ASSERT_TRUE(s.step());
    EXPECT_EQ(rayPixels(s.lastFrame().left), 0);
    // Pointing at the screen from below its centre, turned a little: a ray across the wall.
    sendWand(s, t, {0.2f, -0.6f, 1.8f}, 20, {}, {0, 0}, 1);
    ASSERT_TRUE(s.step());
    EXPECT_GT(rayPixels(s.lastFrame().left), 0);
    EXPECT_GT(rayPixels(s.lastFrame().right), 0);
    EXPECT_NE(s.lastFrame().left.rgb, s.lastFrame().right.rgb);
    // wand_ray = false: the wand works, nothing is drawn.
    std::string off = wandWall() + "wand_ray = false\n";
    WallSession quiet(config(dir, off, "quiet.toml"));
    sendWand(quiet, t, {0.2f, -0.6f, 1.8f}, 20, {}, {0, 0}, 1);
    ASSERT_TRUE(quiet.step());
    EXPECT_TRUE(quiet.wand());
    EXPECT_EQ(rayPixels(quiet.lastFrame().left), 0);
}

// ---- Issue 27: every click between two frames counts; the world scale keys.

// A click of `button` between two steps: pressed in one datagram, let go in the next.
void clickWand(WallSession& s, const TrackingConfig& t, Float3 p, int button, uint64_t& frame) {
    std::vector<bool> down(size_t(button) + 1, false);
    down[size_t(button)] = true;
    sendWand(s, t, p, 0, down, {0, 0}, ++frame);
    sendWand(s, t, p, 0, {}, {0, 0}, ++frame);
}

TEST(WandSession, AClickShorterThanAFrameActsAndSeveralActAsMany) {
    const auto dir = test::scratchDir();
    RunConfig c = config(dir, wandWall(), "wand.toml");
    std::vector<std::string> lines;
    c.log = [&](const std::string& line) { lines.push_back(line); };
    WallSession s(c);
    const TrackingConfig t = loadWallConfig(dir / "wand.toml").tracking;
    const Transform start = s.scene().instances[0].transform;
    const auto said = [&](const std::string& what) {
        return int(std::count_if(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(what) != std::string::npos; }));
    };
    // Level with the red box's centre, a metre in front: a click picks it and lets it go.
    const Float3 atBox{0.3f, 0.4f - 1.7f + 0.2f, -0.5f + 2.5f};
    uint64_t frame = 0;
    sendWand(s, t, atBox, 0, {}, {0, 0}, ++frame);
    ASSERT_TRUE(s.step());
    clickWand(s, t, atBox, t.buttonPick, frame);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(said("wand: picked instance 0"), 1);
    EXPECT_EQ(said("wand: released instance 0"), 1);
    EXPECT_FALSE(s.wand()->dragging);
    EXPECT_EQ(s.scene().instances[0].transform, start) << "picked and let go where it was";
    // Measure mode: one click is point A; three more between the next two frames are B, A, B.
    s.setMeasuring(true);
    clickWand(s, t, atBox, t.buttonPick, frame);
    ASSERT_TRUE(s.step());
    ASSERT_TRUE(s.measurement());
    EXPECT_FALSE(s.measurement()->b);
    for (int i = 0; i < 3; ++i) clickWand(s, t, atBox, t.buttonPick, frame);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(said(", Ctrl+click B"), 2) << "two points A";
    EXPECT_EQ(said(" to B "), 2) << "two points B";
    ASSERT_TRUE(s.measurement() && s.measurement()->b);
    s.setMeasuring(false);
    // The mode button twice between two frames: to orbit and back to fly.
    clickWand(s, t, atBox, t.buttonMode, frame);
    clickWand(s, t, atBox, t.buttonMode, frame);
    ASSERT_TRUE(s.step());
    EXPECT_EQ(said("wand: orbit about the scene's centre"), 1);
    EXPECT_EQ(said("wand: fly"), 1);
}

// ] and [ scale the world about the tracked head: the point between the eyes stays where it was
// in the scene, the navigation scale falls or rises by sqrt(2), and the images change.
TEST(WandSession, TheWorldScaleKeysScaleAboutTheHead) {
    const auto dir = test::scratchDir();
    WallSession s(config(dir, flatWall("[0.0, 0.2, 2.5]", true) + "[navigation]\nscale = 2.0\n", "scaled.toml"));
    const WallConfig wall = loadWallConfig(dir / "scaled.toml");
    EXPECT_EQ(s.navigationScale(), 2.0);
    const Float3 head{0.3f, -0.1f, 1.9f};  // off the viewer: scaling about it moves the camera
    sendHead(s, wall.tracking, head, 0, 1);
    ASSERT_TRUE(s.step());
    const WallFrame before = s.lastFrame();
    auto headInScene = [&] {
        const CameraDesc c = s.camera();
        return wallToWorld(wall.stereo.viewer, {c.position, c.lookAt, c.up, c.fovY}, s.navigationScale()).point(head);
    };
    const Float3 h0 = headInScene();
    const CameraDesc c0 = s.camera();
    InputState key;
    key.keysPressed = {GLFW_KEY_RIGHT_BRACKET};
    s.inject(key);
    ASSERT_TRUE(s.step());
    EXPECT_NEAR(s.navigationScale(), 2.0 / std::sqrt(2.0), 1e-12) << "] makes the world larger";
    const Float3 h1 = headInScene();
    EXPECT_NEAR(h1.x, h0.x, 1e-5);
    EXPECT_NEAR(h1.y, h0.y, 1e-5);
    EXPECT_NEAR(h1.z, h0.z, 1e-5);
    EXPECT_GT(length(s.camera().position - c0.position), 0.05f) << "the camera (the viewer's spot) moved towards the head";
    EXPECT_NE(s.lastFrame().left.rgb, before.left.rgb);
    key.keysPressed = {GLFW_KEY_LEFT_BRACKET};
    s.inject(key);
    ASSERT_TRUE(s.step());
    EXPECT_NEAR(s.navigationScale(), 2.0, 1e-12);
    EXPECT_NEAR(length(s.camera().position - c0.position), 0.0f, 1e-5) << "and back";
}

// One scheduler pass for every view (issue 18): with asynchronous rendering the eye images of
// each head pose are those of the synchronous frames, bit for bit, one step later (the frame
// shown was specified a step earlier), for a moving tracked head, on the flat 2x2 stereo wall
// and the three-wall CAVE. (That a view's pixels are a single-PC render of its camera:
// CaveWallsAreRenderedEachWithItsOwnView.)
void checkAsyncEqualsSync(const std::filesystem::path& dir, std::string (*wall)(const char*, bool), const char* viewer,
                          Float3 at, size_t views) {
    // Without re-projection: a frame shows the head it was specified with (re-projecting, every
    // presentation shows the newest head; ReprojectSession tests that).
    RunConfig sc = config(dir, wall(viewer, true), "sync.toml");
    sc.cluster.async = false;
    sc.reproject = false;
    WallSession sync(sc);
    const TrackingConfig t = loadWallConfig(dir / "sync.toml").tracking;
    const std::vector<std::pair<Float3, double>> heads{{at, 0.0}, {{at.x + 0.3f, at.y - 0.1f, at.z + 0.2f}, 20.0}, {at, -35.0}};
    std::vector<WallFrame> want;
    uint64_t packet = 0;
    for (const auto& [p, roll] : heads) {
        sendHead(sync, t, p, roll, ++packet);
        ASSERT_TRUE(sync.step());
        want.push_back(sync.lastFrame());
    }
    for (bool async : {false, true}) {
        SCOPED_TRACE(async ? "async" : "sync");
        RunConfig oc = config(dir, wall(viewer, true), "onepass.toml");
        oc.cluster.async = async;
        oc.reproject = false;
        WallSession one(oc);
        packet = 0;
        for (size_t i = 0; i < heads.size(); ++i) {
            sendHead(one, t, heads[i].first, heads[i].second, ++packet);
            ASSERT_TRUE(one.step());
            if (async) {
                // (The very first frame has nothing in flight before it: it shows its own head.)
                if (i > 0) {
                    EXPECT_EQ(one.shownTrackerPackets(), packet - 1) << "async shows the frame specified a step earlier";
                }
                ASSERT_TRUE(one.step());
            }
            EXPECT_EQ(one.shownTrackerPackets(), packet);
            EXPECT_EQ(one.lastReport().views, views) << "every view in one frame";
            EXPECT_TRUE(sameBytes(one.lastFrame(), want[i])) << "head " << i;
        }
        EXPECT_NE(want[0].left.rgb, want[1].left.rgb) << "the heads must give different images, or the test proves nothing";
    }
}

TEST(TrackedSession, OnePassStereoAsyncEqualsSync) {
    checkAsyncEqualsSync(test::scratchDir(), flatWall, "[0.0, 0.2, 2.5]", {0.0f, 0.2f, 2.5f}, 2);
}

TEST(TrackedSession, OnePassCaveAsyncEqualsSync) {
    checkAsyncEqualsSync(test::scratchDir(), caveWall, "[0.0, 1.7, 0.0]", {0.0f, 1.7f, 0.0f}, 6);
}

// A stochastic scene (GI) on a tracked wall accumulates view by view: still views refine, a head
// move restarts exactly the views whose camera it changed. On a mono wall the one view is at the
// head's centre, so turning the head in place keeps accumulating and moving it restarts; on a
// stereo wall turning the head moves both eyes, so both restart.
TEST(TrackedSession, HeadMovesRestartOnlyTheViewsTheyChange) {
    const auto dir = test::scratchDir();
    std::string scene = kScene;
    scene.replace(scene.find("[render]\n"), 9, "[render]\ngi = true\n");
    for (bool stereo : {false, true}) {
        SCOPED_TRACE(stereo ? "stereo" : "mono");
        std::string wallText = flatWall("[0.0, 0.2, 2.5]", true);
        if (!stereo) wallText.replace(wallText.find("mode = \"passive\""), 16, "mode = \"none\"");
        RunConfig c = config(dir, wallText, "gi.toml");
        c.scene = test::writeFile(dir / "gi-scene.toml", scene).string();
        WallSession s(c);
        const TrackingConfig t = loadWallConfig(dir / "gi.toml").tracking;
        const size_t views = stereo ? 2 : 1;
        sendHead(s, t, {0.0f, 0.2f, 2.5f}, 0, 1);
        ASSERT_TRUE(s.step());
        ASSERT_TRUE(s.lastReport().stochastic);
        const size_t first = s.viewRestarts();
        EXPECT_EQ(first, views);
        const WallFrame one = s.lastFrame();
        for (int i = 0; i < 3; ++i) ASSERT_TRUE(s.step());
        EXPECT_EQ(s.viewRestarts(), first) << "a still head keeps accumulating";
        EXPECT_NE(s.lastFrame().left.rgb, one.left.rgb) << "four frames averaged differ from the first alone";
        sendHead(s, t, {0.0f, 0.2f, 2.5f}, 25, 2);  // turned in place
        ASSERT_TRUE(s.step());
        EXPECT_EQ(s.viewRestarts(), stereo ? first + 2 : first) << "a turn moves the eyes, not the head's centre";
        const size_t turned = s.viewRestarts();
        sendHead(s, t, {0.2f, 0.2f, 2.5f}, 25, 3);  // moved
        ASSERT_TRUE(s.step());
        EXPECT_EQ(s.viewRestarts(), turned + views);
    }
}

}  // namespace
}  // namespace rtwall
