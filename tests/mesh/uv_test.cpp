// Per-vertex texture coordinates (issue 7): every importer that has them fills
// TriangleMesh::uvs() with the file's exact values, OBJ seams split vertices, the cache keeps
// them (and catches a flipped byte in their section), and bad values give one-line errors.
#include "mesh_test_util.h"
#include "rtwall/mesh.h"

#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshes = fs::path(RTWALL_TEST_DATA_DIR) / "meshes";

// The quad every good file holds (make_uv_meshes.py): positions and their (u, v).
const std::array<std::array<float, 3>, 4> kP = {{{0, 0, 0}, {2, 0, 0}, {2, 0, 1}, {0, 0, 1}}};
const std::array<std::array<float, 2>, 4> kUV = {{{0.125f, 0.25f}, {0.875f, 0.25f}, {0.875f, 0.75f}, {0.125f, 0.75f}}};

// The (u, v) of the vertex at position p (importers may renumber vertices).
std::array<float, 2> uvAtPosition(const TriangleMesh& m, const std::array<float, 3>& p) {
    for (size_t v = 0; v < m.vertexCount(); ++v) {
        const Float3 q = m.position(v);
        if (q.x == p[0] && q.y == p[1] && q.z == p[2]) return {m.uvs()[2 * v], m.uvs()[2 * v + 1]};
    }
    ADD_FAILURE() << "no vertex at (" << p[0] << ", " << p[1] << ", " << p[2] << ")";
    return {-1, -1};
}

class UVQuad : public ::testing::TestWithParam<const char*> {};

TEST_P(UVQuad, KeepsTheFilesExactTextureCoordinates) {
    ImportReport report;
    const TriangleMesh mesh = loadMesh(kMeshes / GetParam(), &report);
    ASSERT_EQ(mesh.vertexCount(), 4u) << report.format;
    ASSERT_EQ(mesh.triangleCount(), 2u);
    ASSERT_TRUE(mesh.hasUVs()) << report.format;
    for (size_t i = 0; i < 4; ++i) {
        const auto uv = uvAtPosition(mesh, kP[i]);
        EXPECT_EQ(uv[0], kUV[i][0]) << "vertex " << i;
        EXPECT_EQ(uv[1], kUV[i][1]) << "vertex " << i;
    }
    EXPECT_EQ(report.seamVerticesSplit, 0u);
}

INSTANTIATE_TEST_SUITE_P(Files, UVQuad,
                         ::testing::Values("uv_quad.obj", "uv_quad_ascii.ply", "uv_quad_st_le.ply", "uv_quad_texture_uv.ply",
                                           "uv_quad.off", "uv_quad.vtk", "uv_quad3.vtp", "uv_quad.wrl"),
                         test::FileCaseName{});

// OBJ gives vt per face corner. Vertex 1 has vt 1 in the first face and vt 5 in the second: it
// is split into two vertices at the same position; vertex 3 has vt 3 in both and is not.
TEST(MeshUVs, ObjSeamSplitsTheVertex) {
    ImportReport report;
    const TriangleMesh mesh = loadMesh(kMeshes / "uv_seam.obj", &report);
    ASSERT_EQ(mesh.vertexCount(), 5u);
    ASSERT_EQ(mesh.triangleCount(), 2u);
    ASSERT_TRUE(mesh.hasUVs());
    EXPECT_EQ(report.seamVerticesSplit, 1u);
    const uint32_t* idx = mesh.indices();
    const float* uv = mesh.uvs();
    EXPECT_EQ(std::vector<uint32_t>(idx, idx + 6), (std::vector<uint32_t>{0, 2, 1, 4, 3, 2}));
    // The copy is vertex 4: vertex 0's position, vt 5's (u, v); vertex 0 keeps vt 1's.
    EXPECT_EQ(mesh.position(4).x, mesh.position(0).x);
    EXPECT_EQ(mesh.position(4).z, mesh.position(0).z);
    EXPECT_EQ(std::vector<float>(uv, uv + 10),
              (std::vector<float>{0.125f, 0.25f, 0.875f, 0.25f, 0.875f, 0.75f, 0.125f, 0.75f, 0.5f, 0.0625f}));
}

