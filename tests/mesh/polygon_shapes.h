// Test polygons, shared by the triangulation tests, the importer tests, the render test and
// rtwall_bench_polygons: the shapes that tests/data/meshes/make_polygon_meshes.py writes into
// every format that carries polygons (the script has its own copy of them, so that a writer and
// a reader cannot share a bug), and generators of random and large ones.
#pragma once

#include "rtwall/mesh.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace rtwall::test {

struct Point2 {
    double u = 0, v = 0;
    bool operator==(const Point2&) const = default;
};

struct TestPolygon {
    std::string name;
    std::vector<Point2> corners;  // counter-clockwise (area > 0); a keyhole's bridge corners appear twice
    double area = 0;              // exact, from the construction (not from the corners)
};

// Twice the signed area of (a, b, p).
inline double orient(Point2 a, Point2 b, Point2 p) { return (b.u - a.u) * (p.v - a.v) - (b.v - a.v) * (p.u - a.u); }

inline double shoelace(const std::vector<Point2>& p) {
    double a = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        const Point2 s = p[i], t = p[(i + 1) % p.size()];
        a += s.u * t.v - s.v * t.u;
    }
    return a / 2;
}

// How often the boundary winds round q (0 outside, 1 inside a counter-clockwise polygon, 0 in a
// keyhole's hole).
inline int winding(const std::vector<Point2>& p, Point2 q) {
    int w = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        const Point2 a = p[i], b = p[(i + 1) % p.size()];
        if (a.v <= q.v) {
            if (b.v > q.v && orient(a, b, q) > 0) ++w;
        } else if (b.v <= q.v && orient(a, b, q) < 0) {
            --w;
        }
    }
    return w;
}

// A ring as CAD exporters write it (LightWave's concave_polygon.obj): one face that goes round
// the outer circle (n corners) back to its first corner, crosses to the inner circle, goes round
// that (m corners) the other way back to its first corner, and closes across the same bridge.
// The corner list starts `start` corners into the outer circle, as LightWave's does.
inline TestPolygon keyholeRing(int n, int m, double outer, double inner, int start = 0) {
    TestPolygon p;
    p.name = "ring";
    const double top = M_PI / 2;
    std::vector<Point2> c;
    for (int i = 0; i <= n; ++i) c.push_back({outer * std::cos(top + 2 * M_PI * (i % n) / n), outer * std::sin(top + 2 * M_PI * (i % n) / n)});
    for (int i = 0; i <= m; ++i) c.push_back({inner * std::cos(top - 2 * M_PI * (i % m) / m), inner * std::sin(top - 2 * M_PI * (i % m) / m)});
    // Rotate so that the list starts inside the outer circle; the boundary stays the same.
    for (size_t k = 0; k < c.size(); ++k) p.corners.push_back(c[(k + size_t(start)) % c.size()]);
    p.area = 0.5 * n * outer * outer * std::sin(2 * M_PI / n) - 0.5 * m * inner * inner * std::sin(2 * M_PI / m);
    return p;
}

// k points, alternating between radius `outer` and `inner`.
inline TestPolygon star(int k, double outer, double inner) {
    TestPolygon p;
    p.name = "star";
    for (int i = 0; i < 2 * k; ++i) {
        const double a = M_PI / 2 + M_PI * i / k, r = i % 2 ? inner : outer;
        p.corners.push_back({r * std::cos(a), r * std::sin(a)});
    }
    p.area = k * outer * inner * std::sin(M_PI / k);
    return p;
}

// The shapes of tests/data/meshes/polygons.*, in file order; where each lies in the files is
// placeShape's business. The last two have no area to check: a degenerate one (every corner on
// a line) and one whose boundary crosses itself.
inline std::vector<TestPolygon> fileShapes() {
    std::vector<TestPolygon> s;
    s.push_back(keyholeRing(32, 32, 1.0, 0.9, 5));
    s.push_back(star(5, 1.0, 0.4));
    // A square with a square hole, bridged from the middle of the outer left side (a corner on a
    // straight side, as is the bridge's end on the hole's side).
    s.push_back({"keyhole",
                 {{-1, 0}, {-1, -1}, {1, -1}, {1, 1}, {-1, 1}, {-1, 0}, {-0.5, 0}, {-0.5, 0.5}, {0.5, 0.5}, {0.5, -0.5}, {-0.5, -0.5}, {-0.5, 0}},
                 3.0});
    // An L with two repeated corners and two corners on straight sides.
    s.push_back({"repeated",
                 {{-1, -1}, {0, -1}, {0, -1}, {1, -1}, {1, 0}, {0.5, 0}, {0, 0}, {0, 1}, {-1, 1}, {-1, 1}, {-1, 0}},
                 3.0});
    // A sliver 2 long and 0.002 high whose top zigzags by 0.0002: nearly collinear corners, and
    // concave at every other one.
    {
        TestPolygon p{"sliver", {{-1, 0}, {1, 0}}, 2 * 0.0021};
        for (int i = 0; i <= 40; ++i) p.corners.push_back({1 - i / 20.0, 0.002 + (i % 2 ? 0.0002 : 0.0)});
        s.push_back(p);
    }
    // A square with a spike of no width: out along an edge and back the same way.
    s.push_back({"spike", {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0}, {0.9, 0}, {0.5, 0}, {0.5, 0.5}, {-0.5, 0.5}}, 1.0});
    {
        TestPolygon p{"hexagon", {}, 1.5 * std::sqrt(3.0)};
        for (int i = 0; i < 6; ++i) p.corners.push_back({std::cos(M_PI * i / 3), std::sin(M_PI * i / 3)});
        s.push_back(p);
    }
    s.push_back({"degenerate", {{-1, 0}, {0, 0}, {1, 0}, {0.5, 0}}, 0.0});
    s.push_back({"self_intersecting", {{-1, -1}, {1, 1}, {1, -1}, {-1, 0.5}}, NAN});
    return s;
}

