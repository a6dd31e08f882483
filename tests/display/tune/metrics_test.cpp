// Error metrics against values computed by hand: identical images, a known shift, a known
// noise level; and the one-line errors for mismatched inputs.
#include <rtwall/tune.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace rtwall {
namespace {

Image filled(int w, int h, uint8_t v) { return Image{w, h, std::vector<uint8_t>(size_t(w) * h * 3, v)}; }

// A horizontal ramp, value = x (every channel).
Image ramp(int w, int h) {
    Image img = filled(w, h, 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) img.pixel(x, y)[c] = uint8_t(x);
    return img;
}

TEST(Metrics, IdenticalImages) {
    const Image a = ramp(64, 48);
    const ImageError e = compareImages(a, a);
    EXPECT_EQ(e.rmse, 0.0);
    EXPECT_EQ(e.psnrDb, kIdenticalPsnr);
    EXPECT_DOUBLE_EQ(e.ssim, 1.0);
    EXPECT_EQ(e.maxError, 0);
    EXPECT_TRUE(e.identical());
}

TEST(Metrics, RampShiftedByOnePixel) {
    // Shifting a ramp of slope 1 by one pixel changes every pixel by exactly 1 level, except the
    // first column, which stays (clamped): RMSE = sqrt((w - 1) / w).
    const int w = 64, h = 32;
    const Image a = ramp(w, h);
    Image b = a;
    for (int y = 0; y < h; ++y)
        for (int x = 1; x < w; ++x)
            for (int c = 0; c < 3; ++c) b.pixel(x, y)[c] = a.pixel(x - 1, y)[c];
    const ImageError e = compareImages(b, a);
    EXPECT_DOUBLE_EQ(e.rmse, std::sqrt(double(w - 1) / w));
    EXPECT_DOUBLE_EQ(e.psnrDb, 20 * std::log10(255.0 / std::sqrt(double(w - 1) / w)));
    EXPECT_EQ(e.maxError, 1);
    EXPECT_EQ(e.maxX, 1);
    EXPECT_EQ(e.maxY, 0);
    EXPECT_DOUBLE_EQ(e.meanAbs, double(w - 1) / w);
    // Away from the first column the windows see x and x - 1: equal variance (the ramp's), equal
    // structure, and a mean one level lower. SSIM = (2 m (m - 1) + C1) / (m^2 + (m - 1)^2 + C1)
    // per window; averaged over windows centred at x = 6..58 (the first column lies outside
    // every window from x = 6 on, and only the valid windows count).
    const double c1 = 6.5025;
    double expect = 0;
    int n = 0;
    for (int cx = 5; cx < w - 5; ++cx) {
        const double m = cx;  // window mean of the ramp = centre column
        expect += (2 * m * (m - 1) + c1) / (m * m + (m - 1) * (m - 1) + c1);
        ++n;
    }
    expect /= n;
    EXPECT_NEAR(e.ssim, expect, 2e-3);
}

TEST(Metrics, StripesShiftedByOnePixelAreCompletelyWrong) {
    // One-pixel black and white stripes shifted by one: every pixel off by 255, PSNR 0 dB, and
    // the structure is inverted (SSIM close to -1).
    Image a = filled(32, 32, 0);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; x += 2)
            for (int c = 0; c < 3; ++c) a.pixel(x, y)[c] = 255;
    Image b = a;
    for (uint8_t& v : b.rgb) v = uint8_t(255 - v);
    const ImageError e = compareImages(b, a);
    EXPECT_DOUBLE_EQ(e.rmse, 255.0);
    EXPECT_DOUBLE_EQ(e.psnrDb, 0.0);
    EXPECT_EQ(e.maxError, 255);
    EXPECT_LT(e.ssim, -0.95);
}

TEST(Metrics, KnownNoiseLevel) {
    // +d or -d on every channel of a flat grey image (random signs): RMSE is exactly d.
    const int d = 5;
    const Image a = filled(128, 128, 128);
    Image b = a;
    std::mt19937 rng(7);
    for (uint8_t& v : b.rgb) v = uint8_t(int(v) + ((rng() & 1) ? d : -d));
    const ImageError e = compareImages(b, a);
    EXPECT_DOUBLE_EQ(e.rmse, d);
    EXPECT_NEAR(e.psnrDb, 20 * std::log10(255.0 / d), 1e-12);  // 34.15 dB
    EXPECT_EQ(e.maxError, d);
    // SSIM against a flat image: the luminance term is ~1 and the rest is C2 / (var + C2), var
    // being the luminance noise variance d^2 (0.299^2 + 0.587^2 + 0.114^2), less the Gaussian
    // window's bias factor (1 - sum of squared weights = 0.9648).
    const double c2 = 58.5225;
    const double var = d * d * (0.299 * 0.299 + 0.587 * 0.587 + 0.114 * 0.114) * 0.9648;
    EXPECT_NEAR(e.ssim, c2 / (var + c2), 0.01);  // 0.848
}

TEST(Metrics, MismatchedSizesAreAnInputError) {
    try {
        compareImages(filled(20, 20, 0), filled(20, 21, 0));
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "the images differ in size: 20x20 against 20x21");
    }
    EXPECT_THROW(compareImages(filled(8, 8, 0), filled(8, 8, 0)), InputError);  // smaller than the SSIM window
}

TEST(Metrics, DifferenceImageIsBlackWhereEqualAndRedAtTheScale) {
    Image a = filled(16, 16, 100);
    Image b = a;
    b.pixel(3, 4)[1] = 132;  // 32 levels off in green
    const Image d = differenceImage(b, a, 32);
    EXPECT_EQ(d.pixel(0, 0)[0], 0);
    EXPECT_EQ(d.pixel(0, 0)[1], 0);
    EXPECT_EQ(d.pixel(0, 0)[2], 0);
    EXPECT_EQ(d.pixel(3, 4)[0], 255);
    EXPECT_EQ(d.pixel(3, 4)[1], 0);
    EXPECT_EQ(d.pixel(3, 4)[2], 0);
    const Image half = differenceImage(b, a, 64);  // 32 of 64: green
    EXPECT_EQ(half.pixel(3, 4)[0], 0);
    EXPECT_EQ(half.pixel(3, 4)[1], 200);
}

TEST(Metrics, BilinearResizeKeepsFlatImagesAndInterpolatesRamps) {
    const Image flat = resizeBilinear(filled(10, 10, 77), 20, 15);
    for (uint8_t v : flat.rgb) EXPECT_EQ(v, 77);
    Image two = filled(2, 1, 0);
    for (int c = 0; c < 3; ++c) two.pixel(1, 0)[c] = 100;
    const Image four = resizeBilinear(two, 4, 1);  // centres at 0.25-steps: 0, 25, 75, 100 (clamped ends)
    EXPECT_EQ(four.pixel(0, 0)[0], 0);
    EXPECT_EQ(four.pixel(1, 0)[0], 25);
    EXPECT_EQ(four.pixel(2, 0)[0], 75);
    EXPECT_EQ(four.pixel(3, 0)[0], 100);
    EXPECT_THROW(resizeBilinear(Image{}, 4, 4), InputError);
}

}  // namespace
}  // namespace rtwall
