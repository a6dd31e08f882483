// rtwall_bench_polygons: rtwall's polygon triangulation (mesh/src/triangulate.cpp, the one every
// importer uses) against the library alternative, VTK's vtkPolygon::Triangulate (ear cutting in
// VTK's CommonDataModel). Prints JSON: for each family of test polygons (tests/mesh/polygon_shapes.h)
// how many each method triangulates exactly (areas add up to the polygon's to 1e-9, every
// triangle wound like the polygon, 200 sampled points covered as often as the boundary winds
// round them), and the time per polygon on a million quads (the convex fast path), on concave
// polygons, and on single polygons of up to two million corners. Timings are no test: run it by
// hand (`build/tools/rtwall_bench_polygons [--quick]`).
#include "polygon_shapes.h"
#include "triangulate.h"

#include <toml++/toml.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolygon.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace {

using rtwall::detail::PolygonTriangulator;
using rtwall::test::Point2;
using rtwall::test::TestPolygon;

struct Input {
    std::vector<float> positions;
    std::vector<uint32_t> corners;
    std::vector<Point2> plane;
};

// One float vertex per distinct corner, at z = 0, or in the plane spanned by e1, e2 through o.
Input makeInput(const TestPolygon& p, const double* o = nullptr, const double* e1 = nullptr, const double* e2 = nullptr) {
    Input in;
    std::map<std::pair<float, float>, uint32_t> index;
    for (const Point2& c : p.corners) {
        const Point2 rounded{float(c.u), float(c.v)};
        const auto [at, added] = index.emplace(std::pair{float(c.u), float(c.v)}, uint32_t(in.plane.size()));
        in.corners.push_back(at->second);
        if (!added) continue;
        in.plane.push_back(rounded);
        for (int k = 0; k < 3; ++k)
            in.positions.push_back(o ? float(o[k] + rounded.u * e1[k] + rounded.v * e2[k]) : float(k == 0 ? rounded.u : k == 1 ? rounded.v : 0));
    }
    return in;
}

using Method = std::function<bool(const Input&, std::vector<uint32_t>&)>;

bool rtwallMethod(const Input& in, std::vector<uint32_t>& out) {
    static PolygonTriangulator t;
    t.triangulate(in.positions.data(), in.corners.data(), in.corners.size());
    out = t.triangles();
    return true;
}

bool vtkMethod(const Input& in, std::vector<uint32_t>& out) {
    static vtkNew<vtkPolygon> polygon;
    static vtkNew<vtkIdList> ids;
    const auto n = vtkIdType(in.corners.size());
    polygon->GetPointIds()->SetNumberOfIds(n);
    polygon->GetPoints()->SetNumberOfPoints(n);
    for (vtkIdType i = 0; i < n; ++i) {
        const float* p = &in.positions[3 * in.corners[size_t(i)]];
        polygon->GetPointIds()->SetId(i, vtkIdType(in.corners[size_t(i)]));
        polygon->GetPoints()->SetPoint(i, p[0], p[1], p[2]);
    }
    ids->Reset();
    const bool ok = polygon->Triangulate(ids) != 0;
    out.clear();
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) out.push_back(in.corners[size_t(ids->GetId(k))]);
    return ok;
}

bool exact(const Input& in, const std::vector<uint32_t>& tris, std::mt19937& rng) {
    std::vector<Point2> boundary;
    for (const uint32_t c : in.corners) boundary.push_back(in.plane[c]);
    const double polygonArea = rtwall::test::shoelace(boundary);
    double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
    for (const Point2& q : boundary) u0 = std::min(u0, q.u), u1 = std::max(u1, q.u), v0 = std::min(v0, q.v), v1 = std::max(v1, q.v);
    // As in triangulate_test.cpp: slivers of nearly collinear float corners have an orientation
    // below double rounding, so only a triangle wound the wrong way by more than that counts.
    const double tiny = 1e-15 * std::max(u1 - u0, v1 - v0) * std::max(u1 - u0, v1 - v0);
    double area = 0;
    for (size_t k = 0; k + 2 < tris.size(); k += 3) {
        const double a = rtwall::test::orient(in.plane[tris[k]], in.plane[tris[k + 1]], in.plane[tris[k + 2]]) / 2;
        if (a * (polygonArea < 0 ? -1 : 1) < -tiny) return false;
        area += a;
    }
    if (std::fabs(area - polygonArea) > 1e-9 * std::fabs(polygonArea)) return false;
    std::uniform_real_distribution<double> su(u0, u1), sv(v0, v1);
    for (int s = 0; s < 200; ++s) {
        const Point2 q{su(rng), sv(rng)};
        int covered = 0;
        for (size_t k = 0; k + 2 < tris.size(); k += 3) {
            const Point2 a = in.plane[tris[k]], b = in.plane[tris[k + 1]], c = in.plane[tris[k + 2]];
            const double d1 = rtwall::test::orient(a, b, q), d2 = rtwall::test::orient(b, c, q), d3 = rtwall::test::orient(c, a, q);
            covered += (d1 > 0 && d2 > 0 && d3 > 0) - (d1 < 0 && d2 < 0 && d3 < 0);
        }
        if (covered != rtwall::test::winding(boundary, q)) return false;
    }
    return true;
}

