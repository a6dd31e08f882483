// TOML scene files (format documented in configs/README.md).
#include "texture.h"
#include "volume.h"

#include <rtwall/engine.h>
#include <rtwall/toml_reader.h>
#include <rtwall/vec.h>

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <tuple>

namespace rtwall {

ViewMode viewModeFromName(const std::string& name) {
    if (name == "shaded") return ViewMode::Shaded;
    if (name == "depth") return ViewMode::Depth;
    if (name == "rays") return ViewMode::Rays;
    if (name == "tile_time") return ViewMode::TileTime;
    if (name == "client") return ViewMode::Client;
    throw InputError("unknown view '" + name + "' (shaded, depth, rays, tile_time, client)");
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

using toml_reader::Reader;
using toml_reader::forEachTable;
using toml_reader::subTable;
using toml_reader::where;

// A texture given by `<prefix>` (a pattern name or "image") and its `<prefix>_...` keys.
TextureDesc readTexture(Reader& r, const std::filesystem::path& dir, const std::string& prefix) {
    TextureDesc t;
    if (!r.has(prefix)) return t;
    const std::string kind = r.choice(prefix, "", {"checker", "marble", "wood", "image"});
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
    t.scale = float(r.number(prefix + "_scale", t.scale, 1e-6, 1e6));
    // Without a mapping: the mesh's UVs where it has them, else xz ("auto").
    const std::string mapping =
        r.choice(prefix + "_mapping", "auto", {"auto", "uv", "xz", "xy", "yz", "spherical", "cylindrical"});
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
    if (const toml::table* t = subTable(top, "image")) {
        Reader r(file, *t, "[image]: ");
        s.width = r.integer("width", s.width, 1, 16384);
        s.height = r.integer("height", s.height, 1, 16384);
        s.tileSize = r.integer("tile", s.tileSize, 1, 1024);
        r.finish();
    }
    if (const toml::table* t = subTable(top, "render")) {
        Reader r(file, *t, "[render]: ");
        s.kernel = r.choice("kernel", "packet", {"packet", "single"}) == "single" ? KernelType::Single
                                                                                   : KernelType::Packet;
        s.shading = r.choice("shading", "full", {"full", "eyelight"}) == "eyelight" ? ShadingMode::EyeLight
                                                                                     : ShadingMode::Full;
        s.maxDepth = r.integer("max_depth", s.maxDepth, 1, 64);
        s.supersample = r.integer("supersample", s.supersample, 1, 16);
        s.shadows = r.boolean("shadows", s.shadows);
        s.background = r.vec3("background", s.background);
        s.ambient = r.vec3("ambient", s.ambient);
        s.threads = r.integer("threads", s.threads, 0, 1024);
        s.pruneThreshold = float(r.number("prune_threshold", s.pruneThreshold, 0.0, 1.0));
        s.gi = r.boolean("gi", s.gi);
        s.samples = r.integer("samples", s.samples, 1, 4096);
        s.view = viewModeFromName(r.choice("view", "shaded", {"shaded", "depth", "rays", "tile_time", "client"}));
        r.finish();
    }
}

void readBvh(Reader& top, const std::filesystem::path& file, BvhSettings& b) {
    const toml::table* t = subTable(top, "bvh");
    if (!t) return;
    Reader r(file, *t, "[bvh]: ");
    const std::string q = r.choice("quality", "medium", {"low", "medium", "high"});
    b.quality = q == "low" ? BvhSettings::Quality::Low : q == "high" ? BvhSettings::Quality::High : BvhSettings::Quality::Medium;
    b.compact = r.boolean("compact", b.compact);
    b.robust = r.boolean("robust", b.robust);
    const std::string prims = r.choice("primitives", "auto", {"auto", "triangles"});
    b.primitives = prims == "triangles" ? BvhSettings::Primitives::Triangles : BvhSettings::Primitives::Auto;
    r.finish();
}

struct LoadSettings {
    bool cache = false;
    std::filesystem::path cacheDir;
};

LoadSettings readLoad(Reader& top, const std::filesystem::path& file) {
    LoadSettings l;
    const toml::table* t = subTable(top, "load");
    if (!t) return l;
    Reader r(file, *t, "[load]: ");
    l.cache = r.boolean("cache", l.cache);
    const std::string dir = r.string("cache_dir", "");
    if (!dir.empty()) l.cacheDir = file.parent_path() / dir;
    r.finish();
    return l;
}

// [import]: the STEP/IGES tessellation every [[mesh]] of such a file gets unless it says otherwise.
struct ImportSettings {
    double linearDeflection = 0.1;
    double angularDeflection = 0.5;
};

void readDeflections(Reader& r, ImportSettings& s) {
    s.linearDeflection = r.number("linear_deflection", s.linearDeflection, 1e-6, 1e6);
    s.angularDeflection = r.number("angular_deflection", s.angularDeflection, 1e-3, 3.14159);
}

// STEP and IGES: the files a [[mesh]] may give deflections for.
bool isCadFile(const std::filesystem::path& file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".step" || ext == ".stp" || ext == ".iges" || ext == ".igs";
}

void noDeflections(Reader& r) {
    for (const char* k : {"linear_deflection", "angular_deflection"})
        if (r.has(k)) r.fail(r.find(k), std::string("key '") + k + "': only STEP and IGES files are tessellated");
}

ImportSettings readImport(Reader& top, const std::filesystem::path& file, ImportSettings s) {
    const toml::table* t = subTable(top, "import");
    if (!t) return s;
    Reader r(file, *t, "[import]: ");
    readDeflections(r, s);
    r.finish();
    return s;
}

std::shared_ptr<const TriangleMesh> makeShape(Reader& r, const std::string& shape) {
    if (shape == "sphere") {
        const int rings = r.integer("rings", 32, 2, 4096), segments = r.integer("segments", 64, 3, 8192);
        return std::make_shared<const TriangleMesh>(makeSphere(rings, segments));
    }
    if (shape == "box") return std::make_shared<const TriangleMesh>(makeBox());
    if (shape == "quad") return std::make_shared<const TriangleMesh>(makeQuad());
    // torus_knot
    const int p = r.integer("p", 2, 1, 64), q = r.integer("q", 3, 1, 64);
    const int segments = r.integer("segments", 256, 3, 1 << 20), sides = r.integer("sides", 16, 3, 4096);
    const float radius = float(r.number("radius", 0.25, 1e-6, 1e6));
    if (int64_t(segments) * sides > (int64_t(1) << 26))
        r.fail(r.find("segments"), "torus_knot: segments x sides must stay below 2^26 vertices");
    return std::make_shared<const TriangleMesh>(makeTorusKnot(p, q, segments, sides, radius));
}

Transform readTransform(Reader& r) {
    // Applied in this order: scale, rotate (x, then y, then z, in degrees), translate.
    Transform t;
    if (r.has("scale")) {
        const toml::node* n = r.find("scale");
        if (n->is_number()) {
            const double s = r.number("scale", 1.0, 1e-12, 1e12);
            t = Transform::scale(s, s, s);
        } else {
            const std::array<double, 3> s = r.vec3d("scale", {1, 1, 1});
            if (s[0] == 0 || s[1] == 0 || s[2] == 0) r.fail(n, "key 'scale': factors must not be zero");
            t = Transform::scale(s[0], s[1], s[2]);
        }
    }
    const std::array<double, 3> rot = r.vec3d("rotate", {0, 0, 0});
    t = Transform::rotateDegrees(1, 0, 0, rot[0]) * t;
    t = Transform::rotateDegrees(0, 1, 0, rot[1]) * t;
    t = Transform::rotateDegrees(0, 0, 1, rot[2]) * t;
    const std::array<double, 3> tr = r.vec3d("translate", {0, 0, 0});
    return Transform::translate(tr[0], tr[1], tr[2]) * t;
}

// The centre of the instances' world bounds, rounded to a whole number, when the scene lies
// further from the origin than its own size (and at least 1024 units); else the origin.
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

}  // namespace

SceneDesc loadSceneFile(const std::filesystem::path& file) { return loadSceneFile(file, SceneLoadOptions{}); }

SceneDesc loadSceneFile(const std::filesystem::path& file, const SceneLoadOptions& options) {
    const toml::table root = toml_reader::parseFile(file);

    SceneDesc scene;
    scene.sourceFile = file;
    const std::filesystem::path dir = file.parent_path();
    Reader top(file, root, "");
    readSettings(top, file, scene.settings);
    readBvh(top, file, scene.bvh);
    const LoadSettings load = readLoad(top, file);
    LoadOptions meshOptions;
    meshOptions.cache = options.cache.value_or(load.cache);
    meshOptions.cacheDir = load.cacheDir;
    SceneLoadStats localStats;
    SceneLoadStats& stats = options.stats ? *options.stats : localStats;
    const ImportSettings import = readImport(top, file, {options.linearDeflection, options.angularDeflection});

    // Progress is counted in bytes of mesh files, which the first pass sums.
    double bytesTotal = 0, bytesDone = 0;
    if (options.progress) {
        if (const toml::array* meshes = root["mesh"].as_array())
            for (const toml::node& m : *meshes)
                if (const toml::table* t = m.as_table())
                    if (auto f = (*t)["file"].value<std::string>()) {
                        std::error_code ec;
                        const auto size = std::filesystem::file_size(dir / *f, ec);
                        if (!ec) bytesTotal += double(size);
                    }
    }

    std::map<std::string, uint32_t> meshIndex, materialIndex;
    std::map<std::filesystem::path, std::shared_ptr<const TriangleMesh>> loadedFiles;  // one copy per file
    // Assembly files (glTF, STEP, IGES) named by [[mesh]]: their meshes, materials and parts join
    // the scene once per file and tolerance; each [[instance]] of the entry places all of its
    // instances, its own transform applied on top.
    struct PlacedAssembly {
        uint32_t firstMesh = 0, firstMaterial = 0;
        int32_t firstPart = 0;
        std::vector<AssemblyInstance> instances;
    };
    std::vector<PlacedAssembly> assemblies;
    std::map<std::string, uint32_t> assemblyIndex;  // [[mesh]] name -> assemblies
    std::map<std::tuple<std::filesystem::path, double, double>, uint32_t> loadedAssemblies;
    auto loadAssemblyEntry = [&](Reader& r, const std::string& name, const std::filesystem::path& path,
                                 const std::filesystem::path& key) {
        ImportSettings tess = import;
        if (isCadFile(path)) readDeflections(r, tess);
        const auto slot = loadedAssemblies.find({key, tess.linearDeflection, tess.angularDeflection});
        if (slot != loadedAssemblies.end()) {
            assemblyIndex[name] = slot->second;
            return;
        }
        AssemblyOptions ao;
        ao.linearDeflection = tess.linearDeflection;
        ao.angularDeflection = tess.angularDeflection;
        ao.cache = meshOptions.cache;
        ao.cacheDir = meshOptions.cacheDir;
        std::error_code ec;
        const double size = double(std::filesystem::file_size(path, ec));
        if (options.progress && !ec)
            ao.progress = [&, size](double f) { return options.progress(bytesTotal > 0 ? (bytesDone + f * size) / bytesTotal : 1.0); };
        Assembly a;
        try {
            const auto t0 = std::chrono::steady_clock::now();
            a = loadAssembly(path, ao);
            const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            if (a.cache == "hit") {
                stats.cacheSeconds += dt;
                ++stats.cacheHits;
            } else {
                stats.importSeconds += dt;
                ++stats.filesImported;
                stats.cacheWritten += a.cache == "written" || a.cache.starts_with("rebuilt");
            }
        } catch (const InputError& e) {
            r.fail(r.find("file"), std::string("mesh '") + name + "': " + e.what());
        }
        if (options.progress) {
            if (!ec) bytesDone += size;
            if (!options.progress(bytesTotal > 0 ? bytesDone / bytesTotal : 1.0)) throw Cancelled();
        }
        PlacedAssembly pa;
        pa.firstMesh = uint32_t(scene.meshes.size());
        for (size_t i = 0; i < a.meshes.size(); ++i)
            scene.meshes.push_back({name + "/" + a.meshNames[i], path.string() + "#" + a.meshNames[i], a.meshes[i]});
        pa.firstMaterial = uint32_t(scene.materials.size());
        for (const AssemblyMaterial& m : a.materials) scene.materials.push_back(materialFromAssembly(m));
        if (a.materials.empty()) scene.materials.push_back(Material{});  // what sceneFromAssembly gives it too
        pa.firstPart = int32_t(scene.parts.size());
        for (const AssemblyPart& p : a.parts) scene.parts.push_back({p.name, p.parent < 0 ? -1 : p.parent + pa.firstPart});
        for (auto& [k, bytes] : a.files) scene.files[k] = bytes;
        pa.instances = std::move(a.instances);
        const uint32_t index = uint32_t(assemblies.size());
        assemblies.push_back(std::move(pa));
        loadedAssemblies[{key, tess.linearDeflection, tess.angularDeflection}] = index;
        assemblyIndex[name] = index;
    };
    forEachTable(top, file, "mesh", [&](Reader& r, const toml::table&) {
        MeshDesc md;
        md.name = r.string("name", "", true);
        if (meshIndex.count(md.name) || assemblyIndex.count(md.name))
            r.fail(r.find("name"), "mesh name '" + md.name + "' is used twice");
        const bool hasFile = r.has("file"), hasShape = r.has("shape");
        if (hasFile == hasShape) r.fail(nullptr, "give exactly one of 'file' and 'shape'");
        if (hasFile) {
            const std::filesystem::path path = dir / r.string("file", "");
            md.source = path.string();
            std::error_code ec;
            const auto key = std::filesystem::weakly_canonical(path, ec);
            if (!isCadFile(path)) noDeflections(r);
            if (isAssemblyFile(path)) return loadAssemblyEntry(r, md.name, path, ec ? path : key);
            auto& slot = loadedFiles[ec ? path : key];
            if (!slot) {
                try {
                    const auto t0 = std::chrono::steady_clock::now();
                    ImportReport report;
                    slot = std::make_shared<const TriangleMesh>(loadMesh(path, meshOptions, &report));
                    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                    if (report.cache == "hit") {
                        stats.cacheSeconds += dt;
                        ++stats.cacheHits;
                    } else {
                        stats.importSeconds += dt;
                        ++stats.filesImported;
                        if (report.cache == "written" || report.cache.starts_with("rebuilt")) ++stats.cacheWritten;
                    }
                } catch (const InputError& e) {
                    r.fail(r.find("file"), std::string("mesh '") + md.name + "': " + e.what());
                }
                if (options.progress) {
                    const auto size = std::filesystem::file_size(path, ec);
                    if (!ec) bytesDone += double(size);
                    if (!options.progress(bytesTotal > 0 ? bytesDone / bytesTotal : 1.0)) throw Cancelled();
                }
            }
            md.mesh = slot;
        } else {
            noDeflections(r);
            const std::string shape = r.choice("shape", "", {"sphere", "box", "quad", "torus_knot"});
            md.source = "shape:" + shape;
            try {
                md.mesh = makeShape(r, shape);
            } catch (const std::invalid_argument& e) {
                r.fail(r.find("shape"), std::string("shape '") + shape + "': " + e.what());
            } catch (const std::bad_alloc&) {
                r.fail(r.find("shape"), std::string("shape '") + shape + "': too large to fit in memory");
            }
        }
        meshIndex[md.name] = uint32_t(scene.meshes.size());
        scene.meshes.push_back(std::move(md));
    });
    if (options.progress && !options.progress(1.0)) throw Cancelled();

    forEachTable(top, file, "material", [&](Reader& r, const toml::table&) {
        Material m;
        m.name = r.string("name", "", true);
        if (materialIndex.count(m.name)) r.fail(r.find("name"), "material name '" + m.name + "' is used twice");
        const std::string type =
            r.choice("type", "lambert", {"lambert", "phong", "mirror", "glass", "metal", "emissive", "volume"});
        m.type = materialTypeFromName(type);
        const bool diffuse = m.type == MaterialType::Lambert || m.type == MaterialType::Phong;
        m.texture = readTexture(r, dir, "texture");
        m.color = r.vec3("color", diffuse && m.texture.kind != TextureKind::Image ? Color{0.8f, 0.8f, 0.8f}
                                                                                  : Color{1, 1, 1});
        checkUnit(r, "texture_color2", m.texture.color2);
        if (m.type == MaterialType::Metal) m.roughness = float(r.number("roughness", m.roughness, 0.0, 1.0));
        if (m.type == MaterialType::Glass) {
            m.absorption = r.vec3("absorption", m.absorption);
            checkNonNegative(r, "absorption", m.absorption);
        }
        m.emission = r.vec3("emission", m.type == MaterialType::Emissive ? Color{1, 1, 1} : Color{0, 0, 0});
        checkNonNegative(r, "emission", m.emission);
        if (m.type != MaterialType::Volume) m.twoSided = r.boolean("two_sided", m.twoSided);
        m.bump = float(r.number("bump", m.bump, 0.0, 100.0));
        m.bumpScale = float(r.number("bump_scale", m.bumpScale, 1e-6, 1e6));
        const std::string bumpMapping = r.choice("bump_mapping", "auto", {"auto", "uv", "object"});
        m.bumpMapping = bumpMapping == "uv"       ? TextureMapping::Uv
                        : bumpMapping == "object" ? TextureMapping::Object
                                                  : TextureMapping::Auto;
        m.alpha = readTexture(r, dir, "alpha");
        m.alphaCutoff = float(r.number("alpha_cutoff", m.alphaCutoff, 0.0, 1.0));
        if (m.type == MaterialType::Volume) {
            m.volumeFile = (dir / r.string("volume_file", "", true)).string();
            try {
                loadVolume(m.volumeFile);
            } catch (const InputError& e) {
                r.fail(r.find("volume_file"), std::string("key 'volume_file': ") + e.what());
            }
            m.volumeStep = float(r.number("volume_step", m.volumeStep, 0.01, 100.0));
            if (const toml::node* n = r.find("transfer")) {
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
        }
        if (m.type == MaterialType::Phong) {
            m.specular = r.vec3("specular", {0.5f, 0.5f, 0.5f});
            m.shininess = float(r.number("shininess", m.shininess, 1.0, 1e5));
        }
        if (m.type == MaterialType::Glass) m.ior = float(r.number("ior", m.ior, 1.0, 4.0));
        if (maxComponent(m.color) > 1.0f || std::min({m.color.x, m.color.y, m.color.z}) < 0.0f)
            r.fail(r.find("color"), "key 'color': components must lie in [0, 1] (a surface cannot reflect more than it receives)");
        materialIndex[m.name] = uint32_t(scene.materials.size());
        scene.materials.push_back(m);
    });

    // Instances place a mesh or a group; a group is a list of such instances and may use groups
    // defined before it, so there are no cycles. Groups are flattened here, on the CPU in double
    // precision, into one level of Embree instances: the Embree build has one instance level
    // (RTC_MAX_INSTANCE_LEVEL_COUNT), and every flattened instance still shares its mesh's BVH.
    constexpr uint32_t kNoMaterial = ~0u;
    struct Child {
        bool isGroup = false;
        bool isAssembly = false;          // target indexes `assemblies`
        uint32_t target = 0;              // mesh, group or assembly index
        uint32_t material = kNoMaterial;  // inherited from the parent when not given
        Transform transform;
    };
    struct Group {
        std::vector<Child> children;
        uint64_t expanded = 0;  // mesh instances it stands for (saturating)
    };
    std::map<std::string, uint32_t> groupIndex;
    std::vector<Group> groups;
    constexpr uint64_t kMaxInstances = uint64_t(1) << 24;

    auto readChild = [&](Reader& r) {
        Child c;
        const bool hasMesh = r.has("mesh"), hasGroup = r.has("group");
        if (hasMesh == hasGroup) r.fail(nullptr, "give exactly one of 'mesh' and 'group'");
        if (hasMesh) {
            const std::string mesh = r.string("mesh", "", true);
            auto mi = meshIndex.find(mesh);
            auto ai = assemblyIndex.find(mesh);
            if (ai != assemblyIndex.end()) {
                c.isAssembly = true;
                c.target = ai->second;
            } else if (mi == meshIndex.end()) {
                r.fail(r.find("mesh"), "key 'mesh': no [[mesh]] is named '" + mesh + "'");
            } else {
                c.target = mi->second;
            }
        } else {
            const std::string group = r.string("group", "", true);
            auto gi = groupIndex.find(group);
            if (gi == groupIndex.end())
                r.fail(r.find("group"), "key 'group': no [[group]] named '" + group + "' is defined before this point");
            c.isGroup = true;
            c.target = gi->second;
        }
        const std::string material = r.string("material", "");
        if (!material.empty() && c.isAssembly)
            r.fail(r.find("material"), "key 'material': an assembly file keeps its own materials");
        if (!material.empty()) {
            auto it = materialIndex.find(material);
            if (it == materialIndex.end())
                r.fail(r.find("material"), "key 'material': no [[material]] is named '" + material + "'");
            c.material = it->second;
        }
        c.transform = readTransform(r);
        return c;
    };
    auto expandedOf = [&](const Child& c) -> uint64_t {
        return c.isGroup ? groups[c.target].expanded : c.isAssembly ? assemblies[c.target].instances.size() : 1;
    };

    forEachTable(top, file, "group", [&](Reader& r, const toml::table&) {
        const std::string name = r.string("name", "", true);
        if (groupIndex.count(name)) r.fail(r.find("name"), "group name '" + name + "' is used twice");
        Group g;
        const toml::node* list = r.find("instance");
        if (!list) r.fail(nullptr, "a group needs at least one [[group.instance]]");
        const toml::array* arr = list->as_array();
        if (!arr || arr->empty()) r.fail(list, "'instance' must be a non-empty array of tables, written [[group.instance]]");
        size_t k = 0;
        for (const toml::node& e : *arr) {
            const toml::table* t = e.as_table();
            if (!t) r.fail(&e, "'instance' entries must be tables, written [[group.instance]]");
            Reader cr(file, *t, "[[group]] '" + name + "' instance #" + std::to_string(++k) + ": ");
            g.children.push_back(readChild(cr));
            cr.finish();
            g.expanded = std::min(kMaxInstances + 1, g.expanded + expandedOf(g.children.back()));
        }
        groupIndex[name] = uint32_t(groups.size());
        groups.push_back(std::move(g));
    });

    uint32_t defaultMaterial = kNoMaterial;
    auto materialOrDefault = [&](uint32_t m) {
        if (m != kNoMaterial) return m;
        if (defaultMaterial == kNoMaterial) {
            Material def;
            def.name = "";
            defaultMaterial = uint32_t(scene.materials.size());
            scene.materials.push_back(def);
        }
        return defaultMaterial;
    };
    // An explicit "uv" mapping needs the mesh's texture coordinates; checked per (material, mesh)
    // pair as the instances expand, and reported at the top-level [[instance]] that places it.
    Reader* placing = nullptr;
    std::set<std::pair<uint32_t, uint32_t>> uvChecked;
    auto requireUVs = [&](uint32_t material, uint32_t mesh) {
        if (!uvChecked.insert({material, mesh}).second) return;
        const Material& m = scene.materials[material];
        const MeshDesc& md = scene.meshes[mesh];
        const char* what = m.texture.kind != TextureKind::None && m.texture.mapping == TextureMapping::Uv ? "texture_mapping"
                           : m.alpha.kind != TextureKind::None && m.alpha.mapping == TextureMapping::Uv ? "alpha_mapping"
                           : m.bump > 0.0f && m.bumpMapping == TextureMapping::Uv                      ? "bump_mapping"
                                                                                                         : nullptr;
        if (!what || md.mesh->hasUVs() || !placing) return;
        placing->fail(nullptr, "material '" + m.name + "' has " + what + " = \"uv\", but mesh '" + md.name + "' (" +
                                   md.source + ") has no texture coordinates");
    };
    // Mesh origins (far-from-origin files are stored recentred) go into the transform here.
    auto emit = [&](const Child& leaf, const Transform& parent, uint32_t inherited) {
        if (leaf.isAssembly) {  // its own materials (a group's inherited one does not apply) and parts
            const PlacedAssembly& pa = assemblies[leaf.target];
            const Transform placement = parent * leaf.transform;
            for (const AssemblyInstance& ai : pa.instances) {
                InstanceDesc in;
                in.mesh = pa.firstMesh + ai.mesh;
                in.material = pa.firstMaterial + ai.material;
                Transform t;
                t.m = ai.transform;  // the mesh's origin() is in it already
                in.transform = placement * t;
                in.part = pa.firstPart + int32_t(ai.part);
                scene.instances.push_back(in);
            }
            return;
        }
        InstanceDesc in;
        in.mesh = leaf.target;
        in.material = materialOrDefault(leaf.material != kNoMaterial ? leaf.material : inherited);
        requireUVs(in.material, in.mesh);
        const auto& o = scene.meshes[leaf.target].mesh->origin();
        in.transform = parent * leaf.transform * Transform::translate(o[0], o[1], o[2]);
        scene.instances.push_back(in);
    };
    std::function<void(const Child&, const Transform&, uint32_t)> expand = [&](const Child& c, const Transform& parent,
                                                                              uint32_t inherited) {
        const uint32_t material = c.material != kNoMaterial ? c.material : inherited;
        if (!c.isGroup) return emit(c, parent, inherited);
        const Transform t = parent * c.transform;
        for (const Child& child : groups[c.target].children) expand(child, t, material);
    };
    uint64_t total = 0;
    forEachTable(top, file, "instance", [&](Reader& r, const toml::table&) {
        const Child c = readChild(r);
        total += expandedOf(c);
        if (total > kMaxInstances)
            r.fail(nullptr, "the scene expands to more than " + std::to_string(kMaxInstances) + " mesh instances");
        placing = &r;
        expand(c, Transform{}, kNoMaterial);
        placing = nullptr;
    });

    std::vector<std::array<double, 3>> lightPositions;
    forEachTable(top, file, "light", [&](Reader& r, const toml::table&) {
        Light l;
        std::array<double, 3> position{0, 10, 0};
        const std::string type = r.choice("type", "point", {"point", "directional", "area"});
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
        l.intensity = float(r.number("intensity", 1.0, 0.0, 1e12));
        scene.lights.push_back(l);
        lightPositions.push_back(position);
    });

    // Section planes: slot i is the i-th [[section]], in the file's coordinates until the rebase.
    std::vector<std::array<double, 3>> sectionPoints;
    forEachTable(top, file, "section", [&](Reader& r, const toml::table&) {
        if (sectionPoints.size() == size_t(kMaxSections))
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
        scene.sections[sectionPoints.size()] = p;
        sectionPoints.push_back(point);
    });

    std::vector<std::array<double, 3>> cameraPositions, cameraTargets;
    forEachTable(top, file, "camera", [&](Reader& r, const toml::table&) {
        CameraDesc c;
        c.name = r.string("name", "camera" + std::to_string(scene.cameras.size() + 1));
        if (scene.findCamera(c.name)) r.fail(r.find("name"), "camera name '" + c.name + "' is used twice");
        const std::array<double, 3> p = r.vec3d("position", {}, true), at = r.vec3d("look_at", {}, true);
        c.up = r.vec3("up", c.up);
        c.fovY = float(r.number("fov", c.fovY, 0.01, 179.0));
        const Float3 view{float(at[0] - p[0]), float(at[1] - p[1]), float(at[2] - p[2])};
        if (length(view) == 0.0f) r.fail(r.find("look_at"), "camera looks at its own position");
        if (length(cross(view, c.up)) == 0.0f) r.fail(r.find("up"), "key 'up' is parallel to the viewing direction");
        scene.cameras.push_back(c);
        cameraPositions.push_back(p);
        cameraTargets.push_back(at);
    });
    // [parts]: hide, isolate and highlight by name, once every instance is known.
    if (const toml::table* t = subTable(top, "parts")) {
        Reader r(file, *t, "[parts]: ");
        PartView view;
        auto patterns = [&](const char* key, std::vector<std::string>& out) {
            const toml::node* n = r.find(key);
            if (!n) return;
            const toml::array* a = n->as_array();
            if (!a) r.fail(n, std::string("key '") + key + "': expected an array of strings");
            for (const toml::node& e : *a) {
                const auto v = e.value<std::string>();
                if (!v || !e.is_string() || v->empty()) r.fail(&e, std::string("key '") + key + "': expected non-empty strings");
                out.push_back(*v);
                try {
                    if (instancesMatching(scene, *v).empty()) throw InputError("no part or mesh matches it");
                } catch (const InputError& err) {
                    r.fail(&e, std::string("key '") + key + "': '" + *v + "': " + err.what());
                }
            }
        };
        patterns("hide", view.hide);
        patterns("isolate", view.isolate);
        patterns("highlight", view.highlight);
        r.finish();
        applyPartView(scene, view);
    }
    top.finish();

    // Rebase: everything the renderer sees in single precision becomes relative to one origin
    // near the geometry, computed and subtracted in double precision.
    scene.origin = rebaseOrigin(scene);
    const auto& o = scene.origin;
    auto rel = [&](const std::array<double, 3>& p) { return Float3{float(p[0] - o[0]), float(p[1] - o[1]), float(p[2] - o[2])}; };
    for (InstanceDesc& in : scene.instances) {
        in.transform.m[3] -= o[0];
        in.transform.m[7] -= o[1];
        in.transform.m[11] -= o[2];
    }
    for (size_t i = 0; i < scene.lights.size(); ++i)
        if (scene.lights[i].type != LightType::Directional) scene.lights[i].position = rel(lightPositions[i]);
    for (size_t i = 0; i < sectionPoints.size(); ++i) scene.sections[i].point = rel(sectionPoints[i]);
    for (size_t i = 0; i < scene.cameras.size(); ++i) {
        scene.cameras[i].position = rel(cameraPositions[i]);
        scene.cameras[i].lookAt = rel(cameraTargets[i]);
    }

    if (scene.cameras.empty()) scene.cameras.push_back(framingCamera(scene.worldBounds()));
    return scene;
}

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
    scene.origin = rebaseOrigin(scene);
    for (InstanceDesc& in : scene.instances) {
        in.transform.m[3] -= scene.origin[0];
        in.transform.m[7] -= scene.origin[1];
        in.transform.m[11] -= scene.origin[2];
    }
    scene.cameras.push_back(framingCamera(scene.worldBounds()));
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
        const auto t0 = std::chrono::steady_clock::now();
        const Assembly a = loadAssembly(file, ao);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (options.stats) {
            SceneLoadStats& st = *options.stats;
            if (a.cache == "hit") {
                st.cacheSeconds += seconds;
                ++st.cacheHits;
            } else {
                st.importSeconds += seconds;
                ++st.filesImported;
                st.cacheWritten += a.cache == "written" || a.cache.starts_with("rebuilt");
            }
        }
        return sceneFromAssembly(a, file);
    }
    SceneDesc scene;
    scene.sourceFile = file;
    MeshDesc md;
    md.name = file.stem().string();
    md.source = file.string();
    md.mesh = std::make_shared<const TriangleMesh>(loadMesh(file));
    scene.meshes.push_back(md);
    // A far-from-origin file is stored recentred; the scene stays in those small coordinates
    // and records where they lie.
    scene.origin = md.mesh->origin();
    Material m;
    m.name = "default";
    m.type = MaterialType::Phong;
    m.color = {0.7f, 0.7f, 0.72f};
    m.specular = {0.2f, 0.2f, 0.2f};
    scene.materials.push_back(m);
    scene.instances.push_back(InstanceDesc{});
    scene.cameras.push_back(framingCamera(scene.worldBounds()));
    addHeadLight(scene);
    return scene;
}

}  // namespace rtwall
