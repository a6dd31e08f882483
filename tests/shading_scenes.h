// Small scenes for the shading tests (engine and cluster): every material on one image, the
// white furnace, and a sphere over a floor anywhere (far from the origin). Texture and volume files are written into a scratch directory.
#pragma once

#include <rtwall/engine.h>
#include <rtwall/image.h>

#include "test_util.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace rtwall::test {

inline std::string writeTestTexture(const std::filesystem::path& dir) {
    Image img;
    img.width = img.height = 16;
    img.rgb.resize(16 * 16 * 3);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            uint8_t* p = img.pixel(x, y);
            p[0] = uint8_t(x * 16);
            p[1] = uint8_t(y * 16);
            p[2] = uint8_t(((x / 4 + y / 4) & 1) * 255);
        }
    const auto file = dir / "texture.png";
    writePng(img, file);
    return file.string();
}

// A blob: density falls off from the centre of a 12^3 grid.
inline std::string writeTestVolume(const std::filesystem::path& dir) {
    std::vector<float> values;
    for (int k = 0; k < 12; ++k)
        for (int j = 0; j < 12; ++j)
            for (int i = 0; i < 12; ++i) {
                const float x = (i - 5.5f) / 5.5f, y = (j - 5.5f) / 5.5f, z = (k - 5.5f) / 5.5f;
                values.push_back(std::max(0.0f, 1.0f - std::sqrt(x * x + y * y + z * z)));
            }
    const auto file = dir / "blob.vti";
    writeVolumeVti(file, 12, 12, 12, values);
    return file.string();
}

inline Material material(const std::string& name, MaterialType type, Color color) {
    Material m;
    m.name = name;
    m.type = type;
    m.color = color;
    return m;
}

// Meshes 0 and 1: the built-in quad and box.
inline void addQuadAndBox(SceneDesc& s) {
    s.meshes.push_back({"quad", "shape:quad", std::make_shared<const TriangleMesh>(makeQuad())});
    s.meshes.push_back({"box", "shape:box", std::make_shared<const TriangleMesh>(makeBox())});
}

// A white floor material and a green leaf whose alpha is a checker of `cells`-unit cells: black
// cells are holes (for the alpha-mask tests).
inline std::vector<Material> floorAndCheckerLeaf(float cells) {
    Material floor;
    floor.color = {1, 1, 1};
    Material leaf;
    leaf.color = {0, 1, 0};
    leaf.alpha.kind = TextureKind::Checker;
    leaf.alpha.color2 = {0, 0, 0};
    leaf.alpha.scale = cells;
    return {floor, leaf};
}

// A directional light straight down.
inline Light sunFromAbove() {
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0, -1, 0};
    return sun;
}

// Every material kind, textures, a bump, an alpha mask, a volume, glass with absorption; a
// point light and an area light; transparent shadows on the floor.
inline SceneDesc materialZoo(const std::filesystem::path& dir, int width = 64, int height = 48) {
    SceneDesc s;
    s.meshes.push_back({"sphere", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(16, 32))});
    addQuadAndBox(s);

    Material floor = material("floor", MaterialType::Lambert, {0.8f, 0.8f, 0.8f});
    floor.texture.kind = TextureKind::Checker;
    floor.texture.scale = 0.5f;
    Material phong = material("phong", MaterialType::Phong, {0.6f, 0.2f, 0.1f});
    phong.specular = {0.3f, 0.3f, 0.3f};
    phong.texture.kind = TextureKind::Marble;
    phong.texture.color2 = {0.1f, 0.1f, 0.3f};
    Material mirror = material("mirror", MaterialType::Mirror, {0.9f, 0.9f, 0.9f});
    Material metal = material("metal", MaterialType::Metal, {0.9f, 0.7f, 0.4f});
    metal.roughness = 0.3f;
    Material glass = material("glass", MaterialType::Glass, {1, 1, 1});
    glass.absorption = {0.5f, 0.1f, 0.05f};
    Material wood = material("wood", MaterialType::Lambert, {0.6f, 0.4f, 0.2f});
    wood.texture.kind = TextureKind::Wood;
    wood.texture.color2 = {0.3f, 0.15f, 0.05f};
    wood.bump = 0.3f;
    wood.bumpScale = 0.2f;
    Material image = material("image", MaterialType::Lambert, {1, 1, 1});
    image.texture.kind = TextureKind::Image;
    image.texture.file = writeTestTexture(dir);
    image.texture.scale = 2.0f;
    Material leaf = material("leaf", MaterialType::Lambert, {0.2f, 0.7f, 0.2f});
    leaf.alpha.kind = TextureKind::Checker;
    leaf.alpha.scale = 0.25f;
    leaf.alpha.color2 = {0, 0, 0};
    Material lamp = material("lamp", MaterialType::Emissive, {1, 1, 1});
    lamp.emission = {4, 4, 3};
    Material volume = material("volume", MaterialType::Volume, {1, 1, 1});
    volume.volumeFile = writeTestVolume(dir);
    volume.transfer = {{0.0f, {1, 1, 1}, 0.0f}, {0.3f, {1.0f, 0.5f, 0.1f}, 2.0f}, {1.0f, {1, 1, 0.8f}, 8.0f}};
    s.materials = {floor, phong, mirror, metal, glass, wood, image, leaf, lamp, volume};

    auto place = [&](uint32_t mesh, uint32_t mat, Transform t) { s.instances.push_back({mesh, mat, t}); };
    place(1, 0, Transform::translate(0, -1, 0) * Transform::scale(6, 1, 6));
    place(0, 1, Transform::translate(-2.4, -0.4, 0) * Transform::scale(0.6, 0.6, 0.6));
    place(0, 2, Transform::translate(-1.2, -0.4, -1.2) * Transform::scale(0.6, 0.6, 0.6));
    place(0, 3, Transform::translate(0, -0.4, 0) * Transform::scale(0.6, 0.6, 0.6));
    place(0, 4, Transform::translate(1.2, -0.2, 0.6) * Transform::scale(0.6, 0.6, 0.6));
    place(2, 5, Transform::translate(2.4, -0.6, 0) * Transform::scale(0.4, 0.4, 0.4));
    place(2, 6, Transform::translate(-1.0, 0.6, -2.5) * Transform::scale(0.8, 0.8, 0.1));
    place(1, 7, Transform::translate(0.6, 0.5, 1.2) * Transform::rotateDegrees(1, 0, 0, 70) *
                    Transform::scale(0.6, 1, 0.6));
    place(0, 8, Transform::translate(2.0, 1.6, -1.5) * Transform::scale(0.2, 0.2, 0.2));
    place(2, 9, Transform::translate(1.4, 0.2, -1.4) * Transform::scale(0.5, 0.5, 0.5));

    Light point;
    point.position = {-2, 4, 3};
    point.intensity = 20.0f;
    Light area;
    area.type = LightType::Area;
    // The engine's area light emits on the side cross(edge1, edge2) points to (ShadeContext::
    // directLight: cosL = -dot(l, cross) / area): (1,0,0) x (0,0,1) = (0,-1,0), down onto the
    // scene. (Until issue 7's headlight work this said edge2 = (0,0,-1), which points up: the
    // light lit nothing; Zoo.AreaLightLightsTheScene guards it.)
    area.position = {0.5f, 3.5f, -1.5f};
    area.edge1 = {1, 0, 0};
    area.edge2 = {0, 0, 1};
    area.intensity = 3.0f;
    s.lights = {point, area};
    CameraDesc cam;
    cam.position = {0, 2.2f, 6.5f};
    cam.lookAt = {0, -0.2f, 0};
    s.cameras = {cam};
    s.settings.width = width;
    s.settings.height = height;
    s.settings.tileSize = 16;
    s.settings.maxDepth = 25;
    s.settings.background = {0.2f, 0.25f, 0.3f};
    return s;
}

