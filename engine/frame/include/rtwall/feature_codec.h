// rtwall feature codec (issue 28): the denoiser's features of a tile on the wire.
//
// What travels is what the active filter reads (featureBitsFor): `temporal` rejects history by
// normal and object (depth goes with the depth codec anyway), `svgf` also demodulates by the
// albedo. Per pixel: albedo as three 8-bit sRGB codes (the precision of the textures it comes
// from), the unit normal in the octahedral map at 2 x 16 bits (under 0.01 degrees), the object
// id as 32 bits: 3 + 4 + 4 = 11 bytes before compression, planar (every pixel's first byte,
// then every pixel's second, ...) so that zstd finds the runs a surface makes. Moments of the GI
// estimate do not travel: the display side takes them from the colour it receives.
// One machine quantises its features the same way (quantiseFeatures), so that it filters the
// very values a cluster does.
#pragma once

#include <cstddef>
#include <cstdint>

namespace rtwall {

enum FeatureBits : uint8_t { kFeatureAlbedo = 1, kFeatureNormal = 2, kFeatureId = 4, kFeatureAll = 7 };

inline constexpr size_t kFeatureAlbedoBytes = 3, kFeatureNormalBytes = 4, kFeatureIdBytes = 4;
inline constexpr size_t encodedFeatureBytes(size_t pixels, uint8_t bits) {
    return pixels * (((bits & kFeatureAlbedo) ? kFeatureAlbedoBytes : 0) + ((bits & kFeatureNormal) ? kFeatureNormalBytes : 0) +
                     ((bits & kFeatureId) ? kFeatureIdBytes : 0));
}

// A tile's features (width x height pixels, `stride` pixels a row; albedo and normal 3 floats a
// pixel) into exactly encodedFeatureBytes(width * height, bits) bytes at `out`. Only the
// features in `bits` are read; their pointers must not be null then.
void encodeFeatures(uint8_t bits, const float* albedo, const float* normal, const uint32_t* id, int width, int height,
                    size_t stride, uint8_t* out);
// The inverse, into rows of `stride` pixels. Throws std::invalid_argument, naming both sizes,
// unless `size` is exactly encodedFeatureBytes(width * height, bits). Features not in `bits` are
// left as they are.
void decodeFeatures(uint8_t bits, const uint8_t* in, size_t size, int width, int height, float* albedo, float* normal,
                    uint32_t* id, size_t stride);
// What the round trip gives, in place, for `pixels` pixels (one machine's features as a
// cluster's): albedo to its 8-bit code's value, the normal to its octahedral code's.
void quantiseFeatures(uint8_t bits, float* albedo, float* normal, size_t pixels);

}  // namespace rtwall
