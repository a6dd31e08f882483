#include "mesh_test_util.h"
#include "rtwall/mesh.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace rtwall {
namespace {

TEST(TriangleMeshTest, EmptyMeshStillHasThePaddingFloat) {
    const TriangleMesh mesh;
    EXPECT_EQ(mesh.vertexCount(), 0u);
    EXPECT_EQ(mesh.triangleCount(), 0u);
    EXPECT_FALSE(mesh.hasNormals());
    EXPECT_EQ(mesh.normals(), nullptr);
    ASSERT_NE(mesh.positions(), nullptr);
    EXPECT_EQ(mesh.positions()[0], 0.0f);
    EXPECT_TRUE(mesh.bounds().empty());
}

// Embree reads the last vertex with a 16-byte load: 3n+1 floats must be there, for positions
// and for normals. Under AddressSanitizer the reads below fail if they are not.
TEST(TriangleMeshTest, BuffersKeepOneFloatOfTailPadding) {
    TriangleMesh mesh;
    for (int n = 1; n <= 40; ++n) {
        mesh.addVertex({float(n), float(-n), float(2 * n)});
        const size_t v = mesh.vertexCount();
        ASSERT_EQ(v, size_t(n));
        EXPECT_EQ(mesh.positions()[3 * v], 0.0f) << "padding after " << v << " vertices";
        EXPECT_EQ(mesh.positions()[3 * v - 1], float(2 * n)) << "last z must not be the padding";
        EXPECT_GE(mesh.residentBytes(), (3 * v + 1) * sizeof(float));
    }
    mesh.setNormals(std::vector<float>(3 * mesh.vertexCount(), 1.0f));
    ASSERT_TRUE(mesh.hasNormals());
    EXPECT_EQ(mesh.normals()[3 * mesh.vertexCount()], 0.0f);
    EXPECT_EQ(mesh.normals()[3 * mesh.vertexCount() - 1], 1.0f);
}

TEST(TriangleMeshTest, VerticesAndTrianglesRoundTrip) {
    TriangleMesh mesh;
    EXPECT_EQ(mesh.addVertex({1, 2, 3}), 0u);
    EXPECT_EQ(mesh.addVertex({4, 5, 6}), 1u);
    EXPECT_EQ(mesh.addVertex({7, 8, 9}), 2u);
    mesh.addTriangle(0, 1, 2);
    mesh.addTriangle(2, 1, 0);
    EXPECT_EQ(mesh.triangleCount(), 2u);
    EXPECT_EQ(mesh.indices()[3], 2u);
    EXPECT_EQ(mesh.position(1).y, 5.0f);
    mesh.setPosition(1, {-4, -5, -6});
    EXPECT_EQ(mesh.position(1).z, -6.0f);
    EXPECT_EQ(mesh.positions()[3 * 3], 0.0f);  // padding untouched
}

TEST(TriangleMeshTest, BoundsCoverEveryVertex) {
    TriangleMesh mesh;
    mesh.addVertex({1, -2, 3});
    mesh.addVertex({-4, 5, 0.5f});
    mesh.addVertex({0, 0, -7});
    ASSERT_FALSE(mesh.bounds().empty());
    test::expectBounds(mesh, {-4, -2, -7}, {1, 5, 3});
}

TEST(TriangleMeshTest, ResidentBytesCountsReservedCapacity) {
    TriangleMesh mesh;
    const size_t before = mesh.residentBytes();
    mesh.reserve(1000, 2000);
    EXPECT_GE(mesh.residentBytes(), (3 * 1000 + 1) * sizeof(float) + 3 * 2000 * sizeof(uint32_t));
    EXPECT_GT(mesh.residentBytes(), before);
}

TEST(TriangleMeshTest, InvalidUseIsRefused) {
    TriangleMesh mesh;
    mesh.addVertex({0, 0, 0});
    mesh.addVertex({1, 0, 0});
    mesh.addVertex({0, 1, 0});
    EXPECT_THROW(mesh.addTriangle(0, 1, 3), std::out_of_range);
    EXPECT_THROW(mesh.setPosition(3, {0, 0, 0}), std::out_of_range);
    EXPECT_THROW(mesh.setNormals({0, 1, 0}), std::invalid_argument);
    mesh.setNormals(std::vector<float>(9, 0.0f));
    EXPECT_THROW(mesh.addVertex({1, 1, 1}), std::logic_error);
    EXPECT_EQ(mesh.triangleCount(), 0u);
}

}  // namespace
}  // namespace rtwall