// The seam's copy of a vertex is the vertex with another (u, v): same position, normal and colour.
TEST(MeshUVs, ObjSeamCopyKeepsNormalAndColour) {
    ImportReport report;
    const TriangleMesh mesh = loadMesh(kMeshes / "uv_seam_attrs.obj", &report);
    ASSERT_EQ(mesh.vertexCount(), 5u);
    ASSERT_EQ(report.seamVerticesSplit, 1u);
    ASSERT_TRUE(mesh.hasNormals());
    ASSERT_TRUE(mesh.hasColors());
    EXPECT_EQ(mesh.uvs()[8], 0.5f);  // the copy (vertex 4) has vt 5
    EXPECT_EQ(mesh.uvs()[9], 0.0625f);
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(mesh.normals()[12 + k], mesh.normals()[k]) << k;
        EXPECT_EQ(mesh.colors()[12 + k], mesh.colors()[k]) << k;
    }
    EXPECT_EQ(mesh.normals()[1], 1.0f);  // vertex 1's own normal, (0, 1, 0)
    EXPECT_EQ(mesh.colors()[0], 255);    // and colour, red
    EXPECT_EQ(mesh.colors()[1], 0);
}

// VRML texCoordIndex gives (u, v) per face corner: each triangle corner gets the (u, v) its index
// names, at the position its coordIndex names (VTK's importer unshares the corners).
TEST(MeshUVs, VrmlTexCoordIndexPerCorner) {
    const TriangleMesh mesh = loadMesh(kMeshes / "uv_texcoordindex.wrl");
    ASSERT_TRUE(mesh.hasUVs());
    ASSERT_EQ(mesh.triangleCount(), 2u);
    const float P[4][3] = {{0, 0, 0}, {2, 0, 0}, {2, 0, 1}, {0, 0, 1}};
    const float T[5][2] = {{0.5f, 0.5f}, {0.125f, 0.0625f}, {0.25f, 0.75f}, {0.375f, 1.0f}, {1.0f, 0.875f}};
    const int coordIndex[6] = {0, 2, 1, 0, 3, 2}, texIndex[6] = {4, 3, 2, 1, 0, 3};
    for (size_t t = 0; t < 2; ++t) {
        // VTK may start a triangle's corner list anywhere: match corners by position.
        for (int k = 0; k < 3; ++k) {
            const int c = coordIndex[3 * t + size_t(k)], ti = texIndex[3 * t + size_t(k)];
            bool found = false;
            for (int j = 0; j < 3; ++j) {
                const uint32_t v = mesh.indices()[3 * t + size_t(j)];
                const Float3 p = mesh.position(v);
                if (p.x != P[c][0] || p.y != P[c][1] || p.z != P[c][2]) continue;
                found = true;
                EXPECT_EQ(mesh.uvs()[2 * v], T[ti][0]) << "triangle " << t << " corner " << k;
                EXPECT_EQ(mesh.uvs()[2 * v + 1], T[ti][1]) << "triangle " << t << " corner " << k;
            }
            EXPECT_TRUE(found) << "triangle " << t << " corner " << k;
        }
    }
}

// Files without texture coordinates get none; so do MeshLab's per-face texcoord lists, which
// the PLY validator drops (they are not per-vertex).
TEST(MeshUVs, FilesWithoutThemHaveNone) {
    EXPECT_FALSE(loadMesh(kMeshes / "box_quads.obj").hasUVs());
    EXPECT_FALSE(loadMesh(kMeshes / "tet_ascii.ply").hasUVs());
    EXPECT_FALSE(loadMesh(kMeshes / "tet_texcoords_ascii.ply").hasUVs());
    EXPECT_FALSE(loadMesh(kMeshes / "box_ascii.vtk").hasUVs());
    EXPECT_FALSE(loadMesh(kMeshes / "box_plain.wrl").hasUVs());
}

// Bad texture coordinates are one-line errors naming the file and what is wrong.
TEST(MeshUVs, BadFilesGiveOneLineErrors) {
    const std::vector<std::pair<const char*, const char*>> cases = {
        {"bad_uv_nan_le.ply", "vertex 1 has a NaN or infinite texture coordinate"},
        {"bad_uv_partial_face.obj", "face 1: vertex 4 has no texture coordinate"},
        {"bad_uv_face_without.obj", "face 1 has no texture coordinates"},
        {"bad_uv_nan.vtk", "NaN or infinite texture coordinate"},
        {"bad_uv_1d.vtk", "texture coordinates have 1 components; expected 2 or 3"},
        // A count mismatch: VTK's XML reader already refuses an array shorter than the points.
        {"bad_uv_count.vtp", "may be too short"},
    };
    for (const auto& [file, expected] : cases) {
        try {
            loadMesh(kMeshes / file);
            ADD_FAILURE() << file << " was accepted";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(file), std::string::npos) << what;
            EXPECT_NE(what.find(expected), std::string::npos) << what;
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        }
    }
}

