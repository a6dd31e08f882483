// The polygon triangulation every importer uses (mesh/src/triangulate.cpp), on the shapes CAD
// exporters write (keyhole rings, stars, bridged holes, repeated corners, collinear runs, nearly
// collinear slivers) and on random and large polygons. Each result is checked three ways: the
// triangles' areas add up to the polygon's exact area (to 2e-6 of it, the float rounding of the
// corners; to 1e-9 of the area of the float-rounded polygon itself), every triangle is wound
// like the polygon, and points sampled over
// the polygon's bounds are covered by exactly as many triangles as the boundary winds round
// them (one inside, none outside and none in a hole), which no overlap or gap survives.
#include "polygon_shapes.h"

#include "../../mesh/src/triangulate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace rtwall {
namespace {

using detail::PolygonKind;
using detail::PolygonTriangulator;
using test::Point2;
using test::TestPolygon;

// A polygon as an importer holds it: one float vertex per distinct corner (so a keyhole's bridge
// corners are one vertex visited twice), at z = 0 or moved into another plane.
struct Input {
    std::vector<float> positions;
    std::vector<uint32_t> corners;
    std::vector<Point2> plane;  // per vertex: the float coordinates in the polygon's plane
};

Input makeInput(const std::vector<Point2>& corners) {
    Input in;
    std::map<std::pair<float, float>, uint32_t> index;
    for (const Point2& c : corners) {
        const auto [at, added] = index.emplace(std::pair{float(c.u), float(c.v)}, uint32_t(in.plane.size()));
        in.corners.push_back(at->second);
        if (!added) continue;
        in.plane.push_back({float(c.u), float(c.v)});
        in.positions.insert(in.positions.end(), {float(c.u), float(c.v), 0.0f});
    }
    return in;
}

struct Result {
    PolygonKind kind;
    std::vector<uint32_t> triangles;
};

Result run(const Input& in) {
    PolygonTriangulator t;
    const PolygonKind kind = t.triangulate(in.positions.data(), in.corners.data(), in.corners.size());
    return {kind, t.triangles()};
}

// The three checks of the file comment, in the polygon's plane. `samples` points.
void expectExact(const TestPolygon& p, const Input& in, const Result& r, int samples = 4000) {
    SCOPED_TRACE(p.name);
    ASSERT_EQ(r.triangles.size() % 3, 0u);
    std::vector<Point2> boundary;
    for (const uint32_t c : in.corners) boundary.push_back(in.plane[c]);
    const double sign = p.area < 0 ? -1.0 : 1.0;
    double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
    for (const Point2& q : boundary) {
        u0 = std::min(u0, q.u), u1 = std::max(u1, q.u), v0 = std::min(v0, q.v), v1 = std::max(v1, q.v);
    }
    // Nearly collinear float corners make slivers whose orientation is below double rounding
    // (1e-18 of the polygon's size squared): no way round.
    const double tiny = 1e-15 * std::max(u1 - u0, v1 - v0) * std::max(u1 - u0, v1 - v0);
    double area = 0;
    size_t wrongWay = 0;
    for (size_t k = 0; k < r.triangles.size(); k += 3) {
        const double a = test::orient(in.plane[r.triangles[k]], in.plane[r.triangles[k + 1]], in.plane[r.triangles[k + 2]]) / 2;
        area += a;
        if (a * sign < -tiny) ++wrongWay;
    }
    // The corners' float rounding moves the polygon's area by up to about 1e-6 of it; the
    // triangles cover that float polygon exactly.
    const double polygonArea = test::shoelace(boundary);
    EXPECT_NEAR(polygonArea, p.area, 2e-6 * std::fabs(p.area) + 1e-12) << "the test shape itself";
    EXPECT_NEAR(area, polygonArea, 1e-9 * std::fabs(polygonArea) + 1e-15);
    EXPECT_EQ(wrongWay, 0u) << "triangles wound against the polygon";
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> su(u0, u1), sv(v0, v1);
    int wrong = 0, insideSamples = 0;
    for (int s = 0; s < samples; ++s) {
        const Point2 q{su(rng), sv(rng)};
        const int w = test::winding(boundary, q);
        int covered = 0;
        for (size_t k = 0; k < r.triangles.size(); k += 3) {
            const Point2 a = in.plane[r.triangles[k]], b = in.plane[r.triangles[k + 1]], c = in.plane[r.triangles[k + 2]];
            const double d1 = test::orient(a, b, q), d2 = test::orient(b, c, q), d3 = test::orient(c, a, q);
            if (d1 > 0 && d2 > 0 && d3 > 0) ++covered;
            if (d1 < 0 && d2 < 0 && d3 < 0) --covered;
        }
        insideSamples += w != 0;
        if (covered != w) ++wrong;
    }
    EXPECT_EQ(wrong, 0) << "of " << samples << " points, covered as often as the boundary winds round them";
    EXPECT_GT(insideSamples, 0);
}

TestPolygon reversed(TestPolygon p) {
    std::reverse(p.corners.begin(), p.corners.end());
    p.area = -p.area;
    return p;
}

// --------------------------------------------------------------------------- the file shapes

// LightWave's ring as a 66-corner keyhole face: a fan fills it into a disc (area 3.0, five times
// the ring's); ear clipping keeps the hole.
TEST(PolygonTriangulation, KeyholeRingKeepsItsHole) {
    const TestPolygon ring = test::keyholeRing(32, 32, 1.0, 0.9, 5);
    ASSERT_EQ(ring.corners.size(), 66u);
    const Input in = makeInput(ring.corners);
    ASSERT_EQ(in.plane.size(), 64u);  // two corners visited twice
    const Result r = run(in);
    EXPECT_EQ(r.kind, PolygonKind::EarClipped);
    EXPECT_EQ(r.triangles.size(), 3u * 64u);
    expectExact(ring, in, r, 20000);
    // Nothing in the hole: every triangle has a corner on the outer circle.
    for (size_t k = 0; k < r.triangles.size(); k += 3) {
        double outer = 0;
        for (int j = 0; j < 3; ++j) outer = std::max(outer, std::hypot(in.plane[r.triangles[k + size_t(j)]].u, in.plane[r.triangles[k + size_t(j)]].v));
        EXPECT_GT(outer, 0.99) << "triangle " << k / 3 << " lies inside the inner circle";
    }
}

TEST(PolygonTriangulation, FileShapesAreExact) {
    const std::vector<TestPolygon> shapes = test::fileShapes();
    const PolygonKind expected[] = {PolygonKind::EarClipped, PolygonKind::EarClipped, PolygonKind::EarClipped,
                                    PolygonKind::EarClipped, PolygonKind::EarClipped, PolygonKind::EarClipped,
                                    PolygonKind::Fan};
    for (size_t k = 0; k < std::size(expected); ++k) {
        const Input in = makeInput(shapes[k].corners);
        const Result r = run(in);
        EXPECT_EQ(r.kind, expected[k]) << shapes[k].name;
        expectExact(shapes[k], in, r);
        // Wound the other way round, the same triangles come out wound that way too.
        const TestPolygon back = reversed(shapes[k]);
        const Input inBack = makeInput(back.corners);
        expectExact(back, inBack, run(inBack));
    }
}

// Repeated corners, corners on a straight line and a zero-width spike add no area: no triangle
// of the L, the keyhole or the spike has zero area (a fan from the first corner would give some,
// e.g. the L's (-1,-1), (0,-1), (0,-1)), and there are no more triangles than corners less two.
TEST(PolygonTriangulation, RepeatsAndCollinearCornersMakeNoZeroAreaTriangles) {
    for (const TestPolygon& p : test::fileShapes()) {
        if (p.name != "repeated" && p.name != "keyhole" && p.name != "spike") continue;
        const Input in = makeInput(p.corners);
        const Result r = run(in);
        for (size_t k = 0; k < r.triangles.size(); k += 3)
            EXPECT_NE(test::orient(in.plane[r.triangles[k]], in.plane[r.triangles[k + 1]], in.plane[r.triangles[k + 2]]), 0.0)
                << p.name << " triangle " << k / 3;
        EXPECT_LE(r.triangles.size(), 3 * (p.corners.size() - 2)) << p.name;
    }
}

TEST(PolygonTriangulation, DegenerateAndSelfIntersectingAreCountedApartAndKept) {
    const std::vector<TestPolygon> shapes = test::fileShapes();
    const TestPolygon& line = shapes[7];
    const TestPolygon& crossing = shapes[8];
    ASSERT_EQ(line.name, "degenerate");
    ASSERT_EQ(crossing.name, "self_intersecting");
    const Result flat = run(makeInput(line.corners));
    EXPECT_EQ(flat.kind, PolygonKind::Degenerate);
    EXPECT_EQ(flat.triangles, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));  // the fan, as before
    const Result bowtie = run(makeInput(crossing.corners));
    EXPECT_EQ(bowtie.kind, PolygonKind::SelfIntersecting);
    // Nothing dropped: the corners left when no ear was found are fanned.
    EXPECT_EQ(bowtie.triangles.size(), 3u * 2u);
}

