// CPU re-projection (rtwall/reproject.h) against true renders of the engine: a view warped to
// its own pose is the view bit for bit (symmetric and off-axis wall cameras); a checkered wall
// warped to a moved pose matches the true render there; the holes behind a box that the camera
// moved past are exactly the disoccluded region, and an older view fills them with the true
// pixels; depth that is not a depth is a hole and never a crash.
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/reproject.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>

namespace rtwall {
namespace {

constexpr int kW = 160, kH = 120;
// A symmetric camera whose focal length is 100 pixels at kH = 120 (tan(fovY / 2) = 0.6): a
// camera moved by b sideways moves a point at distance z by 100 b / z pixels.
const float kFovY = float(2.0 * std::atan(0.6) * 180.0 / std::numbers::pi);

// A checkered Lambert wall (20 x 20 units) at z = 0 facing +z and, optionally, a red box of half
// size 1 whose front face is at z = 5, lit by a sun from behind the viewer: every colour is the
// same from every pose (no mirror, no highlight), so a warped pixel can be compared with a
// true render byte for byte.
SceneDesc wallAndBox(bool box) {
    SceneDesc d;
    test::addQuadAndBox(d);
    Material wall = test::material("wall", MaterialType::Lambert, {0.9f, 0.9f, 0.9f});
    wall.texture.kind = TextureKind::Checker;
    wall.texture.color2 = {0.1f, 0.3f, 0.6f};
    wall.texture.scale = 1.0f;
    d.materials = {wall, test::material("box", MaterialType::Lambert, {0.8f, 0.1f, 0.1f})};
    d.instances.push_back({0, 0, Transform::rotateDegrees(1, 0, 0, 90) * Transform::scale(10, 1, 10)});
    if (box) d.instances.push_back({1, 1, Transform::translate(0, 0, 4)});
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0.3f, -0.4f, -1.0f};
    d.lights = {sun};
    d.settings.ambient = {0.1f, 0.1f, 0.1f};
    test::setImage(d.settings, kW, kH, 32);
    d.settings.threads = 2;
    return d;
}

CameraDesc eyeAt(float x, float y, float z) { return test::cameraAt({x, y, z}, {x, y, 0}, kFovY); }

RenderedFrame render(const SceneDesc& d, const CameraDesc& camera) {
    const Scene scene(d);
    return renderFrameWithDepth(scene, Camera(camera, d.settings.width, d.settings.height), d.settings);
}

size_t count(const WarpedView& v, WarpPixel kind) { return size_t(std::count(v.mask.begin(), v.mask.end(), kind)); }

// Through the general warp (no copy of a same pose) and through the copy: the rendered bytes.
void expectOwnPoseGivesTheView(const SceneDesc& d, const CameraDesc& camera) {
    const RenderedFrame f = render(d, camera);
    Reprojector warper;
    WarpOptions warpAnyway;
    warpAnyway.copySamePose = false;
    const WarpedView& warped = warper.warp({f.image, f.depth, camera}, camera, nullptr, warpAnyway);
    EXPECT_EQ(warped.image.rgb, f.image.rgb);
    EXPECT_EQ(warped.holes, 0u);
    EXPECT_EQ(count(warped, WarpPixel::Warped), f.depth.size());
    const WarpedView& copied = warper.warp({f.image, f.depth, camera}, camera);
    EXPECT_EQ(copied.image.rgb, f.image.rgb);
    EXPECT_EQ(count(copied, WarpPixel::Fresh), f.depth.size());
}

TEST(FrameReproject, OwnPoseGivesTheViewBitForBit) {
    expectOwnPoseGivesTheView(wallAndBox(true), eyeAt(0.3f, -0.2f, 10));
    // A real scene with background, glass, a volume and alpha masks.
    SceneDesc zoo = test::materialZoo(test::scratchDir(), kW, kH);
    expectOwnPoseGivesTheView(zoo, zoo.cameras.front());
}

// A wall's eye camera: an off-axis frustum through the screen's corners from an eye off the
// screen's centre line (as wallViews makes them), looking at the wall and the box obliquely.
TEST(FrameReproject, OwnPoseOnAnOffAxisWallFrustumGivesTheViewBitForBit) {
    CameraDesc eye;
    eye.position = {1.3f, 0.6f, 9.0f};
    eye.window = ProjectionWindow{{-2.0f, -1.5f, 6.5f}, {4.0f, 0, 0}, {0, 3.0f, 0}};
    expectOwnPoseGivesTheView(wallAndBox(true), eye);
}

// The wall alone, viewed from a pose 0.3 right, 0.2 up and 0.5 closer, turned a little: the
// warp puts each pixel within half a pixel of where the true render has it, so every warped or
// crack-filled pixel shows a colour the true render shows within one pixel of it (to 2 levels),
// its depth is the true depth within 1%, and nothing is a hole (the new view sees less).
TEST(FrameReproject, AWallWarpedToANewPoseMatchesItsTrueRender) {
    const SceneDesc d = wallAndBox(false);
    const CameraDesc from = eyeAt(0, 0, 10);
    const CameraDesc to = test::cameraAt({0.3f, 0.2f, 9.5f}, {0.25f, 0.15f, 0}, kFovY);
    const RenderedFrame a = render(d, from), truth = render(d, to);
    Reprojector warper;
    const WarpedView& v = warper.warp({a.image, a.depth, from}, to);
    EXPECT_EQ(v.holes, 0u);
    size_t far = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t i = size_t(y) * kW + size_t(x);
            EXPECT_NEAR(v.depth[i], truth.depth[i], 0.01f * truth.depth[i]) << x << "," << y;
            int best = 256;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = std::clamp(x + dx, 0, kW - 1), ny = std::clamp(y + dy, 0, kH - 1);
                    int worst = 0;
                    for (int c = 0; c < 3; ++c)
                        worst = std::max(worst, std::abs(int(v.image.rgb[i * 3 + size_t(c)]) -
                                                         int(truth.image.rgb[(size_t(ny) * kW + size_t(nx)) * 3 + size_t(c)])));
                    best = std::min(best, worst);
                }
            far += best > 2;
        }
    EXPECT_EQ(far, 0u) << "pixels whose colour the true render has nowhere within one pixel";
}

