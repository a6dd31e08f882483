// A scene file's geometry: [[mesh]] entries (mesh files, assembly files, shapes) and the
// [[group]] and [[instance]] entries that place them.
#include "scene_file.h"
#include "scene_file_keys.h"

#include <rtwall/vec.h>

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <functional>
#include <set>

namespace rtwall::scene_file {

namespace {

using toml_reader::KeyType;
using toml_reader::Reader;

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

std::shared_ptr<const TriangleMesh> makeShape(Reader& r, const std::string& shape) {
    if (shape == "sphere") {
        r.extend(scene_keys::kSphere);
        const int rings = r.integer("rings", 32), segments = r.integer("segments", 64);
        return std::make_shared<const TriangleMesh>(makeSphere(rings, segments));
    }
    if (shape == "box") return std::make_shared<const TriangleMesh>(makeBox());
    if (shape == "quad") return std::make_shared<const TriangleMesh>(makeQuad());
    // torus_knot
    r.extend(scene_keys::kTorusKnot);
    const int p = r.integer("p", 2), q = r.integer("q", 3);
    const int segments = r.integer("segments", 256), sides = r.integer("sides", 16);
    const float radius = float(r.number("radius", 0.25));
    if (int64_t(segments) * sides > (int64_t(1) << 26))
        r.fail(r.find("segments"), "torus_knot: segments x sides must stay below 2^26 vertices");
    return std::make_shared<const TriangleMesh>(makeTorusKnot(p, q, segments, sides, radius));
}

// Reports progress after a file of `size` bytes; false when the size is unknown.
void fileDone(Load& l, double size, bool known) {
    if (!l.options.progress) return;
    if (known) l.bytesDone += size;
    if (!l.options.progress(l.bytesTotal > 0 ? l.bytesDone / l.bytesTotal : 1.0)) throw Cancelled();
}

void loadAssemblyEntry(Load& l, Reader& r, const std::string& name, const std::filesystem::path& path,
                       const std::filesystem::path& key) {
    ImportSettings tess = l.import;
    if (isCadFile(path)) readDeflections(r, tess);
    const auto slot = l.loadedAssemblies.find({key, tess.linearDeflection, tess.angularDeflection});
    if (slot != l.loadedAssemblies.end()) {
        l.assemblyIndex[name] = slot->second;
        return;
    }
    AssemblyOptions ao;
    ao.linearDeflection = tess.linearDeflection;
    ao.angularDeflection = tess.angularDeflection;
    ao.cache = l.meshOptions.cache;
    ao.cacheDir = l.meshOptions.cacheDir;
    ao.shareCongruent = tess.shareCongruent;
    ao.congruenceTolerance = tess.congruenceTolerance;
    std::error_code ec;
    const double size = double(std::filesystem::file_size(path, ec));
    if (l.options.progress && !ec)
        ao.progress = [&l, size](double f) {
            return l.options.progress(l.bytesTotal > 0 ? (l.bytesDone + f * size) / l.bytesTotal : 1.0);
        };
    Assembly a;
    try {
        const auto t0 = std::chrono::steady_clock::now();
        a = loadAssembly(path, ao);
        countImport(l.stats, a.cache, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    } catch (const InputError& e) {
        r.fail(r.find("file"), std::string("mesh '") + name + "': " + e.what());
    }
    fileDone(l, size, !ec);
    SceneDesc& scene = l.scene;
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
    const uint32_t index = uint32_t(l.assemblies.size());
    l.assemblies.push_back(std::move(pa));
    l.loadedAssemblies[{key, tess.linearDeflection, tess.angularDeflection}] = index;
    l.assemblyIndex[name] = index;
}

// A mesh file, read once however many [[mesh]] entries name it.
std::shared_ptr<const TriangleMesh> loadMeshFile(Load& l, Reader& r, const std::string& name, const std::filesystem::path& path,
                                                 const std::filesystem::path& key) {
    auto& slot = l.loadedFiles[key];
    if (slot) return slot;
    try {
        const auto t0 = std::chrono::steady_clock::now();
        ImportReport report;
        slot = std::make_shared<const TriangleMesh>(loadMesh(path, l.meshOptions, &report));
        countImport(l.stats, report.cache, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    } catch (const InputError& e) {
        r.fail(r.find("file"), std::string("mesh '") + name + "': " + e.what());
    }
    if (l.options.progress) {
        std::error_code ec;
        const auto size = std::filesystem::file_size(path, ec);
        fileDone(l, double(size), !ec);
    }
    return slot;
}

void readMesh(Load& l, Reader& r) {
    MeshDesc md;
    md.name = r.string("name", "", true);
    if (l.meshIndex.count(md.name) || l.assemblyIndex.count(md.name))
        r.fail(r.find("name"), "mesh name '" + md.name + "' is used twice");
    const bool hasFile = r.has("file"), hasShape = r.has("shape");
    if (hasFile == hasShape) r.fail(nullptr, "give exactly one of 'file' and 'shape'");
    if (hasFile) {
        const std::filesystem::path path = l.dir / r.string("file", "");
        md.source = path.string();
        std::error_code ec;
        const auto key = std::filesystem::weakly_canonical(path, ec);
        if (!isCadFile(path)) noDeflections(r);
        if (isAssemblyFile(path)) return loadAssemblyEntry(l, r, md.name, path, ec ? path : key);
        md.mesh = loadMeshFile(l, r, md.name, path, ec ? path : key);
    } else {
        noDeflections(r);
        const std::string shape = r.choice("shape", "");
        md.source = "shape:" + shape;
        try {
            md.mesh = makeShape(r, shape);
        } catch (const std::invalid_argument& e) {
            r.fail(r.find("shape"), std::string("shape '") + shape + "': " + e.what());
        } catch (const std::bad_alloc&) {
            r.fail(r.find("shape"), std::string("shape '") + shape + "': too large to fit in memory");
        }
    }
    l.meshIndex[md.name] = uint32_t(l.scene.meshes.size());
    l.scene.meshes.push_back(std::move(md));
}

Transform readTransform(Reader& r) {
    // Applied in this order: scale, rotate (x, then y, then z, in degrees), translate.
    Transform t;
    if (r.has("scale")) {
        const toml::node* n = r.find("scale");
        if (n->is_number()) {
            const toml_reader::Key& k = r.spec("scale", KeyType::Scale);
            const double s = r.number("scale", 1.0, k.lo, k.hi);
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

// Instances place a mesh or a group; a group is a list of such instances and may use groups
// defined before it, so there are no cycles. Groups are flattened here, on the CPU in double
// precision, into one level of Embree instances: the Embree build has one instance level
// (RTC_MAX_INSTANCE_LEVEL_COUNT), and every flattened instance still shares its mesh's BVH.
class InstanceReader {
public:
    explicit InstanceReader(Load& l) : l_(l), scene_(l.scene) {}

    void readGroup(Reader& r) {
        const std::string name = r.string("name", "", true);
        if (groupIndex_.count(name)) r.fail(r.find("name"), "group name '" + name + "' is used twice");
        Group g;
        const toml::node* list = r.find("instance");
        if (!list) r.fail(nullptr, "a group needs at least one [[group.instance]]");
        const toml::array* arr = list->as_array();
        if (!arr || arr->empty()) r.fail(list, "'instance' must be a non-empty array of tables, written [[group.instance]]");
        size_t k = 0;
        for (const toml::node& e : *arr) {
            const toml::table* t = e.as_table();
            if (!t) r.fail(&e, "'instance' entries must be tables, written [[group.instance]]");
            Reader cr(l_.file, *t, "[[group]] '" + name + "' instance #" + std::to_string(++k) + ": ", scene_keys::kInstance);
            g.children.push_back(readChild(cr));
            cr.finish();
            g.expanded = std::min(kMaxInstances + 1, g.expanded + expandedOf(g.children.back()));
        }
        groupIndex_[name] = uint32_t(groups_.size());
        groups_.push_back(std::move(g));
    }

    void readInstance(Reader& r) {
        const Child c = readChild(r);
        total_ += expandedOf(c);
        if (total_ > kMaxInstances)
            r.fail(nullptr, "the scene expands to more than " + std::to_string(kMaxInstances) + " mesh instances");
        placing_ = &r;
        expand(c, Transform{}, kNoMaterial, false);
        placing_ = nullptr;
    }

private:
    static constexpr uint32_t kNoMaterial = ~0u;
    static constexpr uint64_t kMaxInstances = uint64_t(1) << 24;
    struct Child {
        bool isGroup = false;
        bool isAssembly = false;          // target indexes `assemblies`
        uint32_t target = 0;              // mesh, group or assembly index
        uint32_t material = kNoMaterial;  // inherited from the parent when not given
        Transform transform;
        bool movable = false;             // every instance it expands to (a parent's goes on down)
    };
    struct Group {
        std::vector<Child> children;
        uint64_t expanded = 0;  // mesh instances it stands for (saturating)
    };

    Child readChild(Reader& r) {
        Child c;
        const bool hasMesh = r.has("mesh"), hasGroup = r.has("group");
        if (hasMesh == hasGroup) r.fail(nullptr, "give exactly one of 'mesh' and 'group'");
        if (hasMesh) {
            const std::string mesh = r.string("mesh", "", true);
            auto mi = l_.meshIndex.find(mesh);
            auto ai = l_.assemblyIndex.find(mesh);
            if (ai != l_.assemblyIndex.end()) {
                c.isAssembly = true;
                c.target = ai->second;
            } else if (mi == l_.meshIndex.end()) {
                r.fail(r.find("mesh"), "key 'mesh': no [[mesh]] is named '" + mesh + "'");
            } else {
                c.target = mi->second;
            }
        } else {
            const std::string group = r.string("group", "", true);
            auto gi = groupIndex_.find(group);
            if (gi == groupIndex_.end())
                r.fail(r.find("group"), "key 'group': no [[group]] named '" + group + "' is defined before this point");
            c.isGroup = true;
            c.target = gi->second;
        }
        const std::string material = r.string("material", "");
        if (!material.empty() && c.isAssembly)
            r.fail(r.find("material"), "key 'material': an assembly file keeps its own materials");
        if (!material.empty()) {
            auto it = l_.materialIndex.find(material);
            if (it == l_.materialIndex.end())
                r.fail(r.find("material"), "key 'material': no [[material]] is named '" + material + "'");
            c.material = it->second;
        }
        c.transform = readTransform(r);
        c.movable = r.boolean("movable", false);
        return c;
    }

    uint64_t expandedOf(const Child& c) const {
        return c.isGroup ? groups_[c.target].expanded : c.isAssembly ? l_.assemblies[c.target].instances.size() : 1;
    }

    uint32_t materialOrDefault(uint32_t m) {
        if (m != kNoMaterial) return m;
        if (defaultMaterial_ == kNoMaterial) {
            Material def;
            def.name = "";
            defaultMaterial_ = uint32_t(scene_.materials.size());
            scene_.materials.push_back(def);
        }
        return defaultMaterial_;
    }

    // An explicit "uv" mapping needs the mesh's texture coordinates; checked per (material, mesh)
    // pair as the instances expand, and reported at the top-level [[instance]] that places it.
    void requireUVs(uint32_t material, uint32_t mesh) {
        if (!uvChecked_.insert({material, mesh}).second) return;
        const Material& m = scene_.materials[material];
        const MeshDesc& md = scene_.meshes[mesh];
        const char* what = m.texture.kind != TextureKind::None && m.texture.mapping == TextureMapping::Uv ? "texture_mapping"
                           : m.alpha.kind != TextureKind::None && m.alpha.mapping == TextureMapping::Uv ? "alpha_mapping"
                           : m.bump > 0.0f && m.bumpMapping == TextureMapping::Uv                      ? "bump_mapping"
                                                                                                         : nullptr;
        if (!what || md.mesh->hasUVs() || !placing_) return;
        placing_->fail(nullptr, "material '" + m.name + "' has " + what + " = \"uv\", but mesh '" + md.name + "' (" +
                                    md.source + ") has no texture coordinates");
    }

    // Mesh origins (far-from-origin files are stored recentred) go into the transform here.
    void emit(const Child& leaf, const Transform& parent, uint32_t inherited, bool movable) {
        if (leaf.isAssembly) {  // its own materials (a group's inherited one does not apply) and parts
            const PlacedAssembly& pa = l_.assemblies[leaf.target];
            const Transform placement = parent * leaf.transform;
            for (const AssemblyInstance& ai : pa.instances) {
                InstanceDesc in;
                in.mesh = pa.firstMesh + ai.mesh;
                in.material = pa.firstMaterial + ai.material;
                Transform t;
                t.m = ai.transform;  // the mesh's origin() is in it already
                in.transform = placement * t;
                in.part = pa.firstPart + int32_t(ai.part);
                in.movable = movable;
                scene_.instances.push_back(in);
            }
            return;
        }
        InstanceDesc in;
        in.mesh = leaf.target;
        in.material = materialOrDefault(leaf.material != kNoMaterial ? leaf.material : inherited);
        requireUVs(in.material, in.mesh);
        const auto& o = scene_.meshes[leaf.target].mesh->origin();
        in.transform = parent * leaf.transform * Transform::translate(o[0], o[1], o[2]);
        in.movable = movable;
        scene_.instances.push_back(in);
    }

    void expand(const Child& c, const Transform& parent, uint32_t inherited, bool movable) {
        const uint32_t material = c.material != kNoMaterial ? c.material : inherited;
        movable = movable || c.movable;
        if (!c.isGroup) return emit(c, parent, inherited, movable);
        const Transform t = parent * c.transform;
        for (const Child& child : groups_[c.target].children) expand(child, t, material, movable);
    }

    Load& l_;
    SceneDesc& scene_;
    std::map<std::string, uint32_t> groupIndex_;
    std::vector<Group> groups_;
    uint32_t defaultMaterial_ = kNoMaterial;
    Reader* placing_ = nullptr;
    std::set<std::pair<uint32_t, uint32_t>> uvChecked_;
    uint64_t total_ = 0;
};

}  // namespace

// What one import took, into the load's statistics.
void countImport(SceneLoadStats& stats, const std::string& cache, double seconds) {
    if (cache == "hit") {
        stats.cacheSeconds += seconds;
        ++stats.cacheHits;
    } else {
        stats.importSeconds += seconds;
        ++stats.filesImported;
        stats.cacheWritten += cache == "written" || cache.starts_with("rebuilt");
    }
}

void readDeflections(Reader& r, ImportSettings& s) {
    s.linearDeflection = r.number("linear_deflection", s.linearDeflection);
    s.angularDeflection = r.number("angular_deflection", s.angularDeflection);
}

void readMeshes(Reader& top, Load& l) {
    toml_reader::forEachTable(top, l.file, scene_keys::kMesh, [&](Reader& r, const toml::table&) { readMesh(l, r); });
}

void readInstances(Reader& top, Load& l) {
    InstanceReader instances(l);
    toml_reader::forEachTable(top, l.file, scene_keys::kGroup, [&](Reader& r, const toml::table&) { instances.readGroup(r); });
    toml_reader::forEachTable(top, l.file, scene_keys::kInstance, [&](Reader& r, const toml::table&) { instances.readInstance(r); });
}

}  // namespace rtwall::scene_file
