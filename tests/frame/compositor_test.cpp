// The Compositor without a wall: what each eye shows of a frame's views, and when a running
// mean of stochastic frames restarts (the single-PC wall and the display nodes rely on both).
#include <rtwall/frame.h>

#include <gtest/gtest.h>

namespace rtwall {
namespace {

Image flat(int width, int height, uint8_t value) {
    Image i;
    i.width = width;
    i.height = height;
    i.rgb.assign(size_t(width) * size_t(height) * 3, value);
    return i;
}

// The mean the wall shows of these frames (Accumulator, as the compositor promises).
Image meanOf(std::initializer_list<Image> frames) {
    Accumulator a;
    for (const Image& f : frames) a.add(f);
    return a.resolve();
}

FrameView viewAt(float x) {
    FrameView v;
    v.camera.position = {x, 0, 5};
    return v;
}

TEST(Compositor, ADeterministicFrameIsShownAsItIs) {
    Compositor c;
    ComposeFrame f;
    const EyeImages e = c.compose(f, {flat(4, 2, 77)});
    EXPECT_EQ(e.left.rgb, flat(4, 2, 77).rgb);
    EXPECT_TRUE(e.right.rgb.empty());
    EXPECT_EQ(c.accumulatedFrames(), 0);
}

TEST(Compositor, AStochasticMonoFrameRefinesUntilTheStateChanges) {
    Compositor c;
    ComposeFrame f;
    f.stochastic = true;
    f.stateSeq = 3;
    c.compose(f, {flat(4, 2, 10)});
    EXPECT_EQ(c.compose(f, {flat(4, 2, 200)}).left.rgb, meanOf({flat(4, 2, 10), flat(4, 2, 200)}).rgb);
    EXPECT_EQ(c.progressiveRestarts(), 1u);
    f.stateSeq = 4;  // any change of the scene state starts again
    EXPECT_EQ(c.compose(f, {flat(4, 2, 90)}).left.rgb, flat(4, 2, 90).rgb);
    EXPECT_EQ(c.progressiveRestarts(), 2u);
    EXPECT_EQ(c.accumulatedFrames(), 3);
    EXPECT_EQ(c.viewRestarts(), 0u);
}

TEST(Compositor, LinearFramesAreSummedFromTheirLinearBuffers) {
    Compositor c;
    ComposeFrame f;
    f.stochastic = true;
    f.linear = true;
    std::vector<std::vector<float>> linear{std::vector<float>(4 * 2 * 3, 0.25f)};
    Image eightBit = flat(4, 2, 0);  // not what is summed
    const EyeImages e = c.compose(f, {eightBit}, linear);
    Accumulator a;
    a.addLinear(linear[0].data(), 4, 2);
    EXPECT_EQ(e.left.rgb, a.resolve().rgb);
    EXPECT_EQ(c.linearFrames(), 1);
}

// Stereo: each eye's whole-image view is its eye's image; a view restarts only when its own
// camera (or the state) changes, the other eye keeps refining.
TEST(Compositor, EachViewRestartsOnItsOwnCamera) {
    Compositor c;
    ComposeFrame f;
    f.views = {viewAt(-0.03f), viewAt(0.03f)};
    f.eyes = {0, 1};
    f.stochastic = true;
    EyeImages e = c.compose(f, {flat(2, 2, 20), flat(2, 2, 40)});
    EXPECT_EQ(e.left.rgb, flat(2, 2, 20).rgb);
    EXPECT_EQ(e.right.rgb, flat(2, 2, 40).rgb);
    EXPECT_EQ(c.viewRestarts(), 2u);
    f.views[1] = viewAt(0.05f);  // the head moved the right eye only
    e = c.compose(f, {flat(2, 2, 220), flat(2, 2, 100)});
    EXPECT_EQ(e.left.rgb, meanOf({flat(2, 2, 20), flat(2, 2, 220)}).rgb);
    EXPECT_EQ(e.right.rgb, flat(2, 2, 100).rgb);
    EXPECT_EQ(c.viewRestarts(), 3u);
    f.stateSeq = 1;  // a state change restarts both
    c.compose(f, {flat(2, 2, 1), flat(2, 2, 2)});
    EXPECT_EQ(c.viewRestarts(), 5u);
}

// A CAVE: two planes of one eye, each giving its screens' pixels (regions in wall pixels, scaled
// to a frame of half the wall's size); pixels no plane shows stay black.
TEST(Compositor, PlanesGiveTheirRegionsOfTheirEye) {
    Compositor c;
    ComposeFrame f;
    f.views = {viewAt(0), viewAt(1)};
    f.views[0].regions = {{0, 0, 8, 8}};
    f.views[1].regions = {{8, 0, 4, 8}};
    for (FrameView& v : f.views) {
        v.refWidth = 16;
        v.refHeight = 8;
    }
    f.eyes = {-1, -1};
    const EyeImages e = c.compose(f, {flat(8, 4, 50), flat(8, 4, 60)});
    ASSERT_EQ(e.left.width, 8);
    EXPECT_TRUE(e.right.rgb.empty());
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) EXPECT_EQ(e.left.pixel(x, y)[0], x < 4 ? 50 : x < 6 ? 60 : 0) << x << "," << y;
}

// Deterministic frames never touch a view's running mean: it goes on when the scene is
// stochastic again in the same state and camera.
TEST(Compositor, DeterministicFramesLeaveTheViewSumsAlone) {
    Compositor c;
    ComposeFrame f;
    f.views = {viewAt(0)};
    f.eyes = {-1};
    f.stochastic = true;
    c.compose(f, {flat(2, 2, 30)});
    f.stochastic = false;
    EXPECT_EQ(c.compose(f, {flat(2, 2, 255)}).left.rgb, flat(2, 2, 255).rgb);
    f.stochastic = true;
    EXPECT_EQ(c.compose(f, {flat(2, 2, 90)}).left.rgb, meanOf({flat(2, 2, 30), flat(2, 2, 90)}).rgb);
    EXPECT_EQ(c.viewRestarts(), 1u);
}

}  // namespace
}  // namespace rtwall
