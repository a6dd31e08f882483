// Navigation without a window: input states in, poses out.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes

#include "display_test_util.h"

#include <cmath>

namespace rtwall {
namespace {

double distance(Float3 a, Float3 b) {
    return std::sqrt(double(a.x - b.x) * (a.x - b.x) + double(a.y - b.y) * (a.y - b.y) + double(a.z - b.z) * (a.z - b.z));
}

ViewPose start() {
    ViewPose p;
    p.position = {0, 0, 10};
    p.lookAt = {0, 0, 0};
    return p;
}

TEST(Navigator, OrbitKeepsTheDistanceToTheLookAtPoint) {
    Navigator n(start(), 10.0f);
    InputState in;
    in.leftDown = true;
    in.mouseDx = 100;
    in.mouseDy = 40;
    EXPECT_TRUE(n.update(in, 0.016));
    EXPECT_NEAR(distance(n.pose().position, {0, 0, 0}), 10.0, 1e-4);
    EXPECT_GT(std::fabs(n.pose().position.x), 1.0f);  // it moved sideways
    EXPECT_EQ(distance(n.pose().lookAt, {0, 0, 0}), 0.0);
    // Scrolling zooms in towards the look-at point.
    InputState zoom;
    zoom.scroll = 1;
    n.update(zoom, 0.016);
    EXPECT_NEAR(distance(n.pose().position, {0, 0, 0}), 9.0, 1e-4);
}

TEST(Navigator, OrbitNeverFlipsOverThePole) {
    Navigator n(start(), 10.0f);
    InputState in;
    in.leftDown = true;
    in.mouseDy = 100;
    for (int i = 0; i < 50; ++i) n.update(in, 0.016);
    EXPECT_LT(n.pose().position.y / 10.0f, 1.0f);
    EXPECT_GT(n.pose().position.z, 0.0f);  // still on the near side
}

TEST(Navigator, FlyMovesAtTheSceneSpeed) {
    Navigator n(start(), 2.0f);
    n.setMode(Navigator::Mode::Fly);
    InputState in;
    in.keyDown[GLFW_KEY_W] = true;
    EXPECT_TRUE(n.update(in, 0.5));  // 2 units/s for half a second
    EXPECT_NEAR(n.pose().position.z, 9.0f, 1e-5);
    EXPECT_NEAR(n.pose().lookAt.z, -1.0f, 1e-5);
    InputState none;
    EXPECT_FALSE(n.update(none, 0.5));
}

TEST(Navigator, CtrlDigitStoresABookmarkAndTheDigitRecallsIt) {
    Navigator n(start(), 1.0f);
    InputState store;
    store.keysPressed = {GLFW_KEY_3};
    store.modsPressed = {GLFW_MOD_CONTROL};
    n.update(store, 0.0);
    EXPECT_TRUE(n.hasBookmark(3));
    EXPECT_FALSE(n.hasBookmark(4));
    ViewPose elsewhere = start();
    elsewhere.position = {5, 5, 5};
    n.setPose(elsewhere);
    InputState recall;
    recall.keysPressed = {GLFW_KEY_3};
    recall.modsPressed = {0};
    EXPECT_TRUE(n.update(recall, 0.0));
    EXPECT_EQ(n.pose().position.z, 10.0f);
}

TEST(Navigator, RecordsACameraPath) {
    Navigator n(start(), 1.0f);
    InputState r;
    r.keysPressed = {GLFW_KEY_R};
    r.modsPressed = {0};
    n.update(r, 0.0);
    EXPECT_TRUE(n.recording());
    InputState drag;
    drag.leftDown = true;
    drag.mouseDx = 10;
    n.update(drag, 0.016);
    n.update(drag, 0.016);
    n.update(r, 0.0);
    EXPECT_FALSE(n.recording());
    ASSERT_EQ(n.recorded().size(), 3u);
    EXPECT_NE(n.recorded()[1].position.x, n.recorded()[0].position.x) << "the drag between the presses is recorded";
}

TEST(Navigator, ACtrlDragIsPickingNotOrbiting) {
    Navigator n(start(), 1.0f);
    InputState in;
    in.leftDown = true;
    in.clickMods = GLFW_MOD_CONTROL;
    in.mouseDx = 50;
    EXPECT_FALSE(n.update(in, 0.016));
}

}  // namespace
}  // namespace rtwall