// The box in front of the wall, the camera 0.4 to the right: the wall moves 4 pixels, the box's
// front 8. The pixels the warp leaves open are exactly those whose wall point was behind the
// box in the old view or outside it (computed from the true renders, not from the warp); the
// others show the true render's bytes. An older view from 0.8 right saw that region: it fills
// it with the true pixels.
TEST(FrameReproject, HolesAreExactlyTheDisoccludedRegion) {
    const SceneDesc d = wallAndBox(true);
    const CameraDesc a = eyeAt(0, 0, 10), b = eyeAt(0.4f, 0, 10), c = eyeAt(0.8f, 0, 10);
    const RenderedFrame fa = render(d, a), fb = render(d, b), fc = render(d, c);
    const Camera camB(b, kW, kH);
    auto isBox = [&](const RenderedFrame& f, const Camera& cam, int x, int y) {
        const Float3 dir = cam.direction(float(x) + 0.5f, float(y) + 0.5f);
        return f.depth[size_t(y) * kW + size_t(x)] * std::fabs(dir.z) / length(dir) < 7.5f;  // eye-space z
    };
    std::vector<uint8_t> expected(size_t(kW) * kH, 0);
    size_t expectedHoles = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const bool box = isBox(fb, camB, x, y);
            const int from = x + (box ? 8 : 4);  // where fa saw this point
            const bool hole = from >= kW || (!box && isBox(fa, camB, from, y));
            expected[size_t(y) * kW + size_t(x)] = hole;
            expectedHoles += hole;
        }
    ASSERT_GT(expectedHoles, 4u * kH) << "the box should uncover some wall, besides the image's edge";

    Reprojector warper;
    const WarpedView& v = warper.warp({fa.image, fa.depth, a}, b);
    EXPECT_EQ(v.holes, expectedHoles);
    for (size_t i = 0; i < expected.size(); ++i) {
        EXPECT_EQ(v.mask[i], expected[i] ? WarpPixel::Filled : WarpPixel::Warped) << i % kW << "," << i / kW;
        if (!expected[i]) {
            for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(v.image.rgb[i * 3 + size_t(ch)], fb.image.rgb[i * 3 + size_t(ch)]) << i;
        }
    }
    // The older view saw the uncovered wall (not the image's right edge: it looked further right).
    const WarpSource older{fc.image, fc.depth, c};
    const WarpedView& filled = warper.warp({fa.image, fa.depth, a}, b, &older);
    EXPECT_EQ(filled.holes, expectedHoles);
    EXPECT_EQ(count(filled, WarpPixel::Older), expectedHoles);
    EXPECT_EQ(filled.image.rgb, fb.image.rgb);
}

