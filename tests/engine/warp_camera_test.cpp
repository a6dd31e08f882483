// Rays through calibrated projector pixels (issue 30): a Camera's warps. A warp of zero
// offsets is the flat camera bit for bit; a whole-pixel shift moves the image exactly; samples
// that land on no screen are black; surface points give the ray from the eye through them,
// checked against a cylinder computed here in double precision, between pixel centres too.
#include "test_util.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

namespace rtwall {
namespace {

constexpr int W = 64, H = 48;

CameraDesc flatCamera() {
    CameraDesc c;
    c.position = {0.3f, 1.6f, 7.0f};
    c.window = ProjectionWindow{{-3.0f, -0.5f, 2.0f}, {6.0f, 0.0f, 0.0f}, {0.0f, 4.5f, 0.0f}};
    return c;
}

// A grid of screen offsets over `rect`, every sample `offset`, those for which `off` holds NaN.
std::shared_ptr<PixelWarp> offsets(const TileRect& rect, Float3 offset, bool (*off)(int, int) = nullptr) {
    auto w = std::make_shared<PixelWarp>();
    w->kind = PixelWarp::Kind::ScreenOffsets;
    w->width = rect.width();
    w->height = rect.height();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int j = 0; j < w->height; ++j)
        for (int i = 0; i < w->width; ++i) w->samples.push_back(off && off(i, j) ? Float3{nan, nan, nan} : offset);
    return w;
}

Image render(const SceneDesc& d, const CameraDesc& c, std::vector<ScreenWarp> warps = {}) {
    const Scene scene(d);
    return renderFrame(scene, Camera(c, d.settings.width, d.settings.height, std::move(warps)), d.settings);
}

const uint8_t* px(const Image& im, int x, int y) { return im.rgb.data() + (size_t(y) * size_t(im.width) + size_t(x)) * 3; }

TEST(WarpCamera, ZeroOffsetsAreTheFlatCameraBitForBitSupersampledToo) {
    for (int ss : {1, 3}) {
        SceneDesc d = test::demoScene(W, H, ss);
        const CameraDesc flat = flatCamera();
        const TileRect all{0, 0, W, H};
        const std::vector<ScreenWarp> warps{{all, offsets(all, {0, 0, 0}), {}}};
        const Image a = render(d, flat), b = render(d, flat, warps);
        EXPECT_TRUE(a.rgb == b.rgb) << "supersample " << ss;
        // The directions themselves, at centres and between them.
        const Camera cf(flat, W, H), cw(flat, W, H, warps);
        for (float y : {0.0f, 0.5f, 13.25f, 47.9f})
            for (float x : {0.0f, 0.5f, 31.75f, 63.99f}) EXPECT_EQ(cf.direction(x, y), cw.direction(x, y)) << x << "," << y;
    }
}

TEST(WarpCamera, AWholePixelShiftShiftsTheImageExactlyAndOffScreenIsBlack) {
    SceneDesc d = test::demoScene(W, H, 1);
    // Eye-light shading: a pixel's colour is its ray's alone (full shading also draws per-pixel
    // random numbers: pruning coins, light samples, which a shifted pixel does not share).
    d.settings.shading = ShadingMode::EyeLight;
    const CameraDesc flat = flatCamera();
    const TileRect all{0, 0, W, H};
    // Pixel (i, j) looks where flat pixel (i + 3, j - 2) looks; a 10x6 block lands on no screen.
    const Image a = render(d, flat),
                b = render(d, flat, {{all, offsets(all, {3, -2, 0}, [](int i, int j) { return i >= 20 && i < 30 && j >= 10 && j < 16; }), {}}});
    size_t compared = 0, black = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const uint8_t* got = px(b, x, y);
            if (x >= 20 && x < 30 && y >= 10 && y < 16) {
                black += got[0] == 0 && got[1] == 0 && got[2] == 0;
                continue;
            }
            if (x + 3 >= W || y - 2 < 0) continue;
            const uint8_t* want = px(a, x + 3, y - 2);
            ASSERT_TRUE(got[0] == want[0] && got[1] == want[1] && got[2] == want[2]) << x << "," << y;
            ++compared;
        }
    EXPECT_EQ(black, 60u);
    EXPECT_GT(compared, size_t(W * H) * 8 / 10);
    // Off the screen is black where the flat image is not.
    size_t flatBlack = 0;
    for (int y = 10; y < 16; ++y)
        for (int x = 20; x < 30; ++x) flatBlack += px(a, x + 3, y - 2)[0] == 0 && px(a, x + 3, y - 2)[1] == 0;
    EXPECT_EQ(flatBlack, 0u);
}

// A warp over part of the image: the rest looks as the flat camera does.
TEST(WarpCamera, PixelsOutsideEveryWarpLookFlat) {
    const CameraDesc flat = flatCamera();
    const TileRect right{32, 0, 64, 48};
    const Camera cf(flat, W, H), cw(flat, W, H, {{right, offsets(right, {1, 0, 0}), {}}});
    EXPECT_EQ(cw.direction(10.5f, 7.5f), cf.direction(10.5f, 7.5f));
    EXPECT_EQ(cw.direction(40.5f, 7.5f), cf.direction(41.5f, 7.5f));
    EXPECT_TRUE(cw.warped());
    EXPECT_FALSE(cf.warped());
}

