// postWarp (rtwall/frame.h, issue 30): the rasteriser's resampling of a flat render through a
// projector warp, the comparison the direct rays are measured against. Where the warp asks
// for pixel centres of the flat image it returns them exactly: a flat surface's points, and a
// whole-pixel shift; off-screen pixels are black.
#include <rtwall/frame.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace rtwall {
namespace {

Image pattern(int w, int h) {
    Image im;
    im.width = w;
    im.height = h;
    im.rgb.resize(size_t(w) * size_t(h) * 3);
    for (size_t i = 0; i < im.rgb.size(); ++i) im.rgb[i] = uint8_t((i * 37) ^ (i >> 5));
    return im;
}

CameraDesc windowCamera() {
    CameraDesc c;
    c.position = {0, 0, 2.5f};
    c.window = ProjectionWindow{{-1.6f, -1.2f, 0}, {3.2f, 0, 0}, {0, 2.4f, 0}};
    return c;
}

TEST(PostWarp, TheFlatScreensOwnPointsGiveTheFlatImageBack) {
    const int w = 64, h = 48;
    auto g = std::make_shared<PixelWarp>();
    g->kind = PixelWarp::Kind::SurfacePoints;
    g->width = w;
    g->height = h;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) g->samples.push_back({-1.6f + 3.2f * (i + 0.5f) / w, 1.2f - 2.4f * (j + 0.5f) / h, 0.0f});
    g->samples[5] = {std::numeric_limits<float>::quiet_NaN(), 0, 0};
    const Image flat = pattern(w, h);
    Image out;
    postWarp(flat, windowCamera(), {{0, 0, w, h}, g, {}}, w, h, out);
    ASSERT_EQ(out.rgb.size(), flat.rgb.size());
    size_t differ = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (y == 0 && x == 5) {
                EXPECT_EQ(out.pixel(x, y)[0] + out.pixel(x, y)[1] + out.pixel(x, y)[2], 0) << "NaN: black";
                continue;
            }
            differ += std::memcmp(out.pixel(x, y), flat.pixel(x, y), 3) != 0;
        }
    EXPECT_EQ(differ, 0u);
}

TEST(PostWarp, AWholePixelShiftShiftsAndOffTheImageIsBlack) {
    const int w = 40, h = 30;
    auto g = std::make_shared<PixelWarp>(PixelWarp{PixelWarp::Kind::ScreenOffsets, 1, 1, {{3.0f, -2.0f, 0.0f}}});
    const Image flat = pattern(w, h);
    Image out;
    postWarp(flat, windowCamera(), {{0, 0, w, h}, g, {}}, w, h, out);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const uint8_t* o = out.pixel(x, y);
            if (x + 3 < w && y - 2 >= 0) {
                EXPECT_EQ(std::memcmp(o, flat.pixel(x + 3, y - 2), 3), 0) << x << "," << y;
            } else if (x + 3 > w || y - 2 < -1) {  // its centre looks past the flat image's edge
                EXPECT_EQ(o[0] + o[1] + o[2], 0) << x << "," << y;
            }
        }
}

}  // namespace
}  // namespace rtwall