// Where shape k of fileShapes() lies in the files: the ring in the plane x = -1.25 (seen from +x,
// the plane of LightWave's ring), the star tilted 20 degrees about y in the plane through z = 1,
// every other shape k in the plane z = k. Every corner is within 1 of its plane's centre.
inline Float3 placeShape(size_t k, Point2 p) {
    if (k == 0) return {-1.25f, float(p.u), float(p.v)};
    if (k == 1) {
        const double t = 20 * M_PI / 180;
        return {float(p.u * std::cos(t)), float(p.v), float(1 + p.u * std::sin(t))};
    }
    return {float(p.u), float(p.v), float(k)};
}

// The shape a point of the files belongs to, and its coordinates in that shape's plane.
inline size_t shapeOf(Float3 p) { return p.x < -1.1f ? 0 : size_t(std::lround(p.z)); }
inline Point2 unplaceShape(size_t k, Float3 p) {
    if (k == 0) return {p.y, p.z};
    if (k == 1) {
        const double t = 20 * M_PI / 180;
        return {p.x * std::cos(t) + (p.z - 1) * std::sin(t), p.y};
    }
    return {p.x, p.y};
}

// A random plane's orthonormal axes (e1, e2): two vectors of `normal` samples, e2 made
// perpendicular to e1 (Gram-Schmidt), both of unit length.
struct PlaneAxes {
    double e1[3], e2[3];
};
inline PlaneAxes randomPlane(std::mt19937& rng, std::normal_distribution<double>& normal) {
    PlaneAxes a{{normal(rng), normal(rng), normal(rng)}, {normal(rng), normal(rng), normal(rng)}};
    const double l1 = std::sqrt(a.e1[0] * a.e1[0] + a.e1[1] * a.e1[1] + a.e1[2] * a.e1[2]);
    for (double& x : a.e1) x /= l1;
    const double d = a.e1[0] * a.e2[0] + a.e1[1] * a.e2[1] + a.e1[2] * a.e2[2];
    for (int k = 0; k < 3; ++k) a.e2[k] -= d * a.e1[k];
    const double l2 = std::sqrt(a.e2[0] * a.e2[0] + a.e2[1] * a.e2[1] + a.e2[2] * a.e2[2]);
    for (double& x : a.e2) x /= l2;
    return a;
}

// A star-shaped polygon with n corners at random radii in [0.1, 1]: simple, mostly concave.
inline TestPolygon randomPolar(std::mt19937& rng, int n) {
    std::uniform_real_distribution<double> radius(0.1, 1.0);
    TestPolygon p;
    p.name = "polar";
    for (int i = 0; i < n; ++i) {
        const double a = 2 * M_PI * i / n, r = radius(rng);
        p.corners.push_back({r * std::cos(a), r * std::sin(a)});
    }
    p.area = shoelace(p.corners);
    return p;
}

// A rectangle with `holes` round holes, each bridged to the bottom side.
inline TestPolygon multiHole(std::mt19937& rng, int holes) {
    TestPolygon p;
    p.name = "holes";
    const double width = 3.0 * holes + 1;
    p.corners.push_back({0, -2});
    double area = width * 4;
    for (int h = 0; h < holes; ++h) {
        const double cx = 3.0 * h + 2;
        const int m = 8 + int(rng() % 8);
        p.corners.push_back({cx, -2});
        for (int i = 0; i <= m; ++i) {
            const double a = -M_PI / 2 - 2 * M_PI * (i % m) / m;
            p.corners.push_back({cx + std::cos(a), std::sin(a)});
        }
        p.corners.push_back({cx, -2});
        area -= 0.5 * m * std::sin(2 * M_PI / m);
    }
    p.corners.push_back({width, -2});
    p.corners.push_back({width, 2});
    p.corners.push_back({0, 2});
    p.area = area;
    return p;
}

// A strip wound `turns` times round the origin, n corners along each side.
inline TestPolygon spiral(int n, double turns) {
    TestPolygon p;
    p.name = "spiral";
    const double step = 2 * M_PI * turns / n;
    for (int i = 0; i < n; ++i) {
        const double a = step * i, r = 1.5 + 0.5 * a;
        p.corners.push_back({r * std::cos(a), r * std::sin(a)});
    }
    for (int i = n - 1; i >= 0; --i) {
        const double a = step * i, r = 1.0 + 0.5 * a;
        p.corners.push_back({r * std::cos(a), r * std::sin(a)});
    }
    p.area = shoelace(p.corners);
    return p;
}

// A comb: a bar with `teeth` pointed teeth on top.
inline TestPolygon comb(int teeth) {
    TestPolygon p;
    p.name = "comb";
    p.corners = {{0, 0}, {2.0 * teeth, 0}};
    for (int t = teeth - 1; t >= 0; --t) {
        p.corners.push_back({2.0 * t + 2, 1});
        p.corners.push_back({2.0 * t + 1.5, 5});
        p.corners.push_back({2.0 * t + 1, 1});
    }
    p.corners.push_back({0, 1});
    p.area = 2.0 * teeth + teeth * 0.5 * 1.0 * 4;
    return p;
}

}  // namespace rtwall::test