// A cylinder (radius 3 m, axis vertical through (0, y, 3)) seen from (0.2, 0.1, 2.5), moved into
// the world by a turn and scale: each pixel's ray goes through its surface point, computed
// here independently (double), and halfway between two centres through the midpoint of theirs.
TEST(WarpCamera, SurfacePointsGiveRaysFromTheEyeThroughThem) {
    const int gw = 16, gh = 12;
    auto point = [](int i, int j) {  // angle from -40 to +40 degrees, height 1.2 to -1.2 (top row first)
        const double theta = (-40.0 + 80.0 * (i + 0.5) / gw) * M_PI / 180.0, y = 1.2 - 2.4 * (j + 0.5) / gh;
        return std::array<double, 3>{3.0 * std::sin(theta), y, 3.0 - 3.0 * std::cos(theta)};
    };
    auto grid = std::make_shared<PixelWarp>();
    grid->kind = PixelWarp::Kind::SurfacePoints;
    grid->width = gw;
    grid->height = gh;
    for (int j = 0; j < gh; ++j)
        for (int i = 0; i < gw; ++i) {
            const auto p = point(i, j);
            grid->samples.push_back({float(p[0]), float(p[1]), float(p[2])});
        }
    // The room in the world: turned 90 degrees about y (room x -> world -z), scale 2, the viewer
    // (0.2, 0.1, 2.5) at world (10, 0, 0).
    RoomToWorld room;
    room.viewer = {0.2f, 0.1f, 2.5f};
    room.origin = {10, 0, 0};
    room.x = {0, 0, -1};
    room.y = {0, 1, 0};
    room.z = {1, 0, 0};
    room.scale = 2;
    CameraDesc c;
    c.position = {10, 0, 0};  // the eye at the viewer
    c.window = ProjectionWindow{{-1, -1, -1}, {2, 0, 0}, {0, 2, 0}};  // unused by warped pixels
    const TileRect rect{0, 0, gw, gh};
    const Camera cam(c, gw, gh, {{rect, grid, room}});
    auto toWorld = [&](std::array<double, 3> p) {  // independent of RoomToWorld::point
        const double dx = p[0] - 0.2, dy = p[1] - 0.1, dz = p[2] - 2.5;
        return std::array<double, 3>{10.0 + 2.0 * dz, 2.0 * dy, -2.0 * dx};
    };
    auto expectRay = [&](float x, float y, std::array<double, 3> target) {
        const Float3 d = cam.direction(x, y);
        const auto w = toWorld(target);
        const double ex = w[0] - 10.0, ey = w[1], ez = w[2], el = std::sqrt(ex * ex + ey * ey + ez * ez);
        const double dl = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
        EXPECT_NEAR(d.x / dl, ex / el, 2e-6) << x << "," << y;
        EXPECT_NEAR(d.y / dl, ey / el, 2e-6) << x << "," << y;
        EXPECT_NEAR(d.z / dl, ez / el, 2e-6) << x << "," << y;
    };
    for (int j = 0; j < gh; ++j)
        for (int i = 0; i < gw; ++i) expectRay(float(i) + 0.5f, float(j) + 0.5f, point(i, j));
    // Between the centres of (4, 5) and (5, 5): the midpoint of their points.
    const auto a = point(4, 5), b = point(5, 5);
    expectRay(5.0f, 5.5f, {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2});
    // A quarter of the way down from (7, 2) to (7, 3).
    const auto p = point(7, 2), q = point(7, 3);
    expectRay(7.5f, 2.75f, {p[0] + (q[0] - p[0]) / 4, p[1] + (q[1] - p[1]) / 4, p[2] + (q[2] - p[2]) / 4});
}

// A sample whose neighbour lands on no screen: exactly at its own centre it is on the screen;
// any weight on the NaN neighbour makes it off the screen (black, never a mixed ray).
TEST(WarpCamera, ANeighbourOffTheScreenReachesOnlySamplesThatInterpolateIt) {
    const TileRect all{0, 0, 4, 4};
    const Camera cam(flatCamera(), 4, 4, {{all, offsets(all, {0, 0, 0}, [](int i, int) { return i == 2; }), {}}});
    EXPECT_FALSE(std::isnan(cam.direction(1.5f, 1.5f).x));
    EXPECT_TRUE(std::isnan(cam.direction(1.75f, 1.5f).x));
    EXPECT_TRUE(std::isnan(cam.direction(2.5f, 1.5f).x));
    EXPECT_FALSE(std::isnan(cam.direction(3.5f, 0.5f).x));
    EXPECT_TRUE(std::isnan(cam.direction(3.25f, 0.5f).x));
}

}  // namespace
}  // namespace rtwall
