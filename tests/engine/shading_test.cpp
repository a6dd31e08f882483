// Fresnel, refraction and sRGB quantisation against analytic values.
#include "shading.h"
#include "texture.h"

#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace rtwall {
namespace {

TEST(Fresnel, NormalIncidenceMatchesSchlickR0) {
    for (float n : {1.33f, 1.5f, 2.4f}) {
        const float r0 = ((n - 1) / (n + 1)) * ((n - 1) / (n + 1));
        EXPECT_NEAR(fresnelDielectric(1.0f, 1.0f / n), r0, 1e-6f) << "n=" << n;
        // Symmetric from inside at normal incidence.
        EXPECT_NEAR(fresnelDielectric(1.0f, n), r0, 1e-6f) << "n=" << n;
    }
}

TEST(Fresnel, BrewsterAngleHasNoPPolarisedReflection) {
    // At Brewster's angle rp = 0, so the unpolarised reflectance is rs^2 / 2.
    const double n = 1.5, thetaB = std::atan(n);
    const double cosI = std::cos(thetaB), cosT = std::cos(std::asin(std::sin(thetaB) / n));
    const double rs = (cosI - n * cosT) / (cosI + n * cosT);
    EXPECT_NEAR(fresnelDielectric(float(cosI), float(1.0 / n)), 0.5 * rs * rs, 1e-5);
}

TEST(Fresnel, TotalInternalReflectionBeyondCriticalAngle) {
    const float n = 1.5f, critical = std::asin(1.0f / n);
    EXPECT_EQ(fresnelDielectric(std::cos(critical + 0.01f), n), 1.0f);
    EXPECT_LT(fresnelDielectric(std::cos(critical - 0.01f), n), 1.0f);
    Float3 out;
    const float a = critical + 0.05f;
    EXPECT_FALSE(refractDirection(Float3{std::sin(a), -std::cos(a), 0}, Float3{0, 1, 0}, n, out));
}

TEST(Fresnel, GrazingIncidenceReflectsEverything) {
    EXPECT_NEAR(fresnelDielectric(1e-6f, 1.0f / 1.5f), 1.0f, 1e-4f);
}

TEST(Refraction, ObeysSnellsLaw) {
    for (float deg : {0.0f, 10.0f, 30.0f, 60.0f, 85.0f}) {
        const float a = deg * float(std::numbers::pi) / 180.0f;
        const Float3 d{std::sin(a), -std::cos(a), 0};
        Float3 t;
        ASSERT_TRUE(refractDirection(d, Float3{0, 1, 0}, 1.0f / 1.5f, t));
        EXPECT_NEAR(length(t), 1.0f, 1e-6f);
        EXPECT_LT(t.y, 0.0f);  // continues into the surface
        EXPECT_NEAR(std::sin(a), 1.5f * t.x, 1e-5f) << deg;  // n1 sin(i) = n2 sin(t)
    }
}

TEST(Srgb, EveryCodeRoundTripsExactly) {
    for (int c = 0; c < 256; ++c) EXPECT_EQ(linearToSrgb8(srgb8ToLinear(uint8_t(c))), c);
}

TEST(Srgb, QuantisationIsCorrectlyRoundedAndMonotonic) {
    // Compare with the formula evaluated in double precision on a fine grid.
    uint8_t prev = 0;
    for (int i = 0; i <= 100000; ++i) {
        const double x = i / 100000.0;
        const double s = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055;
        const double code = s * 255.0;
        const uint8_t got = linearToSrgb8(float(x));
        // Exactly at a rounding boundary either neighbour is acceptable (float input).
        EXPECT_LE(std::fabs(double(got) - code), 0.5 + 1e-4) << x;
        EXPECT_GE(got, prev);
        prev = got;
    }
    EXPECT_EQ(linearToSrgb8(-1.0f), 0);
    EXPECT_EQ(linearToSrgb8(NAN), 0);
    EXPECT_EQ(linearToSrgb8(INFINITY), 255);
    EXPECT_EQ(linearToSrgb8(7.0f), 255);
}

// Bump mapping takes the analytic gradient of the noise: it must match central differences
// (in double-checked small steps, away from the kinks of |noise| where the one-sided
// derivatives differ) to 1e-3 relative.
// turbulenceGrad evaluates four octaves at once in SIMD lanes; it must give exactly the bits of
// the scalar octave loop (perlinNoiseGrad per octave, summed in octave order), or bump-mapped
// images would change with the build's instruction set. Points on both sides of zero, on
// lattice planes and far out, with 4 and 6 octaves (the lanes plus scalar leftovers).
TEST(Noise, TurbulenceGradientLanesAreBitIdenticalToTheScalarLoop) {
    auto scalar = [](const Float3& p, int octaves, Float3& gradient) {
        float sum = 0.0f, amp = 1.0f, freq = 1.0f;
        gradient = {0, 0, 0};
        for (int i = 0; i < octaves; ++i) {
            Float3 gi;
            const float n = perlinNoiseGrad(p * freq, gi);
            sum += amp * std::fabs(n);
            gradient += gi * (n < 0.0f ? -amp * freq : amp * freq);
            amp *= 0.5f;
            freq *= 2.0f;
        }
        return sum;
    };
    // Points where the noise and its gradient are not zero: two implementations that both gave
    // zeros (or returned early) would agree everywhere.
    int nonTrivial = 0;
    for (int i = 0; i < 3000; ++i) {
        const float s = i % 3 == 0 ? 1.0f : (i % 3 == 1 ? 37.0f : 2000.0f);
        Float3 p{std::sin(1.37f * i) * s, std::cos(0.91f * i) * s, std::sin(0.13f * i + 1.0f) * s};
        if (i % 10 == 0) p.x = std::floor(p.x);  // on a lattice plane
        for (int octaves : {4, 6}) {
            Float3 a, b;
            const float ta = turbulenceGrad(p, octaves, a), tb = scalar(p, octaves, b);
            EXPECT_EQ(ta, tb) << i;
            EXPECT_EQ(a.x, b.x) << i;
            EXPECT_EQ(a.y, b.y) << i;
            EXPECT_EQ(a.z, b.z) << i;
            nonTrivial += ta != 0.0f && (a.x != 0.0f || a.y != 0.0f || a.z != 0.0f);
        }
    }
    EXPECT_GT(nonTrivial, 5400) << "of 6000 points";
}

TEST(Noise, AnalyticGradientMatchesFiniteDifferences) {
    int checked = 0;
    for (int i = 0; i < 400; ++i) {
        const Float3 p{0.037f * i - 7.0f, std::cos(0.31f * i) * 7.0f, std::sin(0.7f * i) * 9.0f};
        Float3 g;
        const float n = perlinNoiseGrad(p, g);
        EXPECT_NEAR(n, perlinNoise(p), 1e-5f) << i;  // the same value, summed in another order
        const float e = 1e-3f;
        const Float3 fd{(perlinNoise(p + Float3{e, 0, 0}) - perlinNoise(p - Float3{e, 0, 0})) / (2 * e),
                        (perlinNoise(p + Float3{0, e, 0}) - perlinNoise(p - Float3{0, e, 0})) / (2 * e),
                        (perlinNoise(p + Float3{0, 0, e}) - perlinNoise(p - Float3{0, 0, e})) / (2 * e)};
        EXPECT_NEAR(g.x, fd.x, 2e-3f * (1.0f + std::fabs(fd.x))) << i;
        EXPECT_NEAR(g.y, fd.y, 2e-3f * (1.0f + std::fabs(fd.y))) << i;
        EXPECT_NEAR(g.z, fd.z, 2e-3f * (1.0f + std::fabs(fd.z))) << i;

        Float3 tg;
        const float t = turbulenceGrad(p, 4, tg);
        EXPECT_NEAR(t, turbulence(p, 4), 1e-5f) << i;
        // Skip points where an octave's noise is near zero (the kink of |noise|).
        bool nearKink = false;
        for (int o = 0; o < 4; ++o) nearKink |= std::fabs(perlinNoise(p * float(1 << o))) < 0.02f;
        if (nearKink) continue;
        const Float3 tfd{(turbulence(p + Float3{e, 0, 0}, 4) - turbulence(p - Float3{e, 0, 0}, 4)) / (2 * e),
                         (turbulence(p + Float3{0, e, 0}, 4) - turbulence(p - Float3{0, e, 0}, 4)) / (2 * e),
                         (turbulence(p + Float3{0, 0, e}, 4) - turbulence(p - Float3{0, 0, e}, 4)) / (2 * e)};
        EXPECT_NEAR(tg.x, tfd.x, 1e-2f * (1.0f + std::fabs(tfd.x))) << i;
        EXPECT_NEAR(tg.y, tfd.y, 1e-2f * (1.0f + std::fabs(tfd.y))) << i;
        EXPECT_NEAR(tg.z, tfd.z, 1e-2f * (1.0f + std::fabs(tfd.z))) << i;
        ++checked;
    }
    EXPECT_GT(checked, 100);
}

}  // namespace
}  // namespace rtwall
