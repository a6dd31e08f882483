// Polygons through every importer (issue 15): tests/data/meshes/polygons.* hold the same nine
// faces (make_polygon_meshes.py; the shapes are test::fileShapes()) in each format that carries
// polygons. Whatever library reads the file, each face must come out as triangles that cover it
// exactly: the triangles of a face add up to its exact area (to 2e-6 of it: float corners), all
// face the way the face does, and points sampled over it are covered once inside and never
// outside or in a hole. Also the Blender 2.47 PLY header line, and what stays refused.
#include "polygon_shapes.h"
#include "mesh_test_util.h"
#include "rtwall/mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;
using test::Point2;

const fs::path kMeshes = fs::path(RTWALL_TEST_DATA_DIR) / "meshes";

fs::path writeTemp(const std::string& name, const std::string& bytes) {
    const fs::path file = test::tempFolder("rtwall_polygon_import_tests") / name;
    test::writeBytes(file, bytes);
    return file;
}

struct Triangle2 {
    Point2 a, b, c;
};

// The mesh's triangles sorted by the face they came from, in that face's plane coordinates.
std::vector<std::vector<Triangle2>> trianglesByShape(const TriangleMesh& mesh, size_t shapes) {
    std::vector<std::vector<Triangle2>> out(shapes);
    const std::array<double, 3>& o = mesh.origin();
    auto world = [&](uint32_t v) {
        const Float3 p = mesh.position(v);
        return Float3{float(p.x + o[0]), float(p.y + o[1]), float(p.z + o[2])};
    };
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const Float3 a = world(mesh.indices()[3 * t]), b = world(mesh.indices()[3 * t + 1]), c = world(mesh.indices()[3 * t + 2]);
        const size_t k = test::shapeOf({(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3, (a.z + b.z + c.z) / 3});
        EXPECT_LT(k, shapes) << "triangle " << t << " lies in no shape's plane";
        if (k >= shapes) continue;
        EXPECT_EQ(test::shapeOf(a), k);
        EXPECT_EQ(test::shapeOf(b), k);
        EXPECT_EQ(test::shapeOf(c), k);
        out[k].push_back({test::unplaceShape(k, a), test::unplaceShape(k, b), test::unplaceShape(k, c)});
    }
    return out;
}

class PolygonImport : public ::testing::TestWithParam<const char*> {};

TEST_P(PolygonImport, EveryFaceIsCoveredExactly) {
    ImportReport report;
    const TriangleMesh mesh = loadMesh(kMeshes / GetParam(), &report);
    const std::vector<test::TestPolygon> shapes = test::fileShapes();
    // Seven faces with area: six ear-clipped (ring, star, keyhole, L with repeats, sliver, spike)
    // and the convex hexagon fanned; the degenerate one fanned into two zero-area triangles; the
    // self-intersecting one fanned where ear clipping ran out of ears.
    EXPECT_EQ(report.polygonsTriangulated, 9u);
    EXPECT_EQ(report.polygonsFanned, 1u);
    EXPECT_EQ(report.polygonsEarClipped, 6u);
    EXPECT_EQ(report.polygonsDegenerate, 1u);
    EXPECT_EQ(report.polygonsSelfIntersecting, 1u);
    EXPECT_EQ(report.degenerateTriangles, 2u);

    const auto byShape = trianglesByShape(mesh, shapes.size());
    for (size_t k = 0; k < 7; ++k) {
        const test::TestPolygon& shape = shapes[k];
        SCOPED_TRACE(shape.name);
        double area = 0;
        for (const Triangle2& t : byShape[k]) {
            const double a = test::orient(t.a, t.b, t.c) / 2;
            EXPECT_GT(a, 0) << "a triangle wound against its face, or of no area";
            area += a;
            // No triangle outside the face: its centroid is inside (not in a hole).
            const Point2 centroid{(t.a.u + t.b.u + t.c.u) / 3, (t.a.v + t.b.v + t.c.v) / 3};
            EXPECT_EQ(test::winding(shape.corners, centroid), 1) << "centroid " << centroid.u << ", " << centroid.v;
        }
        EXPECT_NEAR(area, shape.area, 2e-6 * shape.area);
        // Coverage: points over the face's bounds are covered once inside, never elsewhere.
        double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
        for (const Point2& q : shape.corners) {
            u0 = std::min(u0, q.u), u1 = std::max(u1, q.u), v0 = std::min(v0, q.v), v1 = std::max(v1, q.v);
        }
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> su(u0, u1), sv(v0, v1);
        int wrong = 0, inside = 0;
        for (int s = 0; s < 3000; ++s) {
            const Point2 q{su(rng), sv(rng)};
            int covered = 0;
            for (const Triangle2& t : byShape[k])
                covered += test::orient(t.a, t.b, q) > 0 && test::orient(t.b, t.c, q) > 0 && test::orient(t.c, t.a, q) > 0;
            const int w = test::winding(shape.corners, q);
            inside += w;
            wrong += covered != w;
        }
        EXPECT_EQ(wrong, 0) << "sample points covered other than once inside, never outside";
        EXPECT_GT(inside, 0);
    }
    EXPECT_EQ(byShape[7].size(), 2u);  // degenerate: kept and counted, not dropped
    EXPECT_EQ(byShape[8].size(), 2u);  // self-intersecting: fanned
}

