// Off-axis stereo: each eye's projection window from the wall's physical corners and the viewer.
#include <rtwall/display.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <string>

namespace rtwall {
namespace {

void expectNear(Float3 a, Float3 b, float tol, const char* what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}

StereoConfig wall32x24() {  // configs/wall/stereo-passive.toml
    StereoConfig s;
    s.mode = StereoMode::Passive;
    s.eyeSeparation = 0.065;
    s.viewer = {0, 0, 2.5f};
    s.lowerLeft = {-1.6f, -1.2f, 0};
    s.lowerRight = {1.6f, -1.2f, 0};
    s.upperLeft = {-1.6f, 1.2f, 0};
    return s;
}

TEST(OffAxis, WallWindowIsThePhysicalRectangle) {
    const EyeWindow w = wallEyeWindow(wall32x24(), -1);
    expectNear(w.eye, {0, 0, 2.5f}, 0, "mono eye is the head");
    expectNear(w.lowerLeft, {-1.6f, -1.2f, 0}, 0, "lower left");
    expectNear(w.right, {3.2f, 0, 0}, 1e-6f, "right edge");
    expectNear(w.up, {0, 2.4f, 0}, 1e-6f, "up edge");
}

TEST(OffAxis, EyesDifferByTheSeparation) {
    const StereoConfig s = wall32x24();
    const EyeWindow l = wallEyeWindow(s, 0), r = wallEyeWindow(s, 1);
    expectNear(l.eye, {-0.0325f, 0, 2.5f}, 1e-7f, "left eye");
    expectNear(r.eye, {0.0325f, 0, 2.5f}, 1e-7f, "right eye");
    // Both see the same wall rectangle: only the eye moves.
    expectNear(l.lowerLeft, r.lowerLeft, 0, "same wall");
    expectNear(l.right, r.right, 0, "same wall");
    // Along a tilted wall the eyes still sit along the wall's right edge, the separation apart.
    StereoConfig t = s;
    t.lowerRight = {1.6f, -1.2f, -1.0f};
    const EyeWindow tl = wallEyeWindow(t, 0), tr = wallEyeWindow(t, 1);
    const Float3 d{tr.eye.x - tl.eye.x, tr.eye.y - tl.eye.y, tr.eye.z - tl.eye.z};
    EXPECT_NEAR(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z), 0.065f, 1e-6f);
    EXPECT_NEAR(d.x / d.z, 3.2f / -1.0f, 1e-4f);
    // And through a navigation pose the world-space eyes are still the separation apart, along
    // the camera's right vector.
    ViewPose pose;
    pose.position = {10, 1, -3};
    pose.lookAt = {10, 1, -13};  // looking down -z: right = +x
    const EyeWindow wl = eyeWindowInWorld(l, s.viewer, pose), wr = eyeWindowInWorld(r, s.viewer, pose);
    expectNear(wl.eye, {10 - 0.0325f, 1, -3}, 1e-6f, "world left eye");
    expectNear(wr.eye, {10 + 0.0325f, 1, -3}, 1e-6f, "world right eye");
}

TEST(OffAxis, OffCentreViewerGivesHandComputedAsymmetricFrustum) {
    // The head 1 m right of and 0.6 m above the centre, 2.5 m from the wall: measured from the
    // eye's foot on the wall, the wall spans x in [-2.6, 0.6] and y in [-1.8, 0.6]; at distance 1
    // (Kooima's l, r, b, t over n) that is [-1.04, 0.24] x [-0.72, 0.24].
    StereoConfig s = wall32x24();
    s.viewer = {1.0f, 0.6f, 2.5f};
    const EyeWindow w = wallEyeWindow(s, -1);
    const float n = w.eye.z - w.lowerLeft.z;
    EXPECT_FLOAT_EQ(n, 2.5f);
    EXPECT_NEAR((w.lowerLeft.x - w.eye.x) / n, -1.04f, 1e-6f);
    EXPECT_NEAR((w.lowerLeft.x + w.right.x - w.eye.x) / n, 0.24f, 1e-6f);
    EXPECT_NEAR((w.lowerLeft.y - w.eye.y) / n, -0.72f, 1e-6f);
    EXPECT_NEAR((w.lowerLeft.y + w.up.y - w.eye.y) / n, 0.24f, 1e-6f);
    // Into the world: the viewer is the camera position, wall axes become right/up/back.
    ViewPose pose;
    pose.position = {0, 0, 0};
    pose.lookAt = {1, 0, 0};  // looking down +x: right = +z, up = +y, back = -x
    const EyeWindow g = eyeWindowInWorld(w, s.viewer, pose);
    expectNear(g.eye, {0, 0, 0}, 1e-6f, "head at the camera");
    // Wall lower-left relative to the head: (-2.6, -1.8, -2.5) -> -2.6 right, -1.8 up, 2.5 forward.
    expectNear(g.lowerLeft, {2.5f, -1.8f, -2.6f}, 1e-5f, "lower left in the world");
    expectNear(g.right, {0, 0, 3.2f}, 1e-6f, "right edge along camera right");
    expectNear(g.up, {0, 2.4f, 0}, 1e-6f, "up edge along camera up");
}

TEST(OffAxis, TheStaticHeadIsTheConfigsViewerAndAxisAlignedWallsGiveExactAxes) {
    const StereoConfig s = wall32x24();
    const HeadPose h = staticHead(s);
    EXPECT_EQ(h.position.z, 2.5f);
    // 3.2 / 3.2: exactly 1, so a tracked head looking straight at the wall agrees to the bit.
    EXPECT_EQ(h.right.x, 1.0f);
    EXPECT_EQ(h.right.y, 0.0f);
    EXPECT_EQ(h.up.y, 1.0f);
    for (int eye : {0, 1, -1}) {
        const EyeWindow a = wallEyeWindow(s, eye), b = wallEyeWindow(s, h, eye);
        EXPECT_EQ(a.eye.x, b.eye.x);
        EXPECT_EQ(a.eye.y, b.eye.y);
    }
}

TEST(OffAxis, ATiltedHeadMovesTheEyes) {
    const StereoConfig s = wall32x24();
    HeadPose level = staticHead(s);
    HeadPose tilted = level;
    const float c = std::cos(0.5236f), sn = std::sin(0.5236f);  // rolled 30 degrees to the left
    tilted.right = {c, sn, 0};
    const Float3 l = eyePosition(tilted, 0.065, 0), r = eyePosition(tilted, 0.065, 1);
    expectNear(l, {-0.0325f * c, -0.0325f * sn, 2.5f}, 1e-7f, "left eye lower");
    expectNear(r, {0.0325f * c, 0.0325f * sn, 2.5f}, 1e-7f, "right eye higher");
    EXPECT_NE(r.y, eyePosition(level, 0.065, 1).y);
    // Turned 90 degrees (looking along the wall): the eyes lie one behind the other.
    HeadPose turned = level;
    turned.right = {0, 0, 1};
    expectNear(eyePosition(turned, 0.065, 1), {0, 0, 2.5325f}, 1e-6f, "right eye nearer the viewer's back");
    // The centre of the head for mono walls.
    expectNear(eyePosition(tilted, 0.065, -1), {0, 0, 2.5f}, 0, "mono");
    // The windows follow: same wall, the tilted eye.
    expectNear(wallEyeWindow(s, tilted, 1).eye, r, 0, "window eye");
}

// Where a window puts wall pixel (x, y) (image y down) of a W x H image.
Float3 pixelPoint(const EyeWindow& w, double x, double y, int W, int H) {
    const float u = float(x / W), v = float(1.0 - y / H);
    return {w.lowerLeft.x + w.right.x * u + w.up.x * v, w.lowerLeft.y + w.right.y * u + w.up.y * v,
            w.lowerLeft.z + w.right.z * u + w.up.z * v};
}

TEST(OffAxis, EveryCaveWallGetsItsOwnViewLandingOnItsCorners) {
    const WallConfig cave = loadWallConfig(std::filesystem::path(RTWALL_SOURCE_DIR) / "configs/wall/cave-3.toml");
    ASSERT_EQ(cave.screens.size(), 6u);
    EXPECT_TRUE(wallHasViews(cave));
    HeadPose head = staticHead(cave.stereo);
    head.position = {0.3f, 1.6f, 0.4f};
    for (int eye : {0, 1}) {
        const std::vector<WallView> views = wallViews(cave, head, eye);
        ASSERT_EQ(views.size(), 3u) << "three walls, three planes";
        for (const WallView& v : views) {
            ASSERT_EQ(v.screens.size(), 1u);
            const ScreenConfig& s = cave.screens[v.screens[0]];
            EXPECT_EQ(s.eye, eye == 0 ? Eye::Left : Eye::Right);
            expectNear(v.window.eye, eyePosition(head, 0.065, eye), 0, "the eye");
            // The screen's viewport corners land on its physical corners.
            const PixelRect& p = s.viewport;
            expectNear(pixelPoint(v.window, p.x, p.y + p.height, cave.width, cave.height), s.lowerLeft, 1e-5f, "lower left");
            expectNear(pixelPoint(v.window, p.x + p.width, p.y + p.height, cave.width, cave.height), s.lowerRight, 1e-5f, "lower right");
            expectNear(pixelPoint(v.window, p.x, p.y, cave.width, cave.height), s.upperLeft, 1e-5f, "upper left");
        }
    }
    // A flat wall given per screen by corners that line up is one view: the whole rectangle.
    std::string flat = "[wall]\nwidth = 200\nheight = 100\n[stereo]\nlower_left = [-2, -1, 0]\nlower_right = [2, -1, 0]\n"
                       "upper_left = [-2, 1, 0]\n";
    for (int i = 0; i < 2; ++i) {
        const float x0 = -2.0f + 2.0f * float(i);
        flat += "[[screen]]\nname = \"s" + std::to_string(i) + "\"\nviewport = [" + std::to_string(100 * i) + ", 0, 100, 100]\n" +
                "lower_left = [" + std::to_string(x0) + ", -1, 0]\nlower_right = [" + std::to_string(x0 + 2) + ", -1, 0]\n" +
                "upper_left = [" + std::to_string(x0) + ", 1, 0]\n";
    }
    const WallConfig w = parseWallConfig(flat, "flat.toml");
    const std::vector<WallView> one = wallViews(w, staticHead(w.stereo), -1);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0].screens.size(), 2u);
    expectNear(one[0].window.lowerLeft, {-2, -1, 0}, 1e-6f, "lower left");
    expectNear(one[0].window.right, {4, 0, 0}, 1e-6f, "right");
    expectNear(one[0].window.up, {0, 2, 0}, 1e-6f, "up");
    // Without screen corners: [stereo]'s rectangle, one view, every screen of the eye.
    const WallConfig passive = loadWallConfig(std::filesystem::path(RTWALL_SOURCE_DIR) / "configs/wall/stereo-passive.toml");
    const std::vector<WallView> pv = wallViews(passive, staticHead(passive.stereo), 1);
    ASSERT_EQ(pv.size(), 1u);
    EXPECT_EQ(pv[0].screens, std::vector<size_t>{1});
    EXPECT_FALSE(wallHasViews(loadWallConfig(std::filesystem::path(RTWALL_SOURCE_DIR) / "configs/wall/projectors-2x2.toml")));
}

