// Scenes of one mesh or assembly file (no scene file around them), how an assembly's materials
// become rtwall's, and the framing camera and far-from-origin rebase every kind of scene uses.
#include "scene_file.h"

#include <rtwall/vec.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

namespace rtwall {

namespace scene_file {

std::array<double, 3> rebaseOrigin(const SceneDesc& scene) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    std::vector<Bounds3> meshBounds(scene.meshes.size());
    std::vector<bool> known(scene.meshes.size(), false);
    for (const InstanceDesc& in : scene.instances) {
        if (!known[in.mesh]) {
            meshBounds[in.mesh] = scene.meshes[in.mesh].mesh->bounds();
            known[in.mesh] = true;
        }
        const Bounds3& b = meshBounds[in.mesh];
        if (b.empty()) continue;
        const auto& m = in.transform.m;
        for (int corner = 0; corner < 8; ++corner) {
            const double p[3] = {(corner & 1) ? b.hi.x : b.lo.x, (corner & 2) ? b.hi.y : b.lo.y, (corner & 4) ? b.hi.z : b.lo.z};
            for (int i = 0; i < 3; ++i) {
                const double w = m[4 * i] * p[0] + m[4 * i + 1] * p[1] + m[4 * i + 2] * p[2] + m[4 * i + 3];
                lo[i] = std::min(lo[i], w);
                hi[i] = std::max(hi[i], w);
            }
        }
    }
    double farthest = 0, extent = 0, centre[3];
    for (int i = 0; i < 3; ++i) {
        if (!(lo[i] <= hi[i])) return {0, 0, 0};
        centre[i] = 0.5 * (lo[i] + hi[i]);
        farthest = std::max(farthest, std::fabs(centre[i]));
        extent = std::max(extent, hi[i] - lo[i]);
    }
    if (farthest < 1024.0 || farthest <= extent) return {0, 0, 0};
    return {std::round(centre[0]), std::round(centre[1]), std::round(centre[2])};
}

CameraDesc framingCamera(const Bounds3& b) {
    CameraDesc c;
    c.name = "default";
    if (b.empty()) return c;
    const Float3 center = (b.lo + b.hi) * 0.5f;
    const float radius = std::max(1e-6f, 0.5f * length(b.hi - b.lo));
    c.fovY = 40.0f;
    // Far enough that the bounding sphere fits the vertical field of view, seen from the front-right, slightly above.
    const float dist = radius / std::sin(float(c.fovY * std::numbers::pi / 360.0)) * 1.05f;
    c.position = center + normalize(Float3{0.45f, 0.35f, 1.0f}) * dist;
    c.lookAt = center;
    c.up = {0, 1, 0};
    return c;
}

}  // namespace scene_file

// glTF's metallic-roughness model onto rtwall's kinds (the table in README.md): transmission
// of one half or more is glass of the given ior, tinted by the base colour; metallic of one half
// or more is metal of the base colour and roughness; everything else is Phong with the base
// colour as albedo and glTF's dielectric reflectance 0.04 as specular, in a lobe as sharp as the
// metal's for that roughness (exponent 2/r^2 - 2, at least 1). Emission adds to any kind. The
// base colour texture modulates the colour through the mesh's UVs.
Material materialFromAssembly(const AssemblyMaterial& a) {
    Material m;
    m.name = a.name;
    m.color = {a.baseColor[0], a.baseColor[1], a.baseColor[2]};
    if (a.transmission >= 0.5f) {
        m.type = MaterialType::Glass;
        m.ior = a.ior;
    } else if (a.metallic >= 0.5f) {
        m.type = MaterialType::Metal;
        m.roughness = a.roughness;
    } else {
        m.type = MaterialType::Phong;
        m.specular = {0.04f, 0.04f, 0.04f};
        const float r = std::max(a.roughness, 0.01f);
        m.shininess = std::max(1.0f, 2.0f / (r * r) - 2.0f);
    }
    m.emission = {a.emissive[0], a.emissive[1], a.emissive[2]};
    if (!a.baseColorTexture.empty()) {
        m.texture.kind = TextureKind::Image;
        m.texture.file = a.baseColorTexture;
        m.texture.mapping = TextureMapping::Auto;  // the mesh's UVs where it has them
    }
    // Alpha: the base colour's alpha times the texture's alpha channel. MASK cuts holes below the
    // cutoff; BLEND becomes a hashed alpha, which converges to blending as samples accumulate.
    if (a.alphaMode != AssemblyMaterial::Alpha::Opaque) {
        m.opacity = std::clamp(a.baseColor[3], 0.0f, 1.0f);
        m.alphaChannel = AlphaChannel::Alpha;
        m.alphaCutoff = a.alphaCutoff;
        m.alphaMode = a.alphaMode == AssemblyMaterial::Alpha::Blend ? AlphaMode::Hashed : AlphaMode::Mask;
        if (!a.baseColorTexture.empty()) m.alpha = m.texture;
    }
    m.twoSided = a.doubleSided;
    return m;
}

