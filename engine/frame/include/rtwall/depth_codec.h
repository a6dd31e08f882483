// rtwall depth codec (issue 27): a tile's depth on the wire, 2 bytes a pixel.
//
// Depth is what renderTile writes (rtwall/engine.h, DepthView): the distance along each pixel's
// primary ray in scene units, kBackgroundDepth where the ray hit nothing. The code is the
// logarithm of the depth, quantised to 16 bits over [kDepthCodecNear, kDepthCodecFar]: a
// constant relative error, whatever the scene's units (metres, millimetres of a CAD plant), with
// nothing to agree on per scene. What the warp needs is parallax: a point at depth d moves
// f * b / d pixels when the eye moves b, so a relative depth error e moves it by e times its
// parallax: at most 1.76e-4 of it, a hundredth of a pixel for a 64-pixel parallax.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace rtwall {

inline constexpr float kDepthCodecNear = 1e-4f;  // smaller depths are sent as this
inline constexpr float kDepthCodecFar = 1e6f;    // larger finite depths are sent as this
inline constexpr uint16_t kDepthCodeHole = 0;          // no depth: NaN, infinities, zero, negative
inline constexpr uint16_t kDepthCodeBackground = 0xFFFF;  // kBackgroundDepth (the ray hit nothing)
// Codes 1 ... 0xFFFE are log-uniform over [near, far]: code 1 + round(ln(d / near) / step), step
// = ln(far / near) / 65533. Decoding gives near * exp((code - 1) * step), so |ln(d'/d)| <= step
// / 2 and |d'/d - 1| <= expm1(step / 2) = 1.7570e-4, plus the float's own rounding (2^-24):
// within [near, far] the decoded depth is never off by more than this fraction of the depth.
inline constexpr double kDepthCodecRelativeError = 1.76e-4;

uint16_t encodeDepth(float depth);
// kDepthCodeHole decodes to a quiet NaN (a hole to the warp), kDepthCodeBackground to
// kBackgroundDepth.
float decodeDepth(uint16_t code);

// Bytes on the wire for `pixels` depths: 2 each (little-endian codes, in the order given). A
// 1600x1200 view adds 3,840,000 bytes to its 5,760,000 bytes of raw colour.
inline constexpr size_t encodedDepthBytes(size_t pixels) { return 2 * pixels; }
// `out` must hold exactly encodedDepthBytes(depth.size()) bytes and `in` exactly
// encodedDepthBytes(out.size()): anything else throws std::invalid_argument naming both sizes
// (a truncated or oversized message is refused, never read past).
void encodeDepths(std::span<const float> depth, std::span<uint8_t> out);
void decodeDepths(std::span<const uint8_t> in, std::span<float> out);

}  // namespace rtwall
