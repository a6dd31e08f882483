// VRML 2.0 through VTK's vtkVRMLImporter (mesh/src/import_vtk.cpp), headless: hand-written files
// with and without colour, a Transform, a Group of shapes, and malformed files.
#include "mesh_test_util.h"
#include "rtwall/mesh.h"

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;
using test::signedVolume;

const fs::path kMeshes = fs::path(RTWALL_TEST_DATA_DIR) / "meshes";

using Rgb = std::array<int, 3>;

using test::expectBounds;

// Index of the vertex at p (the importer may reorder nothing, but say so through positions).
size_t vertexAt(const TriangleMesh& m, Float3 p) {
    for (size_t v = 0; v < m.vertexCount(); ++v) {
        const Float3 q = m.position(v);
        if (q.x == p.x && q.y == p.y && q.z == p.z) return v;
    }
    ADD_FAILURE() << "no vertex at " << p.x << " " << p.y << " " << p.z;
    return 0;
}

TEST(Vrml, PlainBoxWithoutColour) {
    ImportReport report;
    const TriangleMesh mesh = loadMesh(kMeshes / "box_plain.wrl", &report);
    EXPECT_EQ(report.format, "wrl");
    EXPECT_EQ(mesh.vertexCount(), 8u);
    EXPECT_EQ(mesh.triangleCount(), 12u);
    EXPECT_EQ(report.polygonsTriangulated, 6u);
    EXPECT_FALSE(mesh.hasColors());
    expectBounds(mesh, {0, 0, 0}, {1, 2, 3});
    EXPECT_NEAR(std::fabs(signedVolume(mesh)), 6.0, 1e-9);
    EXPECT_EQ(mesh.origin(), (std::array<double, 3>{0, 0, 0}));
}

// A Transform moves the box to (10, 20, 30); the Color node's colours stay with their points.
TEST(Vrml, TransformAndPerVertexColours) {
    const TriangleMesh mesh = loadMesh(kMeshes / "box_color_transform.wrl");
    EXPECT_EQ(mesh.triangleCount(), 12u);
    expectBounds(mesh, {10, 20, 30}, {11, 22, 33});
    EXPECT_NEAR(std::fabs(signedVolume(mesh)) , 6.0, 1e-3);
    ASSERT_TRUE(mesh.hasColors());
    auto color = [&](Float3 p) {
        const uint8_t* c = mesh.colors() + 3 * vertexAt(mesh, p);
        return Rgb{c[0], c[1], c[2]};
    };
    EXPECT_EQ(color({10, 20, 30}), (Rgb{255, 0, 0}));
    EXPECT_EQ(color({11, 20, 30}), (Rgb{0, 255, 0}));
    EXPECT_EQ(color({11, 22, 30}), (Rgb{0, 0, 255}));
    EXPECT_EQ(color({10, 22, 33}), (Rgb{0, 0, 0}));
    EXPECT_EQ(color({11, 22, 33}), (Rgb{255, 255, 255}));
}

// Two shapes in a Group: a Material-coloured triangle at the origin, and a quad scaled by 2 and
// moved to (5, 0, -1) without colour, which takes white.
TEST(Vrml, ShapesInAGroupAreMergedInWorldCoordinates) {
    const TriangleMesh mesh = loadMesh(kMeshes / "group_shapes.wrl");
    EXPECT_EQ(mesh.vertexCount(), 7u);
    EXPECT_EQ(mesh.triangleCount(), 3u);
    expectBounds(mesh, {0, 0, -1}, {7, 2, 0});
    ASSERT_TRUE(mesh.hasColors());
    auto color = [&](Float3 p) {
        const uint8_t* c = mesh.colors() + 3 * vertexAt(mesh, p);
        return Rgb{c[0], c[1], c[2]};
    };
    EXPECT_EQ(color({1, 0, 0}), (Rgb{0, 128, 255}));  // diffuseColor 0 0.5 1
    EXPECT_EQ(color({7, 2, -1}), (Rgb{255, 255, 255}));
    // Winding survives the transform: both shapes face +z.
    for (size_t t = 0; t < mesh.triangleCount(); ++t) EXPECT_GT(test::geometricNormal(mesh, t).z, 0.0f) << t;
}

struct BadVrml {
    const char* file;
    const char* expect;
};
std::ostream& operator<<(std::ostream& os, const BadVrml& f) { return os << f.file; }
class VrmlBad : public ::testing::TestWithParam<BadVrml> {};

// One line naming the file (and the line where VTK's parser says), never a crash of rtwall
// (VTK's parser runs in a child process), and never a partial mesh from a truncated file.
TEST_P(VrmlBad, IsRejectedWithAReason) {
    const fs::path file = kMeshes / GetParam().file;
    ASSERT_TRUE(fs::exists(file)) << file;
    const std::string message = test::loadError(file);
    EXPECT_EQ(message.rfind(file.string(), 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
    EXPECT_NE(message.find(GetParam().expect), std::string::npos) << "no '" << GetParam().expect << "' in: " << message;
}

INSTANTIATE_TEST_SUITE_P(Files, VrmlBad,
                         ::testing::Values(BadVrml{"bad_truncated.wrl", ":line 8: VRML: parse error"},
                                           BadVrml{"bad_garbage.wrl", ":line 1: VRML: Unknown node type"},
                                           // VTK's parser reads indices as int: 4000000000 wraps negative.
                                           BadVrml{"bad_index_huge.wrl", "polygon 0: point index -294967296 is out of range"},
                                           BadVrml{"bad_no_geometry.wrl", "no shapes"},
                                           BadVrml{"bad_vrml1.wrl", "VRML 1.0 is not supported"}),
                         test::FileCaseName{});

// VTK's VRML parser prints nothing to the terminal either.
TEST(Vrml, PrintsNothing) {
    ::testing::internal::CaptureStderr();
    ::testing::internal::CaptureStdout();
    EXPECT_THROW(loadMesh(kMeshes / "bad_garbage.wrl"), InputError);
    EXPECT_EQ(loadMesh(kMeshes / "box_plain.wrl").triangleCount(), 12u);
    EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

}  // namespace
}  // namespace rtwall
