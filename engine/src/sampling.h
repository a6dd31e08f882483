// Counter-based random numbers and the few sampling routines the materials share.
//
// No generator state: a random number is a hash of (path seed, dimension), and a path seed is
// a hash of the pixel's image coordinates, the frame and the sample index (children hash in
// their branch). A pixel therefore gets the same numbers whichever tile, thread or render
// client computes it, which is what keeps the cluster bit-identical to one machine.
#pragma once

#include <rtwall/vec.h>

#include <cmath>
#include <cstdint>
#include <numbers>

namespace rtwall {

// Murmur3's 32-bit finaliser: full avalanche, cheap.
inline uint32_t fmix32(uint32_t h) {
    h ^= h >> 16;
    h *= 0x85EBCA6Bu;
    h ^= h >> 13;
    h *= 0xC2B2AE35u;
    h ^= h >> 16;
    return h;
}

inline uint32_t hashCombine(uint32_t seed, uint32_t value) { return fmix32(seed ^ (value * 0x9E3779B9u + 0x7F4A7C15u)); }

inline uint32_t pixelSeed(uint32_t x, uint32_t y, uint32_t frame, uint32_t sample) {
    return hashCombine(hashCombine(hashCombine(fmix32(x + 0x68E31DA4u), y), frame), sample);
}

// Uniform in [0, 1): the top 24 bits, so every value is exact in a float.
inline float randomFloat(uint32_t seed, uint32_t dim) { return float(hashCombine(seed, dim) >> 8) * (1.0f / 16777216.0f); }

// An orthonormal frame around unit n (Duff et al. 2017, branchless).
inline void orthonormalBasis(const Float3& n, Float3& t, Float3& b) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float c = n.x * n.y * a;
    t = {1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x};
    b = {c, sign + n.y * n.y * a, -n.y};
}

inline Float3 fromLocal(const Float3& n, float x, float y, float z) {
    Float3 t, b;
    orthonormalBasis(n, t, b);
    return t * x + b * y + n * z;
}

// Cosine-weighted direction around unit n: pdf = cos / pi.
inline Float3 sampleCosine(const Float3& n, float u1, float u2) {
    const float r = std::sqrt(u1), phi = float(2.0 * std::numbers::pi) * u2;
    return normalize(fromLocal(n, r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u1))));
}

// Phong lobe cos^n around unit axis: pdf = (n + 1) / (2 pi) cos^n.
inline Float3 samplePhongLobe(const Float3& axis, float exponent, float u1, float u2) {
    const float cosT = std::pow(u1, 1.0f / (exponent + 1.0f));
    const float sinT = std::sqrt(std::max(0.0f, 1.0f - cosT * cosT));
    const float phi = float(2.0 * std::numbers::pi) * u2;
    return normalize(fromLocal(axis, sinT * std::cos(phi), sinT * std::sin(phi), cosT));
}

// A sampled direction below the geometric surface is mirrored about its tangent plane: the
// lobe keeps all its energy (a white furnace stays white) at the cost of a slightly wrong
// shape at grazing angles.
inline Float3 keepAbove(const Float3& d, const Float3& ng) {
    const float c = dot(d, ng);
    return c >= 0.0f ? d : normalize(d - ng * (2.0f * c));
}

}  // namespace rtwall
