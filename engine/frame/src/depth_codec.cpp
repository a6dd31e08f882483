#include <rtwall/depth_codec.h>
#include <rtwall/engine.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rtwall {

namespace {

// In double: the float depth is exact there, so the only errors are the quantisation's and the
// final rounding to float.
const double kLogNear = std::log(double(kDepthCodecNear));
const double kStep = (std::log(double(kDepthCodecFar)) - kLogNear) / double(kDepthCodeBackground - 2);

void checkSizes(const char* what, size_t bytes, size_t pixels) {
    if (bytes != encodedDepthBytes(pixels))
        throw std::invalid_argument(std::string(what) + ": " + std::to_string(bytes) + " bytes for " +
                                    std::to_string(pixels) + " depths (expected " +
                                    std::to_string(encodedDepthBytes(pixels)) + ")");
}

}  // namespace

uint16_t encodeDepth(float depth) {
    if (depth == kBackgroundDepth) return kDepthCodeBackground;
    if (!(depth > 0.0f) || !std::isfinite(depth)) return kDepthCodeHole;
    const double steps = std::clamp((std::log(double(depth)) - kLogNear) / kStep, 0.0, double(kDepthCodeBackground - 2));
    return uint16_t(1 + std::lround(steps));
}

float decodeDepth(uint16_t code) {
    if (code == kDepthCodeHole) return std::numeric_limits<float>::quiet_NaN();
    if (code == kDepthCodeBackground) return kBackgroundDepth;
    return float(std::exp(kLogNear + double(code - 1) * kStep));
}

void encodeDepths(std::span<const float> depth, std::span<uint8_t> out) {
    checkSizes("encodeDepths", out.size(), depth.size());
    for (size_t i = 0; i < depth.size(); ++i) {
        const uint16_t code = encodeDepth(depth[i]);
        out[2 * i] = uint8_t(code & 0xFF);
        out[2 * i + 1] = uint8_t(code >> 8);
    }
}

void decodeDepths(std::span<const uint8_t> in, std::span<float> out) {
    checkSizes("decodeDepths", in.size(), out.size());
    for (size_t i = 0; i < out.size(); ++i) out[i] = decodeDepth(uint16_t(in[2 * i] | (in[2 * i + 1] << 8)));
}

}  // namespace rtwall