// --------------------------------------------------------------------------- convex: the fan

TEST(PolygonTriangulation, ConvexPolygonsKeepTheFan) {
    std::vector<std::vector<Point2>> convex = {
        {{0, 0}, {1, 0}, {1, 1}, {0, 1}},
        {{0, 0}, {2, 0}, {2.5, 1}, {1, 2}, {-0.5, 1}},
    };
    std::vector<Point2> round;
    for (int i = 0; i < 100; ++i) round.push_back({std::cos(2 * M_PI * i / 100), std::sin(2 * M_PI * i / 100)});
    convex.push_back(round);
    for (const auto& corners : convex) {
        const Result r = run(makeInput(corners));
        EXPECT_EQ(r.kind, PolygonKind::Fan);
        std::vector<uint32_t> fan;
        for (uint32_t k = 1; k + 1 < corners.size(); ++k) fan.insert(fan.end(), {0, k, k + 1});
        EXPECT_EQ(r.triangles, fan);
    }
    // A twisted (non-planar) quad is convex in the plane that fits it best.
    const std::vector<float> twisted = {0, 0, 0, 1, 0, 0.2f, 1, 1, 0, 0, 1, 0.2f};
    const uint32_t quad[] = {0, 1, 2, 3};
    PolygonTriangulator t;
    EXPECT_EQ(t.triangulate(twisted.data(), quad, 4), PolygonKind::Fan);
    // A pentagram turns left at every corner but goes round twice: not convex.
    std::vector<Point2> pentagram;
    for (int i = 0; i < 5; ++i) pentagram.push_back({std::cos(M_PI / 2 + 4 * M_PI * i / 5), std::sin(M_PI / 2 + 4 * M_PI * i / 5)});
    EXPECT_NE(run(makeInput(pentagram)).kind, PolygonKind::Fan);
    // Three corners are a triangle, whatever they are.
    const uint32_t tri[] = {2, 0, 1};
    EXPECT_EQ(t.triangulate(twisted.data(), tri, 3), PolygonKind::Triangle);
    EXPECT_EQ(t.triangles(), (std::vector<uint32_t>{2, 0, 1}));
}

