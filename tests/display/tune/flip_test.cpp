// LDR-FLIP against values derived by hand from the paper's definition and published CIELAB
// values of the sRGB primaries, and its defining properties: identical images give 0, the
// largest colour difference (green against blue) gives 1, errors stay where the images differ,
// more noise gives more error, and the metric is symmetric.
#include <rtwall/tune.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace rtwall {
namespace {

Image filled(int w, int h, uint8_t r, uint8_t g, uint8_t b) {
    Image img{w, h, std::vector<uint8_t>(size_t(w) * h * 3)};
    for (size_t i = 0; i < size_t(w) * h; ++i) {
        img.rgb[3 * i] = r;
        img.rgb[3 * i + 1] = g;
        img.rgb[3 * i + 2] = b;
    }
    return img;
}

// Published CIELAB (D65) of sRGB green and blue and their Hunt-adjusted HyAB distance raised to
// qc = 0.7: FLIP's cmax.
double cmax() {
    const double gl = 87.7347, ga = -86.1827, gb = 83.1793, bl = 32.3026, ba = 79.1967, bb = -107.8637;
    const double hyab = std::abs(gl - bl) + std::hypot(0.01 * gl * ga - 0.01 * bl * ba, 0.01 * gl * gb - 0.01 * bl * bb);
    return std::pow(hyab, 0.7);
}

// The paper's remapping of a powered colour distance e (pc = 0.4, pt = 0.95).
double remap(double e) {
    const double c = cmax(), p = 0.4 * c;
    return e < p ? 0.95 * e / p : 0.95 + (e - p) / (c - p) * 0.05;
}

TEST(Flip, IdenticalImagesAreZeroEverywhere) {
    Image a = filled(40, 30, 0, 0, 0);
    std::mt19937 rng(7);
    for (uint8_t& v : a.rgb) v = uint8_t(rng() & 255);
    for (float v : flipErrorMap(a, a)) ASSERT_EQ(v, 0.0f);
    EXPECT_EQ(flipMean(a, a), 0.0);
    EXPECT_EQ(compareImages(a, a).flip, 0.0);
}

TEST(Flip, GreenAgainstBlueIsTheLargestErrorOne) {
    // Uniform images have no features, so FLIP is the colour term alone; green and blue are the
    // pair that defines cmax, which maps to exactly 1.
    const Image g = filled(32, 32, 0, 255, 0), b = filled(32, 32, 0, 0, 255);
    for (float v : flipErrorMap(g, b)) ASSERT_NEAR(v, 1.0, 1e-6);
}

TEST(Flip, BlackAgainstWhiteFromTheDefinition) {
    // HyAB(black, white) = |0 - 100| (a = b = 0): 100^0.7 = 25.1, above pc x cmax (16.5), so it
    // lands in the compressed top range: 0.95 + (25.1 - 16.5) / (41.3 - 16.5) x 0.05 = 0.967.
    const Image k = filled(24, 24, 0, 0, 0), w = filled(24, 24, 255, 255, 255);
    const double expect = remap(std::pow(100.0, 0.7));
    EXPECT_NEAR(expect, 0.9674, 1e-3);  // the hand computation above
    EXPECT_NEAR(flipMean(w, k), expect, 1e-4);
    EXPECT_NEAR(compareImages(w, k).flip, expect, 1e-4);
}

TEST(Flip, MidGreyAgainstBlackFromTheDefinition) {
    // sRGB 128 is L* = 53.585 (published), a = b = 0: 53.585^0.7 = 16.23 < pc x cmax, so FLIP =
    // 0.95 x 16.23 / 16.51 = 0.934.
    const Image grey = filled(24, 24, 128, 128, 128), k = filled(24, 24, 0, 0, 0);
    EXPECT_NEAR(flipMean(grey, k), remap(std::pow(53.585, 0.7)), 1e-4);
    // A small step: L* 53.585 (128) against 54.0 (129 is L* 53.98): tiny, far below 1.
    const Image g2 = filled(24, 24, 129, 129, 129);
    EXPECT_NEAR(flipMean(g2, grey), remap(std::pow(53.9889 - 53.585, 0.7)), 2e-3);
}

TEST(Flip, ErrorStaysNearWhereTheImagesDiffer) {
    // A vertical black/white edge at x = 60 against the same edge at x = 62. Beyond the widest
    // filter (CSF radius 10 and feature radius 9 at 67 pixels per degree) both images are locally
    // identical, so FLIP is exactly 0 there; at the edge, colour and features both differ.
    const int w = 128, h = 16;
    Image a = filled(w, h, 0, 0, 0), b = a;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                a.pixel(x, y)[c] = x >= 60 ? 255 : 0;
                b.pixel(x, y)[c] = x >= 62 ? 255 : 0;
            }
    const std::vector<float> map = flipErrorMap(b, a);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float v = map[size_t(y) * w + x];
            if (x < 60 - 20 || x > 62 + 20) {
                ASSERT_EQ(v, 0.0f) << x;
            } else if (x == 60 || x == 61) {
                ASSERT_GT(v, 0.5f) << x;  // black against white, plus the edge moved
            }
        }
}