// Where the ray from the window's eye to the world point q meets the window: (u, v) in [0, 1]
// across it, in double.
std::array<double, 2> projected(const EyeWindow& w, Float3 q) {
    auto d = [](Float3 a) { return std::array<double, 3>{a.x, a.y, a.z}; };
    const auto e = d(w.eye), ll = d(w.lowerLeft), r = d(w.right), u = d(w.up), p = d(q);
    const std::array<double, 3> n{r[1] * u[2] - r[2] * u[1], r[2] * u[0] - r[0] * u[2], r[0] * u[1] - r[1] * u[0]};
    auto dot = [](const std::array<double, 3>& a, const std::array<double, 3>& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    const std::array<double, 3> toWall{ll[0] - e[0], ll[1] - e[1], ll[2] - e[2]}, toPoint{p[0] - e[0], p[1] - e[1], p[2] - e[2]};
    const double t = dot(n, toWall) / dot(n, toPoint);
    const std::array<double, 3> hit{e[0] + t * toPoint[0] - ll[0], e[1] + t * toPoint[1] - ll[1], e[2] + t * toPoint[2] - ll[2]};
    return {dot(hit, r) / dot(r, r), dot(hit, u) / dot(u, u)};
}

// Issue 27: at s scene units per metre a tracked head sees what it sees at scale 1 in the scene
// made 1/s as large (about the camera, where the room's viewer stands): the room is only scaled.
TEST(OffAxis, TheNavigationScaleShowsTheSceneAsIfScaledByItsInverse) {
    const StereoConfig s = wall32x24();
    HeadPose head;
    head.position = {0.3f, 0.1f, 1.8f};  // off the viewer
    ViewPose pose;
    pose.position = {4, 1.5f, -2};
    pose.lookAt = {-2, 1.0f, -10};  // turned and tipped: the room's axes are not the world's
    const std::vector<Float3> scene = {{0, 1, -12}, {3, -2, -7}, {-5, 4, -30}, {4.2f, 1.6f, -2.5f}};
    for (double scale : {0.25, 2.0, 40.0})
        for (int eye : {0, 1}) {
            const EyeWindow room = wallEyeWindow(s, head, eye);
            const EyeWindow scaled = eyeWindowInWorld(room, s.viewer, pose, scale), unit = eyeWindowInWorld(room, s.viewer, pose);
            for (const Float3& q : scene) {
                const Float3 c = pose.position, shrunk{c.x + float((q.x - c.x) / scale), c.y + float((q.y - c.y) / scale),
                                                       c.z + float((q.z - c.z) / scale)};
                const std::array<double, 2> a = projected(scaled, q), b = projected(unit, shrunk);
                EXPECT_NEAR(a[0], b[0], 2e-5) << "scale " << scale << ", eye " << eye;
                EXPECT_NEAR(a[1], b[1], 2e-5) << "scale " << scale << ", eye " << eye;
            }
            // The eyes are the separation times the scale apart in the scene.
            const EyeWindow other = eyeWindowInWorld(wallEyeWindow(s, head, 1 - eye), s.viewer, pose, scale);
            EXPECT_NEAR(length(other.eye - scaled.eye), 0.065 * scale, 1e-5 * scale);
        }
    // Scale 1 is the rigid map, float for float (the default scale changes no image).
    const WallToWorld m = wallToWorld(s.viewer, pose, 1.0);
    const EyeWindow room = wallEyeWindow(s, head, 0), unit = eyeWindowInWorld(room, s.viewer, pose, 1.0);
    const Float3 eye = m.origin + m.direction(room.eye - s.viewer);
    EXPECT_TRUE(unit.eye.x == eye.x && unit.eye.y == eye.y && unit.eye.z == eye.z);
    const Float3 right = m.direction(room.right);
    EXPECT_TRUE(unit.right.x == right.x && unit.right.y == right.y && unit.right.z == right.z);
}

// Rescaling about the head keeps the point between the eyes where it is in the scene and moves
// every other point of the room towards or away from it; the view does not turn.
TEST(OffAxis, RescalingAboutTheHeadKeepsItsScenePoint) {
    const StereoConfig s = wall32x24();
    const Float3 head{0.4f, -0.3f, 1.6f};
    ViewPose pose;
    pose.position = {100, 2, -50};
    pose.lookAt = {97, 2.5f, -54};
    for (const auto& [from, to] : {std::pair{1.0, 2.0}, std::pair{2.0, 0.5}, std::pair{1.0, 1000.0}}) {
        const ViewPose p = rescaledPose(pose, s.viewer, from, to, head);
        const Float3 before = wallToWorld(s.viewer, pose, from).point(head), after = wallToWorld(s.viewer, p, to).point(head);
        EXPECT_NEAR(after.x, before.x, 1e-4 * std::max(1.0, to)) << from << " -> " << to;
        EXPECT_NEAR(after.y, before.y, 1e-4 * std::max(1.0, to));
        EXPECT_NEAR(after.z, before.z, 1e-4 * std::max(1.0, to));
        const Float3 look = p.lookAt - p.position, was = pose.lookAt - pose.position;
        EXPECT_NEAR(look.x, was.x, 1e-4);
        EXPECT_NEAR(look.z, was.z, 1e-4);
        // A point a metre to the head's right is now `to` scene units from it, not `from`.
        const Float3 side = wallToWorld(s.viewer, p, to).point({head.x + 1, head.y, head.z});
        EXPECT_NEAR(length(side - after), to, 1e-4 * std::max(1.0, to));
    }
    // At the viewer (an untracked wall) the camera stays where it is.
    const ViewPose still = rescaledPose(pose, s.viewer, 1.0, 3.0, s.viewer);
    EXPECT_EQ(still.position, pose.position);
    EXPECT_EQ(still.lookAt, pose.lookAt);
}

}  // namespace
}  // namespace rtwall
