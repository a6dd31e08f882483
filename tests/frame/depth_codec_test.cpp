// The depth codec (rtwall/depth_codec.h): depth survives it within the stated relative error,
// what is not a depth becomes a hole, the background stays the background, and sizes that do
// not match are refused with both sizes named.
#include <rtwall/depth_codec.h>
#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace rtwall {
namespace {

double relativeError(float depth) { return std::fabs(double(decodeDepth(encodeDepth(depth))) / double(depth) - 1.0); }

// The bound in the header, proved by what decides it: the worst depths are the ones halfway
// (in log) between two codes, so every code's two boundaries (and a hair either side) are
// tried, and a million log-uniform depths besides. The bound is also tight: the worst error
// seen comes within 1% of it, so it says what the codec does.
TEST(FrameDepthCodec, RelativeErrorStaysWithinTheStatedBound) {
    const double logNear = std::log(double(kDepthCodecNear)), logFar = std::log(double(kDepthCodecFar));
    const double step = (logFar - logNear) / 65533.0;
    double worst = 0;
    for (int code = 1; code <= 0xFFFE; ++code)
        for (double half : {-0.5, 0.5})
            for (float nudge : {-1.0f, 0.0f, 1.0f}) {
                float d = float(std::exp(logNear + (double(code - 1) + half) * step));
                if (nudge != 0) d = std::nextafter(d, nudge * std::numeric_limits<float>::infinity());
                if (d < kDepthCodecNear || d > kDepthCodecFar) continue;
                worst = std::max(worst, relativeError(d));
            }
    std::mt19937 random(27);
    std::uniform_real_distribution<double> logDepth(logNear, logFar);
    for (int i = 0; i < 1'000'000; ++i) worst = std::max(worst, relativeError(float(std::exp(logDepth(random)))));
    EXPECT_LE(worst, kDepthCodecRelativeError);
    EXPECT_GT(worst, 0.99 * kDepthCodecRelativeError) << "the stated bound is loose";
}

// Codes grow with depth (the warp's depth test sees the same order), and the range's ends
// clamp to its first and last code.
TEST(FrameDepthCodec, CodesAreMonotonicAndClampAtTheRangeEnds) {
    uint16_t last = 0;
    for (double d = 1e-6; d < 1e9; d *= 1.0001) {
        const uint16_t code = encodeDepth(float(d));
        ASSERT_GE(code, last) << d;
        last = code;
    }
    EXPECT_EQ(encodeDepth(1e-9f), 1);
    EXPECT_EQ(encodeDepth(kDepthCodecNear), 1);
    EXPECT_EQ(encodeDepth(kDepthCodecFar), 0xFFFE);
    EXPECT_EQ(encodeDepth(1e30f), 0xFFFE);
    EXPECT_FLOAT_EQ(decodeDepth(1), kDepthCodecNear);
    EXPECT_NEAR(decodeDepth(0xFFFE), kDepthCodecFar, kDepthCodecFar * 1e-6);
}

TEST(FrameDepthCodec, WhatIsNoDepthIsAHoleAndTheBackgroundStays) {
    const float inf = std::numeric_limits<float>::infinity();
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::quiet_NaN(),
                      std::numeric_limits<float>::signaling_NaN(), inf, -inf, 0.0f, -0.0f, -1.0f,
                      -kBackgroundDepth, -std::numeric_limits<float>::denorm_min()}) {
        EXPECT_EQ(encodeDepth(bad), kDepthCodeHole) << bad;
    }
    EXPECT_TRUE(std::isnan(decodeDepth(kDepthCodeHole)));
    EXPECT_EQ(encodeDepth(kBackgroundDepth), kDepthCodeBackground);
    EXPECT_EQ(decodeDepth(kDepthCodeBackground), kBackgroundDepth);
    // The smallest positive float is a (clamped) depth, not a hole.
    EXPECT_EQ(encodeDepth(std::numeric_limits<float>::denorm_min()), 1);
}

// A buffer through the wire form and back: 2 bytes a depth, little-endian, each value as
// decodeDepth(encodeDepth()) gives it.
TEST(FrameDepthCodec, BuffersRoundTripTwoBytesADepth) {
    const std::vector<float> depth = {1.0f, 2.5f, kBackgroundDepth, std::nanf(""), -3.0f, 1234.5f, 0.001f};
    std::vector<uint8_t> wire(encodedDepthBytes(depth.size()));
    EXPECT_EQ(wire.size(), 14u);
    encodeDepths(depth, wire);
    EXPECT_EQ(wire[4], 0xFF);
    EXPECT_EQ(wire[5], 0xFF);  // the background's code, little-endian
    EXPECT_EQ(wire[6] | wire[7] | wire[8] | wire[9], 0);  // the holes'
    std::vector<float> back(depth.size());
    decodeDepths(wire, back);
    for (size_t i = 0; i < depth.size(); ++i) {
        const float expected = decodeDepth(encodeDepth(depth[i]));
        if (std::isnan(expected)) EXPECT_TRUE(std::isnan(back[i])) << i;
        else EXPECT_EQ(back[i], expected) << i;
    }
    EXPECT_EQ(encodedDepthBytes(1600 * 1200), 3'840'000u);
}

std::string errorOf(size_t bytes, size_t depths) {
    std::vector<uint8_t> wire(bytes, 0x7F);
    std::vector<float> out(depths);
    try {
        decodeDepths(wire, out);
    } catch (const std::invalid_argument& e) {
        return e.what();
    }
    return "";
}

TEST(FrameDepthCodec, TruncatedOrOversizedInputIsRefused) {
    EXPECT_EQ(errorOf(1199, 600), "decodeDepths: 1199 bytes for 600 depths (expected 1200)");
    EXPECT_EQ(errorOf(1201, 600), "decodeDepths: 1201 bytes for 600 depths (expected 1200)");
    EXPECT_EQ(errorOf(0, 1), "decodeDepths: 0 bytes for 1 depths (expected 2)");
    EXPECT_EQ(errorOf(0, 0), "");
    std::vector<float> depth(10, 1.0f);
    std::vector<uint8_t> small(19);
    EXPECT_THROW(encodeDepths(depth, small), std::invalid_argument);
}

}  // namespace
}  // namespace rtwall
