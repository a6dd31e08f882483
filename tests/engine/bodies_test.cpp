// Issue 29, mesh files that hold many bodies: an OBJ written here (as a plant exported as one
// mesh) of 7 bodies: a chiral torus knot, a turned copy of it numbered otherwise, its mirror
// image (wound outward), two boxes (one turned), a sphere and a box scaled by 1.001. The knot and
// the box are stored once each and placed by instances; the mirror image, the sphere and the
// scaled box, which have no copy, stay together in one mesh; the render agrees with the file
// loaded as one mesh within float rounding.
#include "test_util.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <random>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

struct Body {
    std::vector<std::array<double, 3>> v;
    std::vector<std::array<uint32_t, 3>> f;
};

Body bodyOf(const TriangleMesh& m) {
    Body b;
    for (size_t i = 0; i < m.vertexCount(); ++i)
        b.v.push_back({m.positions()[3 * i], m.positions()[3 * i + 1], m.positions()[3 * i + 2]});
    for (size_t t = 0; t < m.triangleCount(); ++t) b.f.push_back({m.indices()[3 * t], m.indices()[3 * t + 1], m.indices()[3 * t + 2]});
    return b;
}

// Turned by `degrees` about the unit axis (x, y, z) (Rodrigues), then moved by `t`.
Body moved(Body b, std::array<double, 3> axis, double degrees, std::array<double, 3> t) {
    const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    const double x = axis[0] / n, y = axis[1] / n, z = axis[2] / n, a = degrees * M_PI / 180, c = std::cos(a), s = std::sin(a), C = 1 - c;
    const double R[9] = {c + x * x * C, x * y * C - z * s, x * z * C + y * s, y * x * C + z * s, c + y * y * C,
                         y * z * C - x * s, z * x * C - y * s, z * y * C + x * s, c + z * z * C};
    for (auto& p : b.v) {
        const std::array<double, 3> q = p;
        for (int r = 0; r < 3; ++r) p[size_t(r)] = R[3 * r] * q[0] + R[3 * r + 1] * q[1] + R[3 * r + 2] * q[2] + t[size_t(r)];
    }
    return b;
}

Body renumbered(Body b, unsigned seed) {
    std::vector<uint32_t> order(b.v.size());
    std::iota(order.begin(), order.end(), 0u);
    std::mt19937 rng(seed);
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<uint32_t> newOf(order.size());
    Body out;
    for (uint32_t k = 0; k < order.size(); ++k) {
        newOf[order[k]] = k;
        out.v.push_back(b.v[order[k]]);
    }
    for (const auto& f : b.f) out.f.push_back({newOf[f[1]], newOf[f[2]], newOf[f[0]]});  // started elsewhere, same winding
    std::shuffle(out.f.begin(), out.f.end(), rng);
    return out;
}

Body mirrored(Body b) {  // x -> -x, wound outward again
    for (auto& p : b.v) p[0] = -p[0];
    for (auto& f : b.f) std::swap(f[1], f[2]);
    return b;
}

Body scaled(Body b, double s) {
    for (auto& p : b.v)
        for (double& c : p) c *= s;
    return b;
}

fs::path writeObj(const fs::path& file, const std::vector<Body>& bodies) {
    std::ofstream out(file);
    char line[128];
    uint32_t base = 1;
    for (const Body& b : bodies) {
        for (const auto& p : b.v) {
            std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
            out << line;
        }
        for (const auto& f : b.f) out << "f " << base + f[0] << " " << base + f[1] << " " << base + f[2] << "\n";
        base += uint32_t(b.v.size());
    }
    return file;
}

Image render(SceneDesc s) {  // small and quick
    s.settings.width = 160, s.settings.height = 120, s.settings.threads = 2;
    return test::renderFirstCamera(s);
}

TEST(MeshBodies, RepeatedBodiesOfAMeshFileAreStoredOnce) {
    const Body knot = bodyOf(makeTorusKnot(2, 3, 96, 8, 0.25f));
    const Body box = bodyOf(makeBox());
    const Body sphere = bodyOf(makeSphere(8, 12));
    const fs::path file = writeObj(test::scratchDir() / "plant.obj",
                                   {moved(knot, {0, 1, 0}, 0, {0, 0, 0}), moved(renumbered(knot, 7), {1, 1, 0}, 40, {3, 0, 0}),
                                    moved(mirrored(knot), {0, 1, 0}, 20, {-3, 0, 0}), moved(box, {0, 0, 1}, 0, {0, 3, 0}),
                                    moved(box, {0, 1, 1}, 65, {3, 3, 0}), moved(sphere, {0, 1, 0}, 0, {-3, 3, 0}),
                                    moved(scaled(box, 1.001), {0, 1, 0}, 10, {0, -3, 0})});
    SceneLoadOptions off;
    off.shareCongruent = false;
    const SceneDesc whole = sceneFromMeshFile(file, off);
    ASSERT_EQ(whole.meshes.size(), 1u);
    const size_t triangles = whole.meshes[0].mesh->triangleCount();
    const SceneDesc shared = sceneFromMeshFile(file);
    ASSERT_EQ(shared.meshes.size(), 3u) << "the bodies without copies, the knot, the box";
    ASSERT_EQ(shared.instances.size(), 5u);
    EXPECT_EQ(shared.meshes[0].mesh->triangleCount(), knot.f.size() + sphere.f.size() + box.f.size())
        << "the mirrored knot, the sphere and the scaled box, together";
    EXPECT_EQ(shared.meshes[1].mesh->triangleCount(), knot.f.size());
    EXPECT_EQ(shared.meshes[2].mesh->triangleCount(), box.f.size());
    size_t placed = 0;
    for (const InstanceDesc& in : shared.instances) placed += shared.meshes[size_t(in.mesh)].mesh->triangleCount();
    EXPECT_EQ(placed, triangles) << "every triangle of the file placed once";
    EXPECT_EQ(shared.materials.size(), 1u);
    EXPECT_EQ(shared.materials[0].color, whole.materials[0].color);

    // The same picture, within float rounding of the moved copies' vertices.
    const Image a = render(shared), b = render(whole);
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    size_t differing = 0, lit = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        differing += a.rgb[i] != b.rgb[i];
        lit += b.rgb[i] > 30;
    }
    EXPECT_GT(lit, a.rgb.size() / 20) << "the bodies are in view";
    EXPECT_LT(differing, a.rgb.size() / 200) << "under 0.5% of the bytes";

    // A mesh of one body, and a soup of unconnected triangles, stay as they are.
    const fs::path single = writeObj(test::scratchDir() / "one.obj", {knot});
    EXPECT_EQ(sceneFromMeshFile(single).meshes.size(), 1u);
    Body soup;
    for (const auto& f : box.f) {
        const auto n = uint32_t(soup.v.size());
        for (uint32_t k : f) soup.v.push_back(box.v[k]);
        soup.f.push_back({n, n + 1, n + 2});
    }
    const fs::path unwelded = writeObj(test::scratchDir() / "soup.obj", {soup, moved(soup, {0, 1, 0}, 0, {3, 0, 0})});
    EXPECT_EQ(sceneFromMeshFile(unwelded).meshes.size(), 1u);
}

}  // namespace
}  // namespace rtwall