TEST(MeshUVs, SetUVsChecksCountAndValues) {
    TriangleMesh a;
    for (int i = 0; i < 3; ++i) a.addVertex({float(i), float(i * i), 0});
    a.addTriangle(0, 1, 2);
    const size_t plain = a.residentBytes();
    EXPECT_THROW(a.setUVs({0, 0, 1, 0}), std::invalid_argument);                  // 2 vertices' worth
    EXPECT_THROW(a.setUVs({0, 0, 1, 0, 0, NAN}), std::invalid_argument);          // NaN
    EXPECT_THROW(a.setUVs({0, 0, 1, INFINITY, 0, 1}), std::invalid_argument);     // infinite
    EXPECT_FALSE(a.hasUVs());
    a.setUVs({0, 0, 1, 0, 0, 1});
    EXPECT_TRUE(a.hasUVs());
    EXPECT_GE(a.residentBytes(), plain + 24);
    EXPECT_THROW(a.addVertex({0, 0, 1}), std::logic_error);  // texture coordinates are attached last
    a.setUVs({});
    EXPECT_FALSE(a.hasUVs());
}

// The cache keeps the texture coordinates bit for bit, in place (a view of the mapping), and a
// flipped byte in their section (the file's last: 4 vertices x 8 bytes, padded to 64) is caught.
TEST(MeshUVs, CacheRoundTripAndAFlippedUVByte) {
    const fs::path src = test::copyMeshAs("uv_quad.vtk", test::tempFolder("rtwall_uv_cache", true), "quad.vtk");
    const auto [first, second] = test::loadThroughCache(src);
    ASSERT_TRUE(second.hasUVs());
    EXPECT_TRUE(second.isMapped());
    EXPECT_EQ(std::vector<float>(second.uvs(), second.uvs() + 8), std::vector<float>(first.uvs(), first.uvs() + 8));
    EXPECT_EQ(std::vector<float>(second.positions(), second.positions() + 12),
              std::vector<float>(first.positions(), first.positions() + 12));

    const fs::path cache = meshCachePath(src);
    std::string bytes = test::readBytes(cache);
    ASSERT_EQ(bytes.size() % 64, 0u);
    EXPECT_EQ(uint32_t(uint8_t(bytes[8])), 5u);       // cache version 5
    EXPECT_EQ(uint32_t(uint8_t(bytes[48])) & 4u, 4u);  // flag bit 2: texture coordinates
    const size_t uvAt = bytes.size() - 64;
    float u0;
    std::memcpy(&u0, bytes.data() + uvAt, 4);
    ASSERT_EQ(u0, first.uvs()[0]);
    for (size_t i = uvAt + 32; i < bytes.size(); ++i) EXPECT_EQ(bytes[i], 0) << "padding byte " << i;
    bytes[uvAt + 5] = char(bytes[uvAt + 5] ^ 0x01);
    test::expectChecksumRefuses(cache, src, bytes);
}

// A version-3 cache (before texture coordinates) is refused with its version named, and rebuilt.
TEST(MeshUVs, Version3CacheIsRebuilt) {
    const fs::path src = test::copyMeshAs("uv_quad.obj", test::tempFolder("rtwall_uv_cache_v3", true), "quad.obj");
    const LoadOptions lo = test::cacheOn();
    loadMesh(src, lo);
    const fs::path cache = meshCachePath(src);
    std::string bytes = test::readBytes(cache);
    bytes[8] = 3;
    test::writeBytes(cache, bytes);
    ImportReport r;
    const TriangleMesh mesh = loadMesh(src, lo, &r);
    EXPECT_NE(r.cache.find("rebuilt: "), std::string::npos) << r.cache;
    EXPECT_NE(r.cache.find("cache version 3, this rtwall reads version 5"), std::string::npos) << r.cache;
    EXPECT_TRUE(mesh.hasUVs());
    ImportReport again;
    loadMesh(src, lo, &again);
    EXPECT_EQ(again.cache, "hit");
}

}  // namespace
}  // namespace rtwall