// Where the newest view has no depth (NaN, infinities, zero, negative) its pixels are not moved:
// they are holes, filled from the row; a row without any depth takes the nearest row's pixels,
// an image without any the background colour; a depth buffer of the wrong size is refused.
TEST(FrameReproject, DepthThatIsNoDepthIsAHoleAndNeverACrash) {
    const SceneDesc d = wallAndBox(true);
    const CameraDesc a = eyeAt(0, 0, 10);
    const RenderedFrame f = render(d, a);
    std::vector<float> depth = f.depth;
    const float bad[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                         -std::numeric_limits<float>::infinity(), 0.0f, -2.0f};
    for (size_t i = 0; i < depth.size(); i += 7) depth[i] = bad[(i / 7) % 5];
    for (int x = 0; x < kW; ++x) depth[size_t(50) * kW + size_t(x)] = std::nanf("");  // a whole row
    const size_t broken = size_t(std::count_if(depth.begin(), depth.end(), [](float v) { return !(v > 0 && v < INFINITY); }));
    Reprojector warper;
    WarpOptions options;
    options.copySamePose = false;
    options.crackRatio = 0;  // no crack filling: every broken pixel stays a hole
    options.background[0] = 7;
    const WarpedView& v = warper.warp({f.image, depth, a}, a, nullptr, options);
    EXPECT_EQ(v.holes, broken);
    for (size_t i = 0; i < depth.size(); ++i) {
        const bool ok = depth[i] > 0 && depth[i] < INFINITY;
        EXPECT_EQ(v.mask[i], ok ? WarpPixel::Warped : WarpPixel::Filled) << i;
    }
    // The row without any depth takes the nearest row that has some (49 and 51 are as near: the
    // one above), as the row fill left it; the background colour only where no row has any.
    EXPECT_TRUE(std::equal(v.image.rgb.begin() + ptrdiff_t(size_t(50) * kW * 3), v.image.rgb.begin() + ptrdiff_t(size_t(51) * kW * 3),
                           v.image.rgb.begin() + ptrdiff_t(size_t(49) * kW * 3)));
    EXPECT_NE(v.image.rgb[size_t(50) * kW * 3], 7);
    std::vector<float> none(depth.size(), std::nanf(""));
    const WarpedView& empty = warper.warp({f.image, none, a}, a, nullptr, options);
    for (size_t i = 0; i < empty.mask.size(); ++i)
        ASSERT_TRUE(empty.image.rgb[i * 3] == 7 && empty.image.rgb[i * 3 + 1] == 0 && empty.image.rgb[i * 3 + 2] == 0)
            << i << ": nothing to fill from: the background";
    for (const CameraDesc& to : {eyeAt(0.5f, 0.3f, 9), eyeAt(0, 0, -10), test::cameraAt({0, 0, 10}, {0, 0, 20}, kFovY)})
        EXPECT_NO_THROW(warper.warp({f.image, depth, a}, to));
    std::vector<float> short_(f.depth.begin(), f.depth.end() - 1);
    EXPECT_THROW(warper.warp({f.image, short_, a}, a), std::invalid_argument);
}

