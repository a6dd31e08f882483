// Geometry checks shared by the mesh tests.
#pragma once

#include "rtwall/mesh.h"

#include <cmath>

namespace rtwall::test {

inline Float3 sub(Float3 a, Float3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline double dot(Float3 a, Float3 b) { return double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z; }
inline Float3 cross(Float3 a, Float3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(Float3 a) { return std::sqrt(dot(a, a)); }

inline Float3 corner(const TriangleMesh& m, size_t t, int k) { return m.position(m.indices()[3 * t + size_t(k)]); }

// Signed volume by the divergence theorem: exact for a closed mesh, and positive only if every
// triangle is wound counter-clockwise seen from outside.
inline double signedVolume(const TriangleMesh& m) {
    double v = 0;
    for (size_t t = 0; t < m.triangleCount(); ++t)
        v += dot(corner(m, t, 0), cross(corner(m, t, 1), corner(m, t, 2))) / 6.0;
    return v;
}

inline Float3 geometricNormal(const TriangleMesh& m, size_t t) {
    return cross(sub(corner(m, t, 1), corner(m, t, 0)), sub(corner(m, t, 2), corner(m, t, 0)));
}

}  // namespace rtwall::test
