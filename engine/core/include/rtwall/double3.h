// Double3: vector maths in double precision, for the few places where float would lose what they
// need (a navigator's camera far from the origin, an area light's frame, generated geometry
// written to files). Written once here; Float3 (vec.h) stays the type of everything rendered.
#pragma once

#include <rtwall/vec.h>

#include <cmath>

namespace rtwall {

struct Double3 {
    double x = 0, y = 0, z = 0;

    Double3 operator+(const Double3& b) const { return {x + b.x, y + b.y, z + b.z}; }
    Double3 operator-(const Double3& b) const { return {x - b.x, y - b.y, z - b.z}; }
    Double3 operator*(double s) const { return {x * s, y * s, z * s}; }
    bool operator==(const Double3&) const = default;

    double dot(const Double3& b) const { return x * b.x + y * b.y + z * b.z; }
    Double3 cross(const Double3& b) const { return {y * b.z - z * b.y, z * b.x - x * b.z, x * b.y - y * b.x}; }
    double length() const { return std::sqrt(dot(*this)); }
    // The unit vector along this one; the zero vector stays zero.
    Double3 normalized() const {
        const double l = length();
        return l > 0 ? *this * (1.0 / l) : *this;
    }

    static Double3 of(const Float3& f) { return {f.x, f.y, f.z}; }
    Float3 toFloat3() const { return {float(x), float(y), float(z)}; }
};

}  // namespace rtwall