double seconds(const std::function<void()>& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

using Methods = std::pair<const char*, Method>[2];
using Families = std::vector<std::pair<std::string, std::vector<Input>>>;

// Families of polygons with a known exact triangulation, `count` of each random kind (from rng,
// in a fixed order), and the LightWave ring in `count` random planes through (10, -20, 5).
Families makeFamilies(std::mt19937& rng, int count, std::vector<Input>& turned) {
    Families families;
    {
        std::vector<Input> shapes;
        const auto file = rtwall::test::fileShapes();
        for (size_t k = 0; k < 7; ++k) shapes.push_back(makeInput(file[k]));
        families.push_back({"file_shapes", shapes});
    }
    std::vector<Input> polar, rings, holes, nearlyDegenerate;
    for (int i = 0; i < count; ++i) {
        polar.push_back(makeInput(rtwall::test::randomPolar(rng, 4 + int(rng() % 60))));
        const int n = 3 + int(rng() % 50), m = 3 + int(rng() % 50);
        const double inner = (0.2 + 0.75 * double(rng() % 1000) / 1000) * std::cos(M_PI / n) * std::cos(M_PI / m);
        rings.push_back(makeInput(rtwall::test::keyholeRing(n, m, 1.0, inner, int(rng() % size_t(n + m + 2)))));
        TestPolygon h = rtwall::test::multiHole(rng, 1 + int(rng() % 5));
        std::rotate(h.corners.begin(), h.corners.begin() + long(rng() % h.corners.size()), h.corners.end());
        holes.push_back(makeInput(h));
        const TestPolygon base = rtwall::test::randomPolar(rng, 4 + int(rng() % 20));
        TestPolygon d{"nearly_degenerate", {}, 0};
        for (size_t k = 0; k < base.corners.size(); ++k) {
            const Point2 a = base.corners[k], b = base.corners[(k + 1) % base.corners.size()];
            d.corners.push_back(a);
            if (rng() % 3 == 0) d.corners.push_back(a);
            if (rng() % 2 == 0)
                for (int s = 1; s < 4; ++s) d.corners.push_back({a.u + (b.u - a.u) * s / 4, a.v + (b.v - a.v) * s / 4});
        }
        nearlyDegenerate.push_back(makeInput(d));
        std::normal_distribution<double> g;
        const rtwall::test::PlaneAxes axes = rtwall::test::randomPlane(rng, g);
        const double o[3] = {10, -20, 5};
        turned.push_back(makeInput(rtwall::test::keyholeRing(32, 32, 1.0, 0.9, 5), o, axes.e1, axes.e2));
    }
    families.push_back({"random_simple", polar});
    families.push_back({"keyhole_rings", rings});
    families.push_back({"bridged_holes", holes});
    families.push_back({"repeated_and_collinear", nearlyDegenerate});
    return families;
}

// How many polygons of each family each method triangulates exactly, and how many it said it
// could not.
toml::table correctness(const Families& families, const std::vector<Input>& turned, const Methods& methods) {
    toml::table table;
    for (const auto& [name, inputs] : families) {
        toml::table row;
        for (const auto& [method, triangulate] : methods) {
            int good = 0, reportedFailure = 0;
            std::vector<uint32_t> tris;
            std::mt19937 sampler(1);
            for (const Input& in : inputs) {
                reportedFailure += !triangulate(in, tris);
                good += exact(in, tris, sampler);
            }
            row.insert(method, toml::table{{"polygons", int64_t(inputs.size())}, {"exact", good},
                                           {"reported_failure", reportedFailure}});
        }
        table.insert(name, row);
    }
    // In a random plane the float corners are no longer coplanar: checked by area along the normal.
    toml::table row;
    for (const auto& [method, triangulate] : methods) {
        int good = 0;
        std::vector<uint32_t> tris;
        const double expected = rtwall::test::keyholeRing(32, 32, 1.0, 0.9, 5).area;
        for (const Input& in : turned) {
            triangulate(in, tris);
            double area = 0;
            for (size_t k = 0; k + 2 < tris.size(); k += 3) {
                const float* a = &in.positions[3 * tris[k]];
                const float* b = &in.positions[3 * tris[k + 1]];
                const float* c = &in.positions[3 * tris[k + 2]];
                const double ab[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
                const double ac[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
                const double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
                area += std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 2;
            }
            good += std::fabs(area - expected) < 1e-5 * expected;
        }
        row.insert(method, toml::table{{"polygons", int64_t(turned.size())}, {"exact", good}});
    }
    table.insert("ring_in_random_planes", row);
    return table;
}

// Time per polygon: a million quads of a gently curved grid, and concave 16-gons (from rng).
toml::table speed(bool quick, std::mt19937& rng, const Methods& methods) {
    toml::table table;
    const int grid = quick ? 300 : 1000;
    Input quad;
    quad.corners = {0, 1, 2, 3};
    std::vector<Input> quads;
    for (int j = 0; j < grid; ++j)
        for (int i = 0; i < grid; ++i) {
            Input q = quad;
            for (const auto& [di, dj] : {std::pair{0, 0}, {1, 0}, {1, 1}, {0, 1}})
                q.positions.insert(q.positions.end(), {float(i + di), float(j + dj), 0.001f * float(((i + di) * 7 + (j + dj) * 13) % 5)});
            quads.push_back(std::move(q));
        }
    std::vector<Input> concave;
    for (int i = 0; i < (quick ? 10000 : 100000); ++i) concave.push_back(makeInput(rtwall::test::randomPolar(rng, 16)));
    for (const auto& [method, triangulate] : methods) {
        std::vector<uint32_t> tris;
        const double tq = seconds([&] {
            for (const Input& q : quads) triangulate(q, tris);
        });
        const double tc = seconds([&] {
            for (const Input& c : concave) triangulate(c, tris);
        });
        table.insert(method, toml::table{{"quads", int64_t(quads.size())},
                                         {"ns_per_quad", 1e9 * tq / double(quads.size())},
                                         {"concave_16gons", int64_t(concave.size())},
                                         {"ns_per_concave_16gon", 1e9 * tc / double(concave.size())}});
    }
    return table;
}

// Single large polygons (VTK only up to 20,000 corners: it takes seconds there already).
toml::array largePolygons(bool quick, const Methods& methods) {
    toml::array large;
    for (const int n : quick ? std::vector<int>{1000, 10000} : std::vector<int>{1000, 10000, 100000, 1000000}) {
        const TestPolygon shapes[] = {rtwall::test::keyholeRing(n, n, 1.0, 0.99), rtwall::test::star(n, 1.0, 0.5),
                                      rtwall::test::spiral(n, 10.0), rtwall::test::comb(n)};
        for (const TestPolygon& p : shapes) {
            const Input in = makeInput(p);
            toml::table row{{"shape", p.name}, {"corners", int64_t(in.corners.size())}};
            for (const auto& [method, triangulate] : methods) {
                if (std::strcmp(method, "vtk") == 0 && in.corners.size() > 20000) continue;
                std::vector<uint32_t> tris;
                row.insert(std::string(method) + "_seconds", seconds([&] { triangulate(in, tris); }));
                row.insert(std::string(method) + "_triangles", int64_t(tris.size() / 3));
            }
            large.push_back(row);
        }
    }
    return large;
}

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
    const Methods methods = {{"rtwall", rtwallMethod}, {"vtk", vtkMethod}};
    std::mt19937 rng(2024);
    std::vector<Input> turned;
    const Families families = makeFamilies(rng, quick ? 50 : 500, turned);
    toml::table out;
    out.insert("correctness", correctness(families, turned, methods));
    out.insert("speed", speed(quick, rng, methods));
    out.insert("large_polygons", largePolygons(quick, methods));
    std::cout << toml::json_formatter{out} << "\n";
    return 0;
}