TEST(Flip, MoreNoiseMoreError) {
    // A smooth gradient with Gaussian noise of growing level: FLIP grows strictly.
    Image ref = filled(96, 64, 0, 0, 0);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 96; ++x) {
            ref.pixel(x, y)[0] = uint8_t(40 + x * 2);
            ref.pixel(x, y)[1] = uint8_t(60 + y * 2);
            ref.pixel(x, y)[2] = 128;
        }
    double last = 0;
    for (double sigma : {1.0, 4.0, 16.0, 48.0}) {
        std::mt19937 rng(3);
        std::normal_distribution<double> noise(0, sigma);
        Image t = ref;
        for (uint8_t& v : t.rgb) v = uint8_t(std::clamp(std::lround(v + noise(rng)), 0L, 255L));
        const double f = flipMean(t, ref);
        EXPECT_GT(f, last) << "sigma " << sigma;
        EXPECT_LT(f, 1.0);
        last = f;
    }
}

TEST(Flip, Symmetric) {
    Image a = filled(50, 40, 0, 0, 0), b = a;
    std::mt19937 rng(11);
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        a.rgb[i] = uint8_t(rng() & 255);
        b.rgb[i] = uint8_t((a.rgb[i] + (rng() % 40)) & 255);
    }
    const std::vector<float> ab = flipErrorMap(a, b), ba = flipErrorMap(b, a);
    for (size_t i = 0; i < ab.size(); ++i) ASSERT_NEAR(ab[i], ba[i], 1e-6);
}

TEST(Flip, FurtherAwayAFineCheckerboardIsLessVisible) {
    // A one-pixel checkerboard of sRGB 110 and 150 against sRGB 132, their mean in linear light
    // (0.2302 against 0.2307): the further away the viewer (more pixels per degree), the more
    // the CSFs blur the pattern into that mean and the lower FLIP. (Beyond about 67 the 64-pixel
    // image is smaller than the filters and the replicated border dominates.)
    Image checker = filled(64, 64, 0, 0, 0);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x)
            for (int c = 0; c < 3; ++c) checker.pixel(x, y)[c] = (x + y) % 2 ? 150 : 110;
    const Image mean = filled(64, 64, 132, 132, 132);
    double last = 1;
    for (double ppd : {10.0, 20.0, 40.0, 67.0}) {
        const double f = flipMean(checker, mean, ppd);
        EXPECT_LT(f, last) << ppd << " pixels per degree";
        last = f;
    }
    EXPECT_LT(last, 0.01);  // at the default distance the pattern is all but invisible
}

TEST(Flip, BadInputIsOneLine) {
    const Image a = filled(8, 8, 0, 0, 0), b = filled(9, 8, 0, 0, 0);
    try {
        flipMean(a, b);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("8x8 against 9x8"), std::string::npos) << e.what();
    }
    EXPECT_THROW(flipMean(a, a, 0), InputError);
}

}  // namespace
}  // namespace rtwall
