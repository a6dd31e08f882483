// Geometry checks shared by the mesh tests.
#pragma once

#include "rtwall/mesh.h"
#include "rtwall/vec.h"

#include <cmath>

namespace rtwall::test {

inline Float3 corner(const TriangleMesh& m, size_t t, int k) { return m.position(m.indices()[3 * t + size_t(k)]); }

// Signed volume by the divergence theorem: exact for a closed mesh, and positive only if every
// triangle is wound counter-clockwise seen from outside. Summed in double over float terms.
inline double signedVolume(const TriangleMesh& m) {
    double v = 0;
    for (size_t t = 0; t < m.triangleCount(); ++t)
        v += double(dot(corner(m, t, 0), cross(corner(m, t, 1), corner(m, t, 2)))) / 6.0;
    return v;
}

inline Float3 geometricNormal(const TriangleMesh& m, size_t t) {
    return cross(corner(m, t, 1) - corner(m, t, 0), corner(m, t, 2) - corner(m, t, 0));
}

}  // namespace rtwall::test