// The zoo in tiles of 8, as the cluster tests render it; with `giSamples` > 0, path traced with
// that many samples per pixel.
inline SceneDesc zooInTilesOf8(const std::filesystem::path& dir, int width, int height, int giSamples = 0) {
    SceneDesc desc = materialZoo(dir, width, height);
    desc.settings.tileSize = 8;
    if (giSamples > 0) {
        desc.settings.gi = true;
        desc.settings.samples = giSamples;
    }
    return desc;
}

// White furnace: one white object inside a uniform environment of radiance 1, lit by nothing
// else; with GI and enough depth every pixel must be 1.
inline SceneDesc furnace(const Material& m, bool box) {
    SceneDesc s;
    s.meshes.push_back({box ? "box" : "sphere", "shape", std::make_shared<const TriangleMesh>(box ? makeBox() : makeSphere(48, 96))});
    s.materials = {m};
    s.instances.push_back({0, 0, Transform{}});
    CameraDesc cam;
    cam.position = {0, 0, 4.0f};
    cam.lookAt = {0, 0, 0};
    cam.fovY = 30.0f;
    s.cameras = {cam};
    s.settings.width = 24;
    s.settings.height = 24;
    s.settings.tileSize = 8;
    s.settings.background = {1, 1, 1};
    s.settings.ambient = {0, 0, 0};
    s.settings.gi = true;
    s.settings.maxDepth = 64;
    s.settings.pruneThreshold = 0.0f;
    s.settings.samples = 16;
    return s;
}

// A sphere over a floor at (x, y, z), a point light and a camera looking at the sphere, as
// scene-file text (the far-from-origin scene) from tests/data/scenes/sphere_over_floor.toml.
// `head` comes first ([image], [render], [bvh]), the sphere has `rings` x `segments`, and
// `moreLights` follows the point light.
inline std::string sphereOverFloor(double x, double y, double z, const std::string& head, int rings, int segments,
                                   const std::string& moreLights = "") {
    std::string text = head + "\n" + sceneText("sphere_over_floor");
    auto fill = [&](const std::string& blank, const std::string& value) {
        const size_t at = text.find(blank);
        if (at != std::string::npos) text.replace(at, blank.size(), value);
    };
    auto point = [](double px, double py, double pz) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "%.17g, %.17g, %.17g", px, py, pz);
        return std::string(buf);
    };
    fill("@RINGS@", std::to_string(rings));
    fill("@SEGMENTS@", std::to_string(segments));
    fill("@BALL@", point(x, y + 1.0, z));
    fill("@FLOOR@", point(x, y, z));
    fill("@LIGHT@", point(x + 2, y + 6, z + 3));
    fill("@MORE_LIGHTS@", moreLights);
    fill("@EYE@", point(x + 1.5, y + 3, z + 7));
    fill("@TARGET@", point(x, y + 0.8, z));
    return text;
}

}  // namespace rtwall::test
