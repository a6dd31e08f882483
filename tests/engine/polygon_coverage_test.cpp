// A keyhole polygon as the renderer shows it (issue 15): LightWave's ring, one 66-corner face
// (tests/data/meshes/ring.obj), rendered through a projection window that lies in the ring's own
// plane, so that every pixel's ray hits the plane at the pixel's centre on a regular grid. The
// pixels covered, times a pixel's area, must give the ring's exact area to 0.5% (the fan that
// ear clipping replaced covered the whole disc: five times the ring); every pixel whose centre is
// clearly inside the ring is covered, and none outside it or in its hole.
#include "mesh/polygon_shapes.h"

#include <rtwall/engine.h>
#include <rtwall/mesh.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <vector>

namespace rtwall {
namespace {

TEST(PolygonCoverage, KeyholeRingRendersAsARing) {
    const std::filesystem::path file = std::filesystem::path(RTWALL_TEST_DATA_DIR) / "meshes" / "ring.obj";
    const test::TestPolygon ring = test::fileShapes()[0];
    ASSERT_EQ(ring.name, "ring");

    SceneDesc d;
    d.meshes.push_back({"ring", file.string(), std::make_shared<const TriangleMesh>(loadMesh(file))});
    Material m;
    m.color = {1, 1, 1};
    d.materials.push_back(m);
    d.instances.push_back(InstanceDesc{});
    // The ring lies in the plane x = -1.25 with (u, v) = (y, z), facing +x; the window is the
    // square [-1.1, 1.1]^2 of that plane, seen from +x with z up (so y points right).
    const double half = 1.1;
    CameraDesc c;
    c.position = {3, 0, 0};
    c.window = ProjectionWindow{{-1.25f, float(-half), float(-half)}, {0, float(2 * half), 0}, {0, 0, float(2 * half)}};
    d.cameras.push_back(c);
    // Pixel centres with i = j lie exactly on the diagonal through two of the ring's corners,
    // where the triangulation has an edge: Embree's fast intersector can let such a ray through
    // between the two triangles (4 pixels here). Robust traversal makes this a test of the
    // triangles alone.
    d.bvh.robust = true;
    // No lights: with a white ambient term a white surface shows 1, the black background 0.
    RenderSettings& s = d.settings;
    s.width = s.height = 600;
    s.ambient = {1, 1, 1};
    s.background = {0, 0, 0};
    s.shadows = false;

    const Scene scene(d);
    const Camera camera(c, s.width, s.height);
    std::vector<float> out(size_t(3 * s.width * s.height));
    renderTileLinear(scene, camera, {0, 0, s.width, s.height}, 0, s, out.data(), size_t(3 * s.width));

    const double pixel = 2 * half / s.width;
    int covered = 0, wrong = 0, inHole = 0, unsure = 0;
    for (int j = 0; j < s.height; ++j)
        for (int i = 0; i < s.width; ++i) {
            const float value = out[size_t(3 * (j * s.width + i))];
            ASSERT_TRUE(value == 0.0f || std::fabs(value - 1.0f) < 1e-6f) << i << "," << j << ": " << value;
            const bool hit = value > 0.5f;
            covered += hit;
            const test::Point2 centre{-half + pixel * (i + 0.5), half - pixel * (j + 0.5)};
            if (hit && std::hypot(centre.u, centre.v) < 0.89) ++inHole;
            // Pixels whose centre is within a hundredth of a pixel of an edge could go either way.
            const int w = test::winding(ring.corners, centre);
            bool sure = true;
            for (const auto& [du, dv] : {std::pair{0.01, 0.0}, {-0.01, 0.0}, {0.0, 0.01}, {0.0, -0.01}})
                sure = sure && test::winding(ring.corners, {centre.u + du * pixel, centre.v + dv * pixel}) == w;
            if (!sure) {
                ++unsure;
                continue;
            }
            if (hit != (w == 1)) ++wrong;
        }
    const double area = covered * pixel * pixel;
    EXPECT_NEAR(area, ring.area, 0.005 * ring.area) << covered << " pixels covered";
    EXPECT_EQ(inHole, 0) << "pixels covered in the ring's hole";
    EXPECT_EQ(wrong, 0) << "pixels covered outside the ring or left empty inside it";
    EXPECT_LT(unsure, 100);
}

}  // namespace
}  // namespace rtwall
