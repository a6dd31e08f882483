// The VTK importers (mesh/src/import_vtk.cpp) on files written by VTK's own writers
// (tests/data/meshes/make_vtk_meshes.py) and on malformed ones.
#include "mesh_test_util.h"
#include "rtwall/mesh.h"

#include "../../mesh/src/import_vtk.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;
using test::signedVolume;

const fs::path kMeshes = fs::path(RTWALL_TEST_DATA_DIR) / "meshes";

struct VtkFile {
    const char* file;
    const char* format;
    size_t vertices;  // after the surface filter for unstructured grids
    size_t triangles;
    bool normals;
    size_t polygonsTriangulated, strips, skipped;
};
std::ostream& operator<<(std::ostream& os, const VtkFile& f) { return os << f.file; }

class VtkImportGood : public ::testing::TestWithParam<VtkFile> {};

// Every file holds the [0,1]x[0,2]x[0,3] box: counts, exact bounds and the exact signed volume
// (which catches lost, duplicated or flipped faces).
TEST_P(VtkImportGood, LoadsTheBox) {
    const VtkFile& f = GetParam();
    ImportReport report;
    const TriangleMesh mesh = loadMesh(kMeshes / f.file, &report);
    test::expectImported(mesh, report, f.format, f.vertices, f.triangles, f.polygonsTriangulated);
    EXPECT_EQ(report.stripsTriangulated, f.strips);
    EXPECT_EQ(report.cellsSkipped, f.skipped);
    EXPECT_EQ(mesh.hasNormals(), f.normals);
    test::expectBounds(mesh, {0, 0, 0}, {1, 2, 3});
    EXPECT_NEAR(std::fabs(signedVolume(mesh)), 6.0, 1e-6);
    EXPECT_EQ(mesh.origin(), (std::array<double, 3>{0, 0, 0}));
    EXPECT_EQ(mesh.positions()[3 * mesh.vertexCount()], 0.0f);  // Embree's padding
}

INSTANTIATE_TEST_SUITE_P(
    Files, VtkImportGood,
    ::testing::Values(VtkFile{"box_ascii.vtk", "vtk", 8, 12, true, 6, 0, 1}, VtkFile{"box_binary.vtk", "vtk", 8, 12, false, 6, 0, 1},
                      VtkFile{"box_strips.vtk", "vtk", 8, 12, false, 0, 6, 0},
                      VtkFile{"box_hex_ascii.vtk", "vtk", 8, 12, false, 6, 0, 0},
                      VtkFile{"box_ascii.vtp", "vtp", 8, 12, true, 6, 0, 1}, VtkFile{"box_base64.vtp", "vtp", 8, 12, false, 6, 0, 1},
                      VtkFile{"box_raw.vtp", "vtp", 8, 12, false, 6, 0, 1}, VtkFile{"box_zlib.vtp", "vtp", 8, 12, false, 6, 0, 1},
                      VtkFile{"box_lz4.vtp", "vtp", 8, 12, false, 6, 0, 1},
                      VtkFile{"box_hex_zlib.vtu", "vtu", 8, 12, false, 6, 0, 0},
                      VtkFile{"box_hex_ascii.vtu", "vtu", 8, 12, false, 6, 0, 0}),
    test::FileCaseName{});

// Triangle strips alternate their winding: all twelve triangles of the strip box must face out
// the same way as the polygon box (the volume has one sign).
TEST(VtkImport, StripsKeepAConsistentWinding) {
    const TriangleMesh strips = loadMesh(kMeshes / "box_strips.vtk");
    const TriangleMesh polys = loadMesh(kMeshes / "box_ascii.vtk");
    EXPECT_NEAR(signedVolume(strips), signedVolume(polys), 1e-6);
}

// Coordinates near (148376, 1234, -223423) are read in double precision (a .vtp file's points, a
// VRML Transform applied to the box) and stored relative to a whole-number origin, so the float
// buffers hold the box exactly.
class FarFromOrigin : public ::testing::TestWithParam<const char*> {};

