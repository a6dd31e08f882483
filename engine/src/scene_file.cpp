// TOML scene files (format documented in configs/README.md), read section by section from the
// key tables in scene_file_keys.h: the settings, materials, lights, section planes, cameras and
// [parts] here, the geometry in scene_file_geometry.cpp.
#include "scene_file.h"
#include "scene_file_keys.h"
#include "texture.h"
#include "volume.h"

#include <rtwall/engine.h>
#include <rtwall/vec.h>

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>

namespace rtwall {

ViewMode viewModeFromName(const std::string& name) {
    if (name == "shaded") return ViewMode::Shaded;
    if (name == "depth") return ViewMode::Depth;
    if (name == "rays") return ViewMode::Rays;
    if (name == "tile_time") return ViewMode::TileTime;
    if (name == "client") return ViewMode::Client;
    throw InputError("unknown view '" + name + "' (shaded, depth, rays, tile_time, client)");
}

DenoiseSettings::Mode denoiseModeFromName(const std::string& name) {
    if (name == "off") return DenoiseSettings::Mode::Off;
    if (name == "temporal") return DenoiseSettings::Mode::Temporal;
    if (name == "svgf") return DenoiseSettings::Mode::Svgf;
    throw InputError("unknown denoise mode '" + name + "' (off, temporal, svgf)");
}

const char* denoiseModeName(DenoiseSettings::Mode mode) {
    switch (mode) {
    case DenoiseSettings::Mode::Off: return "off";
    case DenoiseSettings::Mode::Temporal: return "temporal";
    case DenoiseSettings::Mode::Svgf: return "svgf";
    }
    return "off";
}

namespace {

MaterialType materialTypeFromName(const std::string& type) {
    return type == "phong"      ? MaterialType::Phong
           : type == "mirror"   ? MaterialType::Mirror
           : type == "glass"    ? MaterialType::Glass
           : type == "metal"    ? MaterialType::Metal
           : type == "emissive" ? MaterialType::Emissive
           : type == "volume"   ? MaterialType::Volume
                                : MaterialType::Lambert;
}

using scene_file::Load;
using toml_reader::Reader;
using toml_reader::forEachTable;
using toml_reader::sectionReader;

// A texture given by `<prefix>` (a pattern name or "image") and its `<prefix>_...` keys.
TextureDesc readTexture(Reader& r, const std::filesystem::path& dir, const std::string& prefix) {
    TextureDesc t;
    if (!r.has(prefix)) return t;
    const std::string kind = r.choice(prefix, "");
    t.kind = kind == "checker" ? TextureKind::Checker
             : kind == "marble" ? TextureKind::Marble
             : kind == "wood"   ? TextureKind::Wood
                                : TextureKind::Image;
    if (t.kind == TextureKind::Image) {
        const std::string file = r.string(prefix + "_file", "", true);
        t.file = (dir / file).string();
        try {
            loadTextureImage(t.file);
        } catch (const InputError& e) {
            r.fail(r.find(prefix + "_file"), std::string("key '") + prefix + "_file': " + e.what());
        }
    }
    t.color2 = r.vec3(prefix + "_color2", t.color2);
    t.scale = float(r.number(prefix + "_scale", t.scale));
    // Without a mapping: the mesh's UVs where it has them, else xz ("auto").
    const std::string mapping = r.choice(prefix + "_mapping", "auto");
    t.mapping = mapping == "xy"            ? TextureMapping::PlanarXY
                : mapping == "yz"          ? TextureMapping::PlanarYZ
                : mapping == "spherical"   ? TextureMapping::Spherical
                : mapping == "cylindrical" ? TextureMapping::Cylindrical
                : mapping == "uv"          ? TextureMapping::Uv
                : mapping == "xz"          ? TextureMapping::PlanarXZ
                                           : TextureMapping::Auto;
    return t;
}

void checkUnit(Reader& r, const std::string& key, const Color& c) {
    if (maxComponent(c) > 1.0f || std::min({c.x, c.y, c.z}) < 0.0f)
        r.fail(r.find(key), "key '" + key + "': components must lie in [0, 1]");
}

void checkNonNegative(Reader& r, const std::string& key, const Color& c) {
    if (std::min({c.x, c.y, c.z}) < 0.0f) r.fail(r.find(key), "key '" + key + "': components must not be negative");
}

void readSettings(Reader& top, const std::filesystem::path& file, RenderSettings& s) {
    if (auto r = sectionReader(top, file, scene_keys::kImage)) {
        toml_reader::readFields<RenderSettings>(
            *r, s, {{"width", &RenderSettings::width}, {"height", &RenderSettings::height}, {"tile", &RenderSettings::tileSize}});
        r->finish();
    }
    if (auto r = sectionReader(top, file, scene_keys::kRender)) {
        s.kernel = r->choice("kernel", "packet") == "single" ? KernelType::Single : KernelType::Packet;
        s.shading = r->choice("shading", "full") == "eyelight" ? ShadingMode::EyeLight : ShadingMode::Full;
        toml_reader::readFields<RenderSettings>(
            *r, s,
            {{"max_depth", &RenderSettings::maxDepth}, {"supersample", &RenderSettings::supersample},
             {"shadows", &RenderSettings::shadows}, {"background", &RenderSettings::background},
             {"ambient", &RenderSettings::ambient}, {"threads", &RenderSettings::threads},
             {"prune_threshold", &RenderSettings::pruneThreshold}, {"gi", &RenderSettings::gi},
             {"samples", &RenderSettings::samples}});
        s.view = viewModeFromName(r->choice("view", "shaded"));
        r->finish();
    }
}

void readDenoise(Reader& top, const std::filesystem::path& file, DenoiseSettings& d) {
    auto r = sectionReader(top, file, scene_keys::kDenoise);
    if (!r) return;
    d.mode = denoiseModeFromName(r->choice("mode", denoiseModeName(d.mode)));
    toml_reader::readFields<DenoiseSettings>(
        *r, d,
        {{"levels", &DenoiseSettings::levels}, {"history", &DenoiseSettings::history},
         {"sigma_depth", &DenoiseSettings::sigmaDepth}, {"sigma_normal", &DenoiseSettings::sigmaNormal},
         {"sigma_luminance", &DenoiseSettings::sigmaLuminance}});
    r->finish();
}

void readBvh(Reader& top, const std::filesystem::path& file, BvhSettings& b) {
    auto r = sectionReader(top, file, scene_keys::kBvh);
    if (!r) return;
    const std::string q = r->choice("quality", "medium");
    b.quality = q == "low" ? BvhSettings::Quality::Low : q == "high" ? BvhSettings::Quality::High : BvhSettings::Quality::Medium;
    b.compact = r->boolean("compact", b.compact);
    b.robust = r->boolean("robust", b.robust);
    const std::string prims = r->choice("primitives", "auto");
    b.primitives = prims == "triangles" ? BvhSettings::Primitives::Triangles : BvhSettings::Primitives::Auto;
    r->finish();
}

struct LoadSettings {
    bool cache = false;
    std::filesystem::path cacheDir;
};

LoadSettings readLoad(Reader& top, const std::filesystem::path& file) {
    LoadSettings l;
    auto r = sectionReader(top, file, scene_keys::kLoad);
    if (!r) return l;
    l.cache = r->boolean("cache", l.cache);
    const std::string dir = r->string("cache_dir", "");
    if (!dir.empty()) l.cacheDir = file.parent_path() / dir;
    r->finish();
    return l;
}

scene_file::ImportSettings readImport(Reader& top, const std::filesystem::path& file, scene_file::ImportSettings s) {
    auto r = sectionReader(top, file, scene_keys::kImport);
    if (!r) return s;
    scene_file::readDeflections(*r, s);
    s.shareCongruent = r->boolean("share_congruent", s.shareCongruent);
    s.congruenceTolerance = r->number("congruence_tolerance", s.congruenceTolerance);
    r->finish();
    return s;
}

// A volume material's data file, ray-march step and transfer function.
void readVolume(Reader& r, const std::filesystem::path& dir, Material& m) {
    m.volumeFile = (dir / r.string("volume_file", "", true)).string();
    try {
        loadVolume(m.volumeFile);
    } catch (const InputError& e) {
        r.fail(r.find("volume_file"), std::string("key 'volume_file': ") + e.what());
    }
    m.volumeStep = float(r.number("volume_step", m.volumeStep));
    const toml::node* n = r.find("transfer");
    if (!n) return;
    const toml::array* a = n->as_array();
    if (!a || a->empty()) r.fail(n, "key 'transfer': expected an array of [value, r, g, b, density]");
    for (const toml::node& e : *a) {
        const toml::array* p = e.as_array();
        double v[5];
        if (!p || p->size() != 5) r.fail(&e, "key 'transfer': each point is [value, r, g, b, density]");
        for (int k = 0; k < 5; ++k) {
            const auto* x = p->get(size_t(k));
            if (auto i = x->as_integer()) v[k] = double(i->get());
            else if (auto f = x->as_floating_point()) v[k] = f->get();
            else r.fail(x, "key 'transfer': expected numbers");
            if (!std::isfinite(v[k])) r.fail(x, "key 'transfer': values must be finite");
        }
        if (v[1] < 0 || v[2] < 0 || v[3] < 0 || v[4] < 0)
            r.fail(&e, "key 'transfer': colour and density must not be negative");
        m.transfer.push_back({float(v[0]), {float(v[1]), float(v[2]), float(v[3])}, float(v[4])});
    }
}

void readMaterial(Load& l, Reader& r) {
    Material m;
    m.name = r.string("name", "", true);
    if (l.materialIndex.count(m.name)) r.fail(r.find("name"), "material name '" + m.name + "' is used twice");
    m.type = materialTypeFromName(r.choice("type", "lambert"));
    const bool diffuse = m.type == MaterialType::Lambert || m.type == MaterialType::Phong;
    m.texture = readTexture(r, l.dir, "texture");
    m.color = r.vec3("color", diffuse && m.texture.kind != TextureKind::Image ? Color{0.8f, 0.8f, 0.8f} : Color{1, 1, 1});
    checkUnit(r, "texture_color2", m.texture.color2);
    if (m.type == MaterialType::Metal) m.roughness = float(r.number("roughness", m.roughness));
    if (m.type == MaterialType::Glass) {
        m.absorption = r.vec3("absorption", m.absorption);
        checkNonNegative(r, "absorption", m.absorption);
    }
    m.emission = r.vec3("emission", m.type == MaterialType::Emissive ? Color{1, 1, 1} : Color{0, 0, 0});
    checkNonNegative(r, "emission", m.emission);
    if (m.type != MaterialType::Volume) m.twoSided = r.boolean("two_sided", m.twoSided);
    m.bump = float(r.number("bump", m.bump));
    m.bumpScale = float(r.number("bump_scale", m.bumpScale));
    const std::string bumpMapping = r.choice("bump_mapping", "auto");
    m.bumpMapping = bumpMapping == "uv"       ? TextureMapping::Uv
                    : bumpMapping == "object" ? TextureMapping::Object
                                              : TextureMapping::Auto;
    m.alpha = readTexture(r, l.dir, "alpha");
    m.alphaCutoff = float(r.number("alpha_cutoff", m.alphaCutoff));
    m.alphaChannel = r.choice("alpha_channel", "red") == "alpha" ? AlphaChannel::Alpha : AlphaChannel::Red;
    m.alphaMode = r.choice("alpha_mode", "mask") == "hashed" ? AlphaMode::Hashed : AlphaMode::Mask;
    m.opacity = float(r.number("opacity", m.opacity));
    if (m.type == MaterialType::Volume) readVolume(r, l.dir, m);
    if (m.type == MaterialType::Phong) {
        m.specular = r.vec3("specular", {0.5f, 0.5f, 0.5f});
        m.shininess = float(r.number("shininess", m.shininess));
    }
    if (m.type == MaterialType::Glass) m.ior = float(r.number("ior", m.ior));
    if (maxComponent(m.color) > 1.0f || std::min({m.color.x, m.color.y, m.color.z}) < 0.0f)
        r.fail(r.find("color"), "key 'color': components must lie in [0, 1] (a surface cannot reflect more than it receives)");
    l.materialIndex[m.name] = uint32_t(l.scene.materials.size());
    l.scene.materials.push_back(m);
}

// Positions of lights, section planes and cameras stay in the file's double-precision
// coordinates until the rebase.
struct FilePositions {
    std::vector<std::array<double, 3>> lights, sectionPoints, cameras, cameraTargets;
};

void readLight(Reader& r, SceneDesc& scene, FilePositions& at) {
    Light l;
    std::array<double, 3> position{0, 10, 0};
    const std::string type = r.choice("type", "point");
    l.type = type == "directional" ? LightType::Directional : type == "area" ? LightType::Area : LightType::Point;
    if (l.type == LightType::Point) position = r.vec3d("position", {}, true);
    else if (l.type == LightType::Area) {
        position = r.vec3d("position", {}, true);
        l.edge1 = r.vec3("edge1", {}, true);
        l.edge2 = r.vec3("edge2", {}, true);
        if (length(cross(l.edge1, l.edge2)) == 0.0f) r.fail(r.find("edge2"), "key 'edge2': the area light has no area");
        l.twoSided = r.boolean("two_sided", l.twoSided);
    } else {
        l.direction = r.vec3("direction", {}, true);
        if (dot(l.direction, l.direction) == 0.0f) r.fail(r.find("direction"), "key 'direction' must not be zero");
    }
    if (l.type != LightType::Area && r.has("two_sided"))
        r.fail(r.find("two_sided"), "key 'two_sided': only area lights have sides");
    l.color = r.vec3("color", l.color);
    l.intensity = float(r.number("intensity", 1.0));
    scene.lights.push_back(l);
    at.lights.push_back(position);
}

// Section planes: slot i is the i-th [[section]].
void readSection(Reader& r, SceneDesc& scene, FilePositions& at) {
    if (at.sectionPoints.size() == size_t(kMaxSections))
        r.fail(nullptr, "more than " + std::to_string(kMaxSections) + " [[section]] planes (the renderer clips by at most " +
                            std::to_string(kMaxSections) + ")");
    SectionPlane p;
    const std::array<double, 3> point = r.vec3d("point", {}, true);
    p.normal = r.vec3("normal", {}, true);
    if (dot(p.normal, p.normal) == 0.0f) r.fail(r.find("normal"), "key 'normal' must not be zero");
    p.capColor = r.vec3("cap_color", p.capColor);
    checkUnit(r, "cap_color", p.capColor);
    p.caps = r.boolean("caps", p.caps);
    p.enabled = r.boolean("enabled", true);
    scene.sections[at.sectionPoints.size()] = p;
    at.sectionPoints.push_back(point);
}

void readCamera(Reader& r, SceneDesc& scene, FilePositions& at) {
    CameraDesc c;
    c.name = r.string("name", "camera" + std::to_string(scene.cameras.size() + 1));
    if (scene.findCamera(c.name)) r.fail(r.find("name"), "camera name '" + c.name + "' is used twice");
    const std::array<double, 3> p = r.vec3d("position", {}, true), target = r.vec3d("look_at", {}, true);
    c.up = r.vec3("up", c.up);
    c.fovY = float(r.number("fov", c.fovY));
    const Float3 view{float(target[0] - p[0]), float(target[1] - p[1]), float(target[2] - p[2])};
    if (length(view) == 0.0f) r.fail(r.find("look_at"), "camera looks at its own position");
    if (length(cross(view, c.up)) == 0.0f) r.fail(r.find("up"), "key 'up' is parallel to the viewing direction");
    scene.cameras.push_back(c);
    at.cameras.push_back(p);
    at.cameraTargets.push_back(target);
}

// [parts]: hide, isolate and highlight by name, once every instance is known.
void readParts(Reader& top, const std::filesystem::path& file, SceneDesc& scene) {
    auto r = sectionReader(top, file, scene_keys::kParts);
    if (!r) return;
    PartView view;
    auto patterns = [&](const char* key, std::vector<std::string>& out) {
        const toml::node* n = r->find(key);
        if (!n) return;
        const toml::array* a = n->as_array();
        if (!a) r->fail(n, std::string("key '") + key + "': expected an array of strings");
        for (const toml::node& e : *a) {
            const auto v = e.value<std::string>();
            if (!v || !e.is_string() || v->empty()) r->fail(&e, std::string("key '") + key + "': expected non-empty strings");
            out.push_back(*v);
            try {
                if (instancesMatching(scene, *v).empty()) throw InputError("no part or mesh matches it");
            } catch (const InputError& err) {
                r->fail(&e, std::string("key '") + key + "': '" + *v + "': " + err.what());
            }
        }
    };
    patterns("hide", view.hide);
    patterns("isolate", view.isolate);
    patterns("highlight", view.highlight);
    r->finish();
    applyPartView(scene, view);
}

// Everything the renderer sees in single precision becomes relative to one origin near the
// geometry, computed and subtracted in double precision.
void rebase(SceneDesc& scene, const FilePositions& at) {
    scene.origin = scene_file::rebaseOrigin(scene);
    const auto& o = scene.origin;
    auto rel = [&](const std::array<double, 3>& p) { return Float3{float(p[0] - o[0]), float(p[1] - o[1]), float(p[2] - o[2])}; };
    for (InstanceDesc& in : scene.instances) {
        in.transform.m[3] -= o[0];
        in.transform.m[7] -= o[1];
        in.transform.m[11] -= o[2];
    }
    for (size_t i = 0; i < scene.lights.size(); ++i)
        if (scene.lights[i].type != LightType::Directional) scene.lights[i].position = rel(at.lights[i]);
    for (size_t i = 0; i < at.sectionPoints.size(); ++i) scene.sections[i].point = rel(at.sectionPoints[i]);
    for (size_t i = 0; i < scene.cameras.size(); ++i) {
        scene.cameras[i].position = rel(at.cameras[i]);
        scene.cameras[i].lookAt = rel(at.cameraTargets[i]);
    }
}

// The bytes of every mesh file, for progress.
double meshBytes(const toml::table& root, const std::filesystem::path& dir) {
    double total = 0;
    if (const toml::array* meshes = root["mesh"].as_array())
        for (const toml::node& m : *meshes)
            if (const toml::table* t = m.as_table())
                if (auto f = (*t)["file"].value<std::string>()) {
                    std::error_code ec;
                    const auto size = std::filesystem::file_size(dir / *f, ec);
                    if (!ec) total += double(size);
                }
    return total;
}

}  // namespace

SceneDesc loadSceneFile(const std::filesystem::path& file) { return loadSceneFile(file, SceneLoadOptions{}); }

SceneDesc loadSceneFile(const std::filesystem::path& file, const SceneLoadOptions& options) {
    const toml::table root = toml_reader::parseFile(file);

    Load l(file, options);
    SceneDesc& scene = l.scene;
    scene.sourceFile = file;
    Reader top(file, root, "", scene_keys::kTop);
    readSettings(top, file, scene.settings);
    readBvh(top, file, scene.bvh);
    readDenoise(top, file, scene.denoise);
    const LoadSettings load = readLoad(top, file);
    l.meshOptions.cache = options.cache.value_or(load.cache);
    l.meshOptions.cacheDir = load.cacheDir;
    l.import = readImport(top, file, {options.linearDeflection, options.angularDeflection});
    if (options.progress) l.bytesTotal = meshBytes(root, l.dir);

    scene_file::readMeshes(top, l);
    if (options.progress && !options.progress(1.0)) throw Cancelled();
    forEachTable(top, file, scene_keys::kMaterial, [&](Reader& r, const toml::table&) { readMaterial(l, r); });
    scene_file::readInstances(top, l);
    FilePositions at;
    forEachTable(top, file, scene_keys::kLight, [&](Reader& r, const toml::table&) { readLight(r, scene, at); });
    forEachTable(top, file, scene_keys::kSection, [&](Reader& r, const toml::table&) { readSection(r, scene, at); });
    forEachTable(top, file, scene_keys::kCamera, [&](Reader& r, const toml::table&) { readCamera(r, scene, at); });
    readParts(top, file, scene);
    top.finish();

    rebase(scene, at);
    if (scene.cameras.empty()) scene.cameras.push_back(scene_file::framingCamera(scene.worldBounds()));
    return std::move(scene);
}

}  // namespace rtwall