// A non-planar quad whose first edge runs along the axis the projection drops: in the plane its
// first two corners coincide, in space they do not, so both triangles stay (the fan had them too).
TEST(PolygonTriangulation, NonPlanarPolygonsLoseNoCorner) {
    const std::vector<float> p = {0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0};
    const uint32_t quad[] = {0, 1, 2, 3};
    PolygonTriangulator t;
    t.triangulate(p.data(), quad, 4);
    ASSERT_EQ(t.triangles().size(), 6u);
    for (const uint32_t corner : quad)
        EXPECT_NE(std::find(t.triangles().begin(), t.triangles().end(), corner), t.triangles().end()) << corner;
}

// --------------------------------------------------------------------------- random and large

TEST(PolygonTriangulation, RandomSimplePolygonsAreExact) {
    std::mt19937 rng(12345);
    for (int i = 0; i < 300; ++i) {
        const TestPolygon p = test::randomPolar(rng, 4 + int(rng() % 60));
        const Input in = makeInput(p.corners);
        expectExact(p, in, run(in), 1000);
    }
}

TEST(PolygonTriangulation, RandomKeyholesAndBridgedHolesAreExact) {
    std::mt19937 rng(99);
    for (int i = 0; i < 200; ++i) {
        const int n = 3 + int(rng() % 50), m = 3 + int(rng() % 50);
        // The inner polygon stays inside the outer one's inscribed circle.
        const double inner = (0.2 + 0.75 * double(rng() % 1000) / 1000) * std::cos(M_PI / n) * std::cos(M_PI / m);
        TestPolygon p = test::keyholeRing(n, m, 1.0, inner, int(rng() % size_t(n + m + 2)));
        const Input in = makeInput(p.corners);
        expectExact(p, in, run(in), 1000);
    }
    for (int i = 0; i < 100; ++i) {
        TestPolygon p = test::multiHole(rng, 1 + int(rng() % 5));
        std::rotate(p.corners.begin(), p.corners.begin() + long(rng() % p.corners.size()), p.corners.end());
        const Input in = makeInput(p.corners);
        expectExact(p, in, run(in), 1000);
    }
}