namespace {

// A head light from above the camera's right shoulder, plus a soft ambient term so nothing is pitch black.
void addHeadLight(SceneDesc& scene) {
    const CameraDesc& c = scene.cameras.front();
    Light key;
    key.type = LightType::Directional;
    key.direction = normalize((c.lookAt - c.position) + Float3{-0.3f, -0.5f, 0.0f} * length(c.lookAt - c.position));
    key.intensity = 2.5f;
    scene.lights.push_back(key);
    scene.settings.ambient = {0.15f, 0.15f, 0.15f};
}

}  // namespace

SceneDesc sceneFromAssembly(const Assembly& a, const std::filesystem::path& file) {
    SceneDesc scene;
    scene.sourceFile = file;
    for (size_t i = 0; i < a.meshes.size(); ++i) {
        MeshDesc md;
        md.name = a.meshNames[i];
        md.source = file.string() + "#" + a.meshNames[i];
        md.mesh = a.meshes[i];
        scene.meshes.push_back(std::move(md));
    }
    for (const AssemblyMaterial& m : a.materials) scene.materials.push_back(materialFromAssembly(m));
    if (scene.materials.empty()) scene.materials.push_back(Material{});
    scene.instances.reserve(a.instances.size());
    for (const AssemblyInstance& ai : a.instances) {
        InstanceDesc in;
        in.mesh = ai.mesh;
        in.material = ai.material;
        in.transform.m = ai.transform;
        in.part = ai.part;
        scene.instances.push_back(in);
    }
    for (const AssemblyPart& p : a.parts) scene.parts.push_back({p.name, p.parent});
    scene.files = a.files;
    // Far-from-origin assemblies are rebased as scene files are.
    scene.origin = scene_file::rebaseOrigin(scene);
    for (InstanceDesc& in : scene.instances) {
        in.transform.m[3] -= scene.origin[0];
        in.transform.m[7] -= scene.origin[1];
        in.transform.m[11] -= scene.origin[2];
    }
    scene.cameras.push_back(scene_file::framingCamera(scene.worldBounds()));
    addHeadLight(scene);
    return scene;
}

SceneDesc sceneFromMeshFile(const std::filesystem::path& file) { return sceneFromMeshFile(file, SceneLoadOptions{}); }

SceneDesc sceneFromMeshFile(const std::filesystem::path& file, const SceneLoadOptions& options) {
    if (isAssemblyFile(file)) {
        AssemblyOptions ao;
        ao.linearDeflection = options.linearDeflection;
        ao.angularDeflection = options.angularDeflection;
        ao.cache = options.cache.value_or(false);
        ao.progress = options.progress;
        ao.shareCongruent = options.shareCongruent;
        const auto t0 = std::chrono::steady_clock::now();
        const Assembly a = loadAssembly(file, ao);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (options.stats) scene_file::countImport(*options.stats, a.cache, seconds);
        return sceneFromAssembly(a, file);
    }
    Material m;
    m.name = "default";
    m.type = MaterialType::Phong;
    m.color = {0.7f, 0.7f, 0.72f};
    m.specular = {0.2f, 0.2f, 0.2f};
    auto mesh = std::make_shared<const TriangleMesh>(loadMesh(file));
    if (options.shareCongruent) {
        // Repeated bodies (a plant exported as one mesh): the distinct ones, placed by instances.
        const Assembly a = shareCongruentBodies(mesh, file.stem().string());
        if (a.congruentMeshes > 0) {
            SceneDesc scene = sceneFromAssembly(a, file);  // its meshes' sources are "FILE#NAME", as assemblies'
            scene.materials.assign(1, m);
            return scene;
        }
    }
    SceneDesc scene;
    scene.sourceFile = file;
    MeshDesc md;
    md.name = file.stem().string();
    md.source = file.string();
    md.mesh = std::move(mesh);
    scene.meshes.push_back(md);
    // A far-from-origin file is stored recentred; the scene stays in those small coordinates
    // and records where they lie.
    scene.origin = md.mesh->origin();
    scene.materials.push_back(m);
    scene.instances.push_back(InstanceDesc{});
    scene.cameras.push_back(scene_file::framingCamera(scene.worldBounds()));
    addHeadLight(scene);
    return scene;
}

}  // namespace rtwall
