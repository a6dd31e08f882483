// Off-axis stereo: each eye's projection window from the wall's physical corners and the viewer.
#include <rtwall/display.h>

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace rtwall