// Stepping back with a wider view, the new pose sees rows above and below what the view saw:
// each such row (no pixel from the view) takes the nearest row that has some, as that row was
// filled, never the background colour (until issue 27's follow-up they were the background:
// black edges that the guard bands in docs/latency.md had to hide).
TEST(FrameReproject, ARowNoViewCoveredTakesTheNearestRow) {
    const SceneDesc d = wallAndBox(true);
    const CameraDesc a = eyeAt(0, 0, 10);
    const CameraDesc wide = test::cameraAt({0, 0, 12}, {0, 0, 0}, kFovY * 1.3f);
    const RenderedFrame f = render(d, a);
    Reprojector warper;
    WarpOptions options;
    options.background[1] = 255;  // a green no render has
    const WarpedView& v = warper.warp({f.image, f.depth, a}, wide, nullptr, options);
    std::vector<bool> known(kH, false);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) known[size_t(y)] = known[size_t(y)] || v.mask[size_t(y) * kW + size_t(x)] != WarpPixel::Filled;
    int empty = 0;
    for (int y = 0; y < kH; ++y) {
        if (known[size_t(y)]) continue;
        ++empty;
        int above = y - 1, below = y + 1;
        while (above >= 0 && !known[size_t(above)]) --above;
        while (below < kH && !known[size_t(below)]) ++below;
        const int from = below >= kH || (above >= 0 && y - above <= below - y) ? above : below;
        ASSERT_GE(from, 0);
        EXPECT_TRUE(std::equal(v.image.rgb.begin() + ptrdiff_t(size_t(y) * kW * 3), v.image.rgb.begin() + ptrdiff_t(size_t(y + 1) * kW * 3),
                               v.image.rgb.begin() + ptrdiff_t(size_t(from) * kW * 3)))
            << "row " << y << " should be row " << from;
    }
    EXPECT_GE(empty, 4) << "the wider view should see rows beyond the rendered one at the top and bottom";
    for (size_t i = 0; i < v.mask.size(); ++i) ASSERT_FALSE(v.image.rgb[i * 3 + 1] == 255 && v.image.rgb[i * 3] == 0) << i;
    // On any number of threads.
    options.threads = 3;
    Reprojector three;
    EXPECT_EQ(three.warp({f.image, f.depth, a}, wide, nullptr, options).image.rgb, v.image.rgb);
}

// Frame after frame at one size the warp reuses its buffers and gives the same bytes.
TEST(FrameReproject, RepeatsBitForBitInTheSameBuffers) {
    const SceneDesc d = wallAndBox(true);
    const CameraDesc a = eyeAt(0, 0, 10), b = eyeAt(0.25f, 0.1f, 9.7f);
    const RenderedFrame f = render(d, a);
    Reprojector warper;
    const WarpedView first = warper.warp({f.image, f.depth, a}, b);
    const uint8_t* pixels = warper.result().image.rgb.data();
    const WarpedView& again = warper.warp({f.image, f.depth, a}, b);
    EXPECT_EQ(again.image.rgb, first.image.rgb);
    EXPECT_EQ(again.mask, first.mask);
    EXPECT_EQ(warper.result().image.rgb.data(), pixels);
    Image debug;
    warpDebugColours(again, debug);
    EXPECT_EQ(debug.rgb.size(), first.image.rgb.size());
}

// Any number of threads gives the bytes one thread gives: the box scene warped to a pose that
// magnifies (cracks), uncovers (holes, filled from an older view and the row) and turns, and
// the zoo's background, glass and alpha masks moved sideways.
TEST(FrameReproject, ThreadCountDoesNotChangeABit) {
    const SceneDesc d = wallAndBox(true);
    const CameraDesc a = eyeAt(0, 0, 10), b = test::cameraAt({0.45f, 0.2f, 8.5f}, {0.3f, 0.1f, 0}, kFovY), c = eyeAt(0.8f, 0, 10);
    const RenderedFrame fa = render(d, a), fc = render(d, c);
    SceneDesc zoo = test::materialZoo(test::scratchDir(), kW, kH);
    const CameraDesc z = zoo.cameras.front();
    CameraDesc zMoved = z;
    zMoved.position = z.position + Float3{0.3f, 0.1f, 0};
    const RenderedFrame fz = render(zoo, z);
    const WarpSource older{fc.image, fc.depth, c};
    struct Case {
        WarpSource newest;
        CameraDesc target;
        const WarpSource* older;
    };
    for (const Case& k : {Case{{fa.image, fa.depth, a}, b, &older}, Case{{fa.image, fa.depth, a}, b, nullptr},
                          Case{{fz.image, fz.depth, z}, zMoved, nullptr}}) {
        WarpOptions options;
        options.threads = 1;
        Reprojector one;
        const WarpedView& base = one.warp(k.newest, k.target, k.older, options);
        ASSERT_GT(base.holes, 0u);
        ASSERT_GT(count(base, WarpPixel::Warped), base.mask.size() / 2);
        for (int threads : {2, 3, 7, 0}) {
            options.threads = threads;
            Reprojector many;
            const WarpedView& v = many.warp(k.newest, k.target, k.older, options);
            EXPECT_EQ(v.image.rgb, base.image.rgb) << threads << " threads";
            EXPECT_EQ(v.depth, base.depth) << threads << " threads";
            EXPECT_EQ(v.mask, base.mask) << threads << " threads";
            EXPECT_EQ(v.holes, base.holes) << threads << " threads";
        }
    }
}