INSTANTIATE_TEST_SUITE_P(Formats, PolygonImport,
                         ::testing::Values("polygons.obj", "polygons.off", "polygons_ascii.ply", "polygons_le.ply",
                                           "polygons.vtk", "polygons.vtp", "polygons.vtu", "polygons.wrl"),
                         test::FileCaseName{});

// OpenMesh's OBJ reader keeps only the first visit of each vertex in a face, which cut the
// ring's hole open (a gap of one of its 32 segments); the corners are put back. Where the two
// visits of a bridge corner name different texture coordinates, each visit keeps its own.
TEST(PolygonImport, ObjKeyholeKeepsBothVisitsWithTheirTextureCoordinates) {
    // The keyhole square of fileShapes(), with vt: every vertex its (u, v) = its position, but
    // the second visit of bridge corner 1 (at (-1, 0)) has its own vt 9.
    const std::string obj =
        "v -1 0 0\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv -0.5 0 0\nv -0.5 0.5 0\nv 0.5 0.5 0\nv 0.5 -0.5 0\nv -0.5 -0.5 0\n"
        "vt -1 0\nvt -1 -1\nvt 1 -1\nvt 1 1\nvt -1 1\nvt -0.5 0\nvt -0.5 0.5\nvt 0.5 0.5\nvt 0.5 -0.5\nvt -0.5 -0.5\nvt 0.25 0.75\n"
        "f 1/1 2/2 3/3 4/4 5/5 1/11 6/6 7/7 8/8 9/9 10/10 6/6\n";
    ImportReport report;
    const TriangleMesh mesh = loadMesh(writeTemp("keyhole_uv.obj", obj), &report);
    EXPECT_EQ(report.polygonsEarClipped, 1u);
    EXPECT_EQ(report.seamVerticesSplit, 1u);
    ASSERT_TRUE(mesh.hasUVs());
    EXPECT_EQ(mesh.vertexCount(), 11u);
    double area = 0;
    bool copyUsed = false;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t* i = mesh.indices() + 3 * t;
        const Float3 a = mesh.position(i[0]), b = mesh.position(i[1]), c = mesh.position(i[2]);
        area += ((b.x - a.x) * double(c.y - a.y) - (b.y - a.y) * double(c.x - a.x)) / 2;
        for (int k = 0; k < 3; ++k) copyUsed = copyUsed || i[k] == 10;
    }
    EXPECT_DOUBLE_EQ(area, 3.0);
    EXPECT_TRUE(copyUsed);
    EXPECT_EQ(mesh.uvs()[2 * 10], 0.25f);
    EXPECT_EQ(mesh.uvs()[2 * 10 + 1], 0.75f);
    EXPECT_EQ(mesh.uvs()[0], -1.0f);
}

// --------------------------------------------------------------------------- PLY header lines

