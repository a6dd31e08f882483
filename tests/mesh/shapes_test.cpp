#include "mesh_test_util.h"
#include "rtwall/mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rtwall {
namespace {

using test::geometricNormal;
using test::signedVolume;

// Shading normals must be unit length and on the same side as the geometric normal, or
// shading flips on the triangles where they disagree.
void expectConsistentNormals(const TriangleMesh& mesh) {
    ASSERT_TRUE(mesh.hasNormals());
    for (size_t v = 0; v < mesh.vertexCount(); ++v) EXPECT_NEAR(length(mesh.normal(v)), 1.0, 1e-5) << "vertex " << v;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const Float3 g = geometricNormal(mesh, t);
        for (int k = 0; k < 3; ++k)
            EXPECT_GT(dot(g, mesh.normal(mesh.indices()[3 * t + size_t(k)])), 0.0) << "triangle " << t << " corner " << k;
    }
}

class MeshShapesSphere : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(MeshShapesSphere, UnitSphereWithFormulaCounts) {
    const auto [rings, segments] = GetParam();
    const TriangleMesh sphere = makeSphere(rings, segments);
    EXPECT_EQ(sphere.vertexCount(), size_t((rings - 1) * segments + 2));
    EXPECT_EQ(sphere.triangleCount(), size_t(2 * segments * (rings - 1)));
    for (size_t v = 0; v < sphere.vertexCount(); ++v) {
        const Float3 p = sphere.position(v), n = sphere.normal(v);
        EXPECT_NEAR(length(p), 1.0, 1e-6) << "vertex " << v;
        EXPECT_NEAR(dot(p, n), 1.0, 1e-6) << "normal of vertex " << v << " is not radial";
    }
    expectConsistentNormals(sphere);
    // Inscribed polyhedron: positive (outward winding), below the sphere's volume.
    const double volume = signedVolume(sphere);
    EXPECT_GT(volume, 0.0);
    EXPECT_LT(volume, 4.0 / 3.0 * std::numbers::pi);
    const Bounds3 b = sphere.bounds();
    EXPECT_FLOAT_EQ(b.hi.y, 1.0f);
    EXPECT_FLOAT_EQ(b.lo.y, -1.0f);
}

INSTANTIATE_TEST_SUITE_P(Sizes, MeshShapesSphere,
                         ::testing::Values(std::pair{2, 3}, std::pair{3, 4}, std::pair{16, 32}, std::pair{64, 128}));

TEST(MeshShapes, FineSphereApproachesTheSphereVolume) {
    EXPECT_NEAR(signedVolume(makeSphere(128, 256)), 4.0 / 3.0 * std::numbers::pi, 2e-3);
}

TEST(MeshShapes, BoxIsTheClosedCube) {
    const TriangleMesh box = makeBox();
    EXPECT_EQ(box.vertexCount(), 8u);
    EXPECT_EQ(box.triangleCount(), 12u);
    EXPECT_FALSE(box.hasNormals());
    test::expectBounds(box, {-1, -1, -1}, {1, 1, 1});
    EXPECT_DOUBLE_EQ(signedVolume(box), 8.0);
    // Every face normal is an axis: two triangles per axis direction.
    int perAxis[6] = {};
    for (size_t t = 0; t < box.triangleCount(); ++t) {
        const Float3 g = geometricNormal(box, t);
        const float c[3] = {g.x, g.y, g.z};
        int nonZero = 0;
        for (int k = 0; k < 3; ++k) {
            if (c[k] != 0.0f) {
                ++nonZero;
                ++perAxis[2 * k + (c[k] > 0)];
            }
        }
        EXPECT_EQ(nonZero, 1) << "triangle " << t;
    }
    for (int a = 0; a < 6; ++a) EXPECT_EQ(perAxis[a], 2) << "axis direction " << a;
}

TEST(MeshShapes, QuadFacesUp) {
    const TriangleMesh quad = makeQuad();
    EXPECT_EQ(quad.vertexCount(), 4u);
    EXPECT_EQ(quad.triangleCount(), 2u);
    const Bounds3 b = quad.bounds();
    EXPECT_EQ(b.lo.x, -1.0f);
    EXPECT_EQ(b.hi.x, 1.0f);
    EXPECT_EQ(b.lo.y, 0.0f);
    EXPECT_EQ(b.hi.y, 0.0f);
    EXPECT_EQ(b.lo.z, -1.0f);
    EXPECT_EQ(b.hi.z, 1.0f);
    for (size_t v = 0; v < 4; ++v) EXPECT_EQ(quad.normal(v).y, 1.0f);
    for (size_t t = 0; t < 2; ++t) {
        const Float3 g = geometricNormal(quad, t);
        EXPECT_GT(g.y, 0.0f);
        EXPECT_EQ(g.x, 0.0f);
        EXPECT_EQ(g.z, 0.0f);
    }
    expectConsistentNormals(quad);
}

TEST(MeshShapes, TorusKnotIsAClosedTubeOfTheGivenRadius) {
    const int segments = 128, sides = 12;
    const float radius = 0.1f;
    const TriangleMesh knot = makeTorusKnot(2, 3, segments, sides, radius);
    EXPECT_EQ(knot.vertexCount(), size_t(segments * sides));
    EXPECT_EQ(knot.triangleCount(), size_t(2 * segments * sides));
    expectConsistentNormals(knot);
    EXPECT_GT(signedVolume(knot), 0.0);
    // Each ring of `sides` vertices is a circle of the tube radius around its centre, and the
    // normals point away from that centre.
    for (int i = 0; i < segments; ++i) {
        Float3 centre{0, 0, 0};
        for (int j = 0; j < sides; ++j) {
            const Float3 p = knot.position(size_t(i * sides + j));
            centre = {centre.x + p.x / sides, centre.y + p.y / sides, centre.z + p.z / sides};
        }
        for (int j = 0; j < sides; ++j) {
            const size_t v = size_t(i * sides + j);
            const Float3 offset = knot.position(v) - centre;
            EXPECT_NEAR(length(offset), radius, 1e-5) << "ring " << i;
            EXPECT_NEAR(dot(offset, knot.normal(v)) / radius, 1.0, 1e-4) << "ring " << i;
        }
    }
    const Bounds3 b = knot.bounds();
    EXPECT_LE(std::max({-b.lo.x, -b.lo.y, -b.lo.z, b.hi.x, b.hi.y, b.hi.z}), 1.0f + radius);
}

TEST(MeshShapes, BadArgumentsAreRefused) {
    EXPECT_THROW(makeSphere(1, 8), std::invalid_argument);
    EXPECT_THROW(makeSphere(8, 2), std::invalid_argument);
    EXPECT_THROW(makeSphere(100000, 100000), std::invalid_argument);
    EXPECT_THROW(makeTorusKnot(0, 3, 64, 8, 0.1f), std::invalid_argument);
    EXPECT_THROW(makeTorusKnot(2, 3, 2, 8, 0.1f), std::invalid_argument);
    EXPECT_THROW(makeTorusKnot(2, 3, 64, 8, 0.0f), std::invalid_argument);
    EXPECT_THROW(makeTorusKnot(2, 3, 64, 8, NAN), std::invalid_argument);
}

}  // namespace
}  // namespace rtwall