// A region (a display node's screens and ring) warps only its pixels, reading only its source
// pixels: outside it the buffers keep what they held; inside it every pixel the whole-view warp
// moved from within the region is the same, on any number of threads. The region's edges act
// as the image's. The whole image as a region (or more, clipped) is the whole-view warp; an
// empty one warps nothing.
TEST(FrameReproject, ARegionWarpsOnlyItsPixels) {
    const SceneDesc d = wallAndBox(true);
    const CameraDesc a = eyeAt(0, 0, 10), b = eyeAt(0.4f, 0, 10), c = eyeAt(0.8f, 0, 10), elsewhere = eyeAt(-0.6f, 0.2f, 9);
    const RenderedFrame fa = render(d, a), fc = render(d, c);
    const WarpSource older{fc.image, fc.depth, c};
    Reprojector whole;
    const WarpedView base = whole.warp({fa.image, fa.depth, a}, b, &older);
    ASSERT_GT(base.holes, 0u);
    for (const TileRect all : {TileRect{0, 0, kW, kH}, TileRect{-5, -9, kW + 5, kH + 30}}) {
        WarpOptions options;
        options.region = all;
        Reprojector r;
        const WarpedView& v = r.warp({fa.image, fa.depth, a}, b, &older, options);
        EXPECT_EQ(v.image.rgb, base.image.rgb);
        EXPECT_EQ(v.mask, base.mask);
        EXPECT_EQ(v.holes, base.holes);
    }
    // The node holds only the region: outside it, no depth (nothing rendered there).
    const TileRect region{40, 32, 120, 96};
    auto inside = [&](int x, int y) { return x >= region.x0 && x < region.x1 && y >= region.y0 && y < region.y1; };
    std::vector<float> held = fa.depth, heldOlder = fc.depth;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            if (!inside(x, y)) held[size_t(y) * kW + size_t(x)] = heldOlder[size_t(y) * kW + size_t(x)] = std::nanf("");
    const WarpSource heldOlderSource{fc.image, heldOlder, c};
    std::optional<WarpedView> one;
    for (int threads : {1, 3}) {
        Reprojector r;
        const WarpedView prior = r.warp({fc.image, fc.depth, c}, elsewhere);  // what the buffers held
        WarpOptions options;
        options.threads = threads;
        options.region = region;
        const WarpedView& v = r.warp({fa.image, held, a}, b, &heldOlderSource, options);
        size_t compared = 0;
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x) {
                const size_t i = size_t(y) * kW + size_t(x);
                if (!inside(x, y)) {
                    ASSERT_EQ(std::memcmp(&v.image.rgb[i * 3], &prior.image.rgb[i * 3], 3), 0) << x << "," << y << " is outside";
                    ASSERT_EQ(v.mask[i], prior.mask[i]);
                    continue;
                }
                // The camera moved 0.4 right: a point seen at x came from x + 4 (wall) or x + 8 (box).
                if (base.mask[i] != WarpPixel::Warped || x + 8 >= region.x1) continue;
                EXPECT_EQ(std::memcmp(&v.image.rgb[i * 3], &base.image.rgb[i * 3], 3), 0) << x << "," << y;
                EXPECT_EQ(v.mask[i], WarpPixel::Warped) << x << "," << y;
                ++compared;
            }
        EXPECT_GT(compared, size_t(region.width() - 8) * size_t(region.height()) * 3 / 4);
        if (!one) one = v;
        else EXPECT_EQ(v.image.rgb, one->image.rgb) << threads << " threads";
    }
    // An empty region: nothing warped.
    Reprojector r;
    const WarpedView prior = r.warp({fc.image, fc.depth, c}, elsewhere);
    WarpOptions none;
    none.region = TileRect{10, 10, 10, 50};
    const WarpedView& v = r.warp({fa.image, fa.depth, a}, b, nullptr, none);
    EXPECT_EQ(v.image.rgb, prior.image.rgb);
    EXPECT_EQ(v.holes, 0u);
}

TEST(FrameReproject, TimingHookMeasures) {
    for (int threads : {1, 2}) {
        const WarpTiming t = timeReprojection(64, 48, 5, threads);
        EXPECT_EQ(t.runs, 5);
        EXPECT_GT(t.medianMs, 0.0);
        EXPECT_GE(t.p95Ms, t.medianMs);
    }
}

}  // namespace
}  // namespace rtwall
