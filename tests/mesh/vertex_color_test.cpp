// Per-vertex colours (issue 3: "point colours are kept when present"): every importer that has
// them fills TriangleMesh::colors(), the cache keeps them, and data that is not a colour is not
// kept.
#include "mesh_test_util.h"
#include "rtwall/mesh.h"

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshes = fs::path(RTWALL_TEST_DATA_DIR) / "meshes";

using Rgb = std::array<int, 3>;
Rgb colorOf(const TriangleMesh& m, size_t v) {
    const uint8_t* c = m.colors() + 3 * v;
    return {c[0], c[1], c[2]};
}

// Every file holds the same triangle: vertex 0 orange (255,128,0), 1 green, 2 blue; float
// colours (128/255 and the like) round back to the same bytes, alpha is dropped.
class ColoredTriangle : public ::testing::TestWithParam<const char*> {};

TEST_P(ColoredTriangle, KeepsEveryVertexColour) {
    ImportReport report;
    const TriangleMesh mesh = loadMesh(kMeshes / GetParam(), &report);
    ASSERT_EQ(mesh.vertexCount(), 3u);
    ASSERT_EQ(mesh.triangleCount(), 1u);
    ASSERT_TRUE(mesh.hasColors()) << report.format;
    EXPECT_EQ(colorOf(mesh, 0), (Rgb{255, 128, 0}));
    EXPECT_EQ(colorOf(mesh, 1), (Rgb{0, 255, 0}));
    EXPECT_EQ(colorOf(mesh, 2), (Rgb{0, 0, 255}));
}

INSTANTIATE_TEST_SUITE_P(Files, ColoredTriangle,
                         ::testing::Values("tri_colors_ascii.ply", "tri_colors_float_le.ply", "tri_colors.off", "tri_colors.obj",
                                           "tri_colors.vtk", "tri_colors.vtp"),
                         test::FileCaseName{});

// A one-component scalar field is data for a lookup table, not a colour: not kept. Nor are
// files without colours given any.
TEST(VertexColors, ScalarFieldsAndPlainFilesHaveNone) {
    EXPECT_FALSE(loadMesh(kMeshes / "tri_scalars.vtk").hasColors());
    EXPECT_FALSE(loadMesh(kMeshes / "box_ascii.vtk").hasColors());
    EXPECT_FALSE(loadMesh(kMeshes / "tet_ascii.ply").hasColors());
    EXPECT_FALSE(loadMesh(kMeshes / "box_quads.off").hasColors());
}

// Colours take 3 bytes per vertex in the resident size, and nothing when absent.
TEST(VertexColors, ResidentBytesCountThem) {
    TriangleMesh a;
    for (int i = 0; i < 3; ++i) a.addVertex({float(i), float(i * i), 0});
    a.addTriangle(0, 1, 2);
    const size_t plain = a.residentBytes();
    a.setColors({1, 2, 3, 4, 5, 6, 7, 8, 9});
    EXPECT_GE(a.residentBytes(), plain + 9);
    EXPECT_THROW(a.setColors({1, 2, 3}), std::invalid_argument);
    EXPECT_THROW(a.addVertex({0, 0, 1}), std::logic_error);  // colours are attached last
    a.setColors({});
    EXPECT_FALSE(a.hasColors());
}

// The cache keeps colours byte for byte, and a flipped colour byte is caught by the checksum.
TEST(VertexColors, CacheRoundTripKeepsThem) {
    const fs::path src = test::copyMeshAs("tri_colors_ascii.ply", test::tempFolder("rtwall_color_cache", true), "tri.ply");
    const auto [first, second] = test::loadThroughCache(src);
    ASSERT_TRUE(second.hasColors());
    EXPECT_EQ(std::vector<uint8_t>(second.colors(), second.colors() + 9), std::vector<uint8_t>(first.colors(), first.colors() + 9));
    EXPECT_EQ(std::vector<float>(second.positions(), second.positions() + 10),
              std::vector<float>(first.positions(), first.positions() + 10));

    // The colour section is the file's last: its first byte sits at the start of the last
    // 64-byte block.
    const fs::path cache = meshCachePath(src);
    std::string bytes = test::readBytes(cache);
    ASSERT_EQ(bytes.size() % 64, 0u);
    const size_t colorAt = bytes.size() - 64;
    ASSERT_EQ(uint8_t(bytes[colorAt]), 255);
    ASSERT_EQ(uint8_t(bytes[colorAt + 1]), 128);
    bytes[colorAt + 1] = char(0x7f);
    test::expectChecksumRefuses(cache, src, bytes);
}

}  // namespace
}  // namespace rtwall