TEST(PolygonTriangulation, NearlyDegeneratePolygonsAreExact) {
    std::mt19937 rng(4242);
    for (int i = 0; i < 200; ++i) {
        // Collinear runs (three corners on each of some sides) and repeated corners.
        const TestPolygon base = test::randomPolar(rng, 4 + int(rng() % 20));
        TestPolygon p{"collinear and repeated", {}, base.area};
        for (size_t k = 0; k < base.corners.size(); ++k) {
            const Point2 a = base.corners[k], b = base.corners[(k + 1) % base.corners.size()];
            p.corners.push_back(a);
            if (rng() % 3 == 0) p.corners.push_back(a);
            if (rng() % 2 == 0)
                for (int s = 1; s < 4; ++s) p.corners.push_back({a.u + (b.u - a.u) * s / 4, a.v + (b.v - a.v) * s / 4});
        }
        // The corners on sides are rounded to float off the sides: the float polygon's own area.
        const Input in = makeInput(p.corners);
        std::vector<Point2> rounded;
        for (const uint32_t c : in.corners) rounded.push_back(in.plane[c]);
        p.area = test::shoelace(rounded);
        expectExact(p, in, run(in), 1000);
    }
    for (int i = 0; i < 100; ++i) {
        // Slivers a thousand times longer than high, with a zigzag of a tenth of that height.
        const int n = 4 + int(rng() % 30);
        TestPolygon p{"sliver", {}, 0};
        for (int k = 0; k < n; ++k) p.corners.push_back({double(k), 1e-3 * double(rng() % 100) / 1000});
        for (int k = n - 1; k >= 0; --k) p.corners.push_back({double(k) + 0.5 / n, 1e-3 + 1e-4 * double(rng() % 1000) / 1000});
        const Input in = makeInput(p.corners);
        std::vector<Point2> rounded;
        for (const uint32_t c : in.corners) rounded.push_back(in.plane[c]);
        p.area = test::shoelace(rounded);
        expectExact(p, in, run(in), 1000);
    }
}

// Large polygons go through the grid of blocking corners (more than 32 of them): still exact.
TEST(PolygonTriangulation, LargePolygonsAreExact) {
    const TestPolygon shapes[] = {test::keyholeRing(2000, 1500, 1.0, 0.95, 17), test::star(1000, 1.0, 0.6),
                                  test::spiral(2000, 4.0), test::comb(500)};
    for (const TestPolygon& p : shapes) {
        const Input in = makeInput(p.corners);
        const Result r = run(in);
        EXPECT_EQ(r.kind, PolygonKind::EarClipped) << p.name;
        expectExact(p, in, r, 300);
    }
}

// Any plane, away from the origin: the ring turned into a random plane through (10, -20, 5).
TEST(PolygonTriangulation, KeyholeRingInAnyPlane) {
    const TestPolygon ring = test::keyholeRing(32, 32, 1.0, 0.9, 5);
    std::mt19937 rng(3);
    std::normal_distribution<double> normal;
    for (int trial = 0; trial < 50; ++trial) {
        // An orthonormal frame (e1, e2, e1 x e2) from two random vectors.
        const test::PlaneAxes axes = test::randomPlane(rng, normal);
        const double(&e1)[3] = axes.e1;
        const double(&e2)[3] = axes.e2;
        const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const double origin[3] = {10, -20, 5};
        Input in = makeInput(ring.corners);
        for (size_t v = 0; v < in.plane.size(); ++v)
            for (int k = 0; k < 3; ++k)
                in.positions[3 * v + size_t(k)] = float(origin[k] + in.plane[v].u * e1[k] + in.plane[v].v * e2[k]);
        const Result r = run(in);
        EXPECT_EQ(r.kind, PolygonKind::EarClipped);
        // In 3D: the areas along the ring's normal add up, and every triangle faces the same way.
        double area = 0;
        for (size_t k = 0; k < r.triangles.size(); k += 3) {
            const float* a = &in.positions[3 * r.triangles[k]];
            const float* b = &in.positions[3 * r.triangles[k + 1]];
            const float* c = &in.positions[3 * r.triangles[k + 2]];
            const double ab[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
            const double ac[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
            const double along = ((ab[1] * ac[2] - ab[2] * ac[1]) * n[0] + (ab[2] * ac[0] - ab[0] * ac[2]) * n[1] +
                                  (ab[0] * ac[1] - ab[1] * ac[0]) * n[2]) / 2;
            EXPECT_GT(along, 0) << "trial " << trial << " triangle " << k / 3;
            area += along;
        }
        EXPECT_NEAR(area, ring.area, 1e-5 * ring.area) << "trial " << trial;
    }
}

}  // namespace
}  // namespace rtwall
