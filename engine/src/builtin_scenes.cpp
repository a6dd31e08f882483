// Scenes built in code, shared by tests, benchmarks and examples.

#include <rtwall/engine.h>
#include <rtwall/vec.h>

#include <algorithm>
#include <cmath>

namespace rtwall {

namespace {

SceneDesc knotField(int64_t triangles) {
    // A 4 x 3 grid of distinct torus knots (different p, q: twelve unique meshes, nothing
    // instanced twice) on a floor, so that the benchmark's triangles are all unique.
    SceneDesc s;
    const int cols = 4, rows = 3, knots = cols * rows;
    const int sides = 48;
    const int segments = std::max<int>(8, int(std::max<int64_t>(triangles, 1000) / knots / (2 * sides)));
    const int pq[knots][2] = {{2, 3}, {3, 2}, {2, 5}, {3, 4}, {3, 5}, {4, 3}, {2, 7}, {5, 2}, {3, 7}, {5, 3}, {4, 5}, {5, 4}};
    Material floor;
    floor.name = "floor";
    floor.color = {0.6f, 0.6f, 0.6f};
    Material knot;
    knot.name = "knot";
    knot.type = MaterialType::Phong;
    knot.color = {0.7f, 0.35f, 0.2f};
    knot.specular = {0.3f, 0.3f, 0.3f};
    knot.shininess = 40.0f;
    s.materials = {floor, knot};
    s.meshes.push_back({"floor", "shape:quad", std::make_shared<const TriangleMesh>(makeQuad())});
    s.instances.push_back({0, 0, Transform::translate(0, -1.1, 0) * Transform::scale(6, 1, 6)});
    for (int k = 0; k < knots; ++k) {
        s.meshes.push_back({"knot" + std::to_string(k), "shape:torus_knot",
                            std::make_shared<const TriangleMesh>(makeTorusKnot(pq[k][0], pq[k][1], segments, sides, 0.12f))});
        const double x = (k % cols - 1.5) * 2.2, z = (k / cols - 1.0) * 2.2;
        s.instances.push_back({uint32_t(k + 1), 1, Transform::translate(x, 0, z) * Transform::scale(0.8, 0.8, 0.8)});
    }
    s.lights.push_back({LightType::Point, {4, 8, 6}, {}, {1, 1, 1}, 300.0f});
    s.lights.push_back({LightType::Directional, {}, {-0.3f, -1.0f, -0.4f}, {0.9f, 0.95f, 1.0f}, 0.8f});
    s.cameras.push_back({"default", {0.0f, 5.5f, 7.5f}, {0, -0.3f, 0}, {0, 1, 0}, 50.0f, std::nullopt});
    s.settings.width = 1600;
    s.settings.height = 1200;
    s.settings.ambient = {0.05f, 0.05f, 0.05f};
    return s;
}

}  // namespace

SceneDesc builtinScene(const std::string& name, int64_t triangles) {
    if (name == "knots") return knotField(triangles);
    throw InputError("builtin scene '" + name + "' does not exist (known: knots)");
}

}  // namespace rtwall