// loadMesh with stderr captured into `err`, also when it throws (a capture left running would
// swallow the test's own failure report).
TriangleMesh loadCapturingStderr(const fs::path& file, ImportReport* report, std::string& err) {
    ::testing::internal::CaptureStderr();
    try {
        TriangleMesh mesh = loadMesh(file, report);
        err = ::testing::internal::GetCapturedStderr();
        return mesh;
    } catch (...) {
        err = ::testing::internal::GetCapturedStderr();
        throw;
    }
}

std::string tetPly(const std::string& extraHeaderLine) {
    return "ply\nformat ascii 1.0\n" + extraHeaderLine + "element vertex 4\nproperty float x\nproperty float y\n"
           "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
}

// assimp's Wuson.ply (Blender 2.47) has this line in its header; it lays nothing out, so it is
// skipped with one warning that names the file and the line.
TEST(PlyHeader, Blender247LineIsSkippedWithOneWarning) {
    const fs::path file = kMeshes / "blender_247.ply";
    ImportReport report;
    std::string err;
    const TriangleMesh mesh = loadCapturingStderr(file, &report, err);
    EXPECT_EQ(mesh.triangleCount(), 4u);
    ASSERT_EQ(report.warnings.size(), 1u);
    const std::string& w = report.warnings[0];
    EXPECT_EQ(w.rfind(file.string() + ":line 3: ", 0), 0u) << w;
    EXPECT_NE(w.find("'Created by Blender3D 247 - www.b"), std::string::npos) << w;
    EXPECT_EQ(w.find('\n'), std::string::npos);
    EXPECT_EQ(err, "warning: " + w + "\n");
}

// Lines that could be meant to lay out the data stay errors, one line each: a misspelt keyword,
// or a line shaped like a property or an element line.
TEST(PlyHeader, LinesThatCouldChangeTheLayoutAreRefused) {
    const struct {
        const char* line;
        const char* error;
    } cases[] = {
        {"elment face 4\n", ":line 3: unknown PLY header keyword 'elment'"},
        {"propery float nx\n", ":line 3: unknown PLY header keyword 'propery'"},
        {"Property float nx\n", ":line 3: unknown PLY header keyword 'Property'"},
        {"vertex_normal float nx\n", ":line 3: unknown PLY header keyword 'vertex_normal'"},
        {"normals list uchar float n\n", ":line 3: unknown PLY header keyword 'normals'"},
        {"normal vertex 4\n", ":line 3: unknown PLY header keyword 'normal'"},
        {"end_headr\n", ":line 3: unknown PLY header keyword 'end_headr'"},
    };
    for (const auto& c : cases) {
        const fs::path file = writeTemp("layout.ply", tetPly(c.line));
        try {
            loadMesh(file);
            ADD_FAILURE() << c.line << " was accepted";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.rfind(file.string() + c.error, 0), 0u) << what;
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        }
    }
    // And what changes the layout for sure stays refused as before.
    const fs::path badFormat = writeTemp("format.ply", "ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n");
    EXPECT_THROW(
        {
            try {
                loadMesh(badFormat);
            } catch (const InputError& e) {
                EXPECT_NE(std::string(e.what()).find(":line 2: unknown PLY format 'binary_middle_endian'"), std::string::npos) << e.what();
                throw;
            }
        },
        InputError);
}

// Other lines that are no keyword are skipped, each with its warning; a file without any has none.
TEST(PlyHeader, EveryOtherUnknownLineIsWarnedAbout) {
    ImportReport report;
    std::string err;
    const TriangleMesh mesh = loadCapturingStderr(writeTemp("two.ply", tetPly("exported by some tool\nunits: millimetres\n")), &report, err);
    EXPECT_EQ(mesh.triangleCount(), 4u);
    ASSERT_EQ(report.warnings.size(), 2u);
    EXPECT_NE(report.warnings[0].find(":line 3: "), std::string::npos);
    EXPECT_NE(report.warnings[1].find(":line 4: "), std::string::npos);
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 2);
    ImportReport clean;
    loadMesh(writeTemp("clean.ply", tetPly("")), &clean);
    EXPECT_TRUE(clean.warnings.empty());
}

}  // namespace
}  // namespace rtwall
