// Float3 and the small vector maths on it, written once for every library, tool and test.
// Deliberately plain scalar code: the packet kernel gains its speed in Embree's traversal, and
// scalar shading keeps the packet and single-ray paths bit-identical.
#pragma once

#include <algorithm>
#include <cmath>

namespace rtwall {

struct Float3 {
    float x = 0, y = 0, z = 0;
    bool operator==(const Float3&) const = default;
};

inline Float3 operator+(Float3 a, Float3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Float3 operator-(Float3 a, Float3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Float3 operator-(Float3 a) { return {-a.x, -a.y, -a.z}; }
inline Float3 operator*(Float3 a, Float3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline Float3 operator*(Float3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Float3 operator*(float s, Float3 a) { return a * s; }
inline Float3& operator+=(Float3& a, Float3 b) { return a = a + b; }
inline float dot(Float3 a, Float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Float3 cross(Float3 a, Float3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Float3 a) { return std::sqrt(dot(a, a)); }
inline Float3 normalize(Float3 a) {
    float l = length(a);
    return l > 0.0f ? a * (1.0f / l) : a;
}
inline float maxAbsComponent(Float3 a) { return std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}); }
inline float maxComponent(Float3 a) { return std::max({a.x, a.y, a.z}); }
inline bool isFinite(Float3 a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }

}  // namespace rtwall