TEST_P(FarFromOrigin, IsRecentredWithoutLoss) {
    const TriangleMesh mesh = loadMesh(kMeshes / GetParam());
    const auto o = mesh.origin();
    EXPECT_EQ(o, (std::array<double, 3>{148377.0, 1235.0, -223422.0}));  // the centre, rounded
    const Bounds3 b = mesh.bounds();
    EXPECT_EQ(double(b.lo.x) + o[0], 148376.0);
    EXPECT_EQ(double(b.hi.x) + o[0], 148377.0);
    EXPECT_EQ(double(b.lo.y) + o[1], 1234.0);
    EXPECT_EQ(double(b.hi.y) + o[1], 1236.0);
    EXPECT_EQ(double(b.lo.z) + o[2], -223423.0);
    EXPECT_EQ(double(b.hi.z) + o[2], -223420.0);
    EXPECT_NEAR(std::fabs(signedVolume(mesh)), 6.0, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Files, FarFromOrigin, ::testing::Values("box_far.vtp", "box_far.wrl"), test::FileCaseName{});

// The content, not the name, says what a file is: a VTK file or a VRML file without a known
// extension, and a legacy VTK file named .vtp (read by the legacy reader).
struct NamedCopy {
    const char* file;
    const char* name;  // the copy's name
    const char* format;
};
std::ostream& operator<<(std::ostream& os, const NamedCopy& c) { return os << c.name; }
class ContentDecides : public ::testing::TestWithParam<NamedCopy> {};

TEST_P(ContentDecides, TheFormat) {
    const fs::path file = test::copyMeshAs(GetParam().file, test::tempFolder("rtwall_content_tests"), GetParam().name);
    ImportReport report;
    EXPECT_EQ(loadMesh(file, &report).triangleCount(), 12u);
    EXPECT_EQ(report.format, GetParam().format);
}

INSTANTIATE_TEST_SUITE_P(Files, ContentDecides,
                         ::testing::Values(NamedCopy{"box_zlib.vtp", "box_no_ext", "vtp"},
                                           NamedCopy{"box_ascii.vtk", "legacy_named.vtp", "vtk"},
                                           NamedCopy{"box_plain.wrl", "box_vrml", "wrl"}),
                         [](const ::testing::TestParamInfo<NamedCopy>& p) { return test::fileTestName(p.param.name); });

struct BadVtk {
    const char* file;
    std::vector<const char*> expect;
};
std::ostream& operator<<(std::ostream& os, const BadVtk& f) { return os << f.file; }
class VtkImportBad : public ::testing::TestWithParam<BadVtk> {};

TEST_P(VtkImportBad, IsRejectedWithAReason) {
    const fs::path file = kMeshes / GetParam().file;
    ASSERT_TRUE(fs::exists(file)) << file;
    const std::string message = test::loadError(file);
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
    for (const char* part : GetParam().expect) EXPECT_NE(message.find(part), std::string::npos) << "no '" << part << "' in: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    Files, VtkImportBad,
    ::testing::Values(BadVtk{"bad_points_huge.vtk", {":line 5", "POINTS declares 4000000000"}},
                      BadVtk{"bad_points_huge.vtp", {":offset ", "NumberOfPoints=4000000000"}},
                      BadVtk{"bad_index_out_of_range.vtk", {"polygon 0", "point index 7 is out of range"}},
                      BadVtk{"bad_index_negative.vtk", {"polygon 0", "point index -1"}},
                      BadVtk{"bad_index.vtp", {"polygon 0", "point index 9 is out of range"}},
                      // VTK's ASCII reader stops at the 'nan' token itself.
                      BadVtk{"bad_nan.vtk", {"VTK", "nan"}},
                      // VTK reads the points it finds and stops: what is left has no triangles.
                      BadVtk{"bad_truncated_ascii.vtk", {"no triangles"}},
                      BadVtk{"bad_truncated_binary.vtk", {":offset ", "POLYGONS: truncated"}},
                      BadVtk{"bad_structured.vtk", {":line ", "not supported"}},
                      BadVtk{"bad_not_vtk.vtk", {"not a VTK file"}},
                      BadVtk{"bad_garbage.vtp", {"VTK"}},
                      // Found by fuzz_import_vtk / fuzz_import_vtp: VTK 9.1 itself dies on these (a NULL
                      // dereference in vtkDataReader::ReadString, a division by zero in
                      // vtkXMLDataParser::ReadCompressedData); the child process keeps rtwall alive.
                      BadVtk{"bad_fuzz_vtk_reader_null_deref.vtk", {}},
                      BadVtk{"bad_fuzz_vtp_zero_block_size.vtp", {}}),
    test::FileCaseName{});

// NaN in binary data reaches the importer's own check, which names the point.
TEST(VtkImport, NanInBinaryDataIsRejected) {
    std::string f = "# vtk DataFile Version 3.0\nnan\nBINARY\nDATASET POLYDATA\nPOINTS 3 float\n";
    const float pts[9] = {0, 0, 0, 1, 0, 0, 0, std::nanf(""), 0};
    for (float v : pts) {
        unsigned char b[4];
        std::memcpy(b, &v, 4);
        for (int k = 3; k >= 0; --k) f.push_back(char(b[k]));  // big-endian
    }
    f += "\nPOLYGONS 1 4\n";
    for (int32_t v : {3, 0, 1, 2})
        for (int k = 3; k >= 0; --k) f.push_back(char((uint32_t(v) >> (8 * k)) & 0xff));
    f += "\n";
    const fs::path dir = fs::path(::testing::TempDir()) / "rtwall_vtk_tests";
    fs::create_directories(dir);
    std::ofstream(dir / "nan_binary.vtk", std::ios::binary).write(f.data(), std::streamsize(f.size()));
    try {
        loadMesh(dir / "nan_binary.vtk");
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("point 2 has a NaN"), std::string::npos) << e.what();
    }
}

// VTK's own messages never reach the terminal.
TEST(VtkImport, PrintsNothing) {
    ::testing::internal::CaptureStderr();
    ::testing::internal::CaptureStdout();
    EXPECT_THROW(loadMesh(kMeshes / "bad_garbage.vtp"), InputError);
    EXPECT_THROW(loadMesh(kMeshes / "bad_truncated_binary.vtk"), InputError);
    const std::string out = ::testing::internal::GetCapturedStdout();
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(err, "");
    EXPECT_EQ(out, "");
}

// The count check alone: a header claiming more than the bytes can hold is refused before VTK
// sees it, for both encodings.
TEST(VtkImport, CountsAreCheckedAgainstTheFileSize) {
    const std::string ascii = "# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 100 float\n0 0 0\n";
    EXPECT_THROW(detail::checkVtkCounts(detail::VtkKind::Legacy, ascii, "a.vtk"), InputError);
    const std::string fine = "# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 0 0\n";
    EXPECT_NO_THROW(detail::checkVtkCounts(detail::VtkKind::Legacy, fine, "a.vtk"));
    // Data lines with large numbers are not headers.
    const std::string data = "# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n100000 100001 100002\n";
    EXPECT_NO_THROW(detail::checkVtkCounts(detail::VtkKind::Legacy, data, "a.vtk"));
}

}  // namespace
}  // namespace rtwall
