#include "scene_state.h"

#include "fields.h"

#include <stdexcept>

namespace rtwall::cluster {

namespace {

// The members of SceneDesc and SceneSnapshot that the two functions below map, one by one. A
// member added to either fails the build here until it is mapped (or said not to travel).
// SceneDesc::sourceFile, the cameras (version 13: a camera travels only with a frame,
// FrameBegin::views), parts (an assembly's part names: picking and `rtwall
// info` on the master) and denoise (the display side filters, issue 28) do not travel.
static_assert(fieldCount<SceneDesc>() == 13,
              "SceneDesc has a member snapshotOf/sceneOf do not map: map it (or say why it does not travel), "
              "and decide in diffScenes whether an edit of it is an update or needs a restart");
static_assert(fieldCount<SceneSnapshot>() == 10, "SceneSnapshot has a member snapshotOf/sceneOf do not map");

// The scene state as plain data, wherever it is held: what changes write.
struct StateFields {
    std::vector<Material>& materials;
    std::vector<InstanceDesc>& instances;
    std::vector<Light>& lights;
    RenderSettings& settings;
    SectionPlanes& sections;
    std::vector<AssetRef>* assets;  // a snapshot's files; a SceneDesc holds file bytes, which its owner adds
};

template <class T> T& element(std::vector<T>& v, uint32_t i, const char* what) {
    if (i >= v.size())
        throw DecodeError(std::string(what) + " " + std::to_string(i) + " does not exist (the scene has " +
                          std::to_string(v.size()) + ")");
    return v[i];
}

void apply(const StateFields& s, const Change& change) {
    struct Visitor {
        const StateFields& s;
        void operator()(const TransformChange& c) const { element(s.instances, c.instance, "instance").transform = c.transform; }
        void operator()(const MaterialChange& c) const {
            element(s.materials, c.material, "material") = c.value;
            if (!s.assets) return;
            for (const AssetRef& file : c.files) {
                bool known = false;
                for (const AssetRef& a : *s.assets) known = known || a.path == file.path;
                if (!known) s.assets->push_back(file);
            }
        }
        void operator()(const LightChange& c) const { element(s.lights, c.light, "light") = c.value; }
        void operator()(const SettingsChange& c) const { s.settings = c.settings; }
        void operator()(const SectionChange& c) const {
            if (c.section >= s.sections.size())
                throw DecodeError("section " + std::to_string(c.section) + " does not exist (at most " +
                                  std::to_string(s.sections.size()) + ")");
            s.sections[c.section] = c.value;
        }
        void operator()(const VisibilityChange& c) const {
            element(s.instances, c.instance, "instance").visibility = c.visibility;
        }
    };
    std::visit(Visitor{s}, change);
}

}  // namespace

MeshRef meshRefOf(const MeshDesc& mesh) {
    const std::vector<uint8_t> bytes = encodeMesh(*mesh.mesh);  // only to hash it; freed at once
    return MeshRef{mesh.name, mesh.source, hashBytes(bytes.data(), bytes.size()), bytes.size()};
}

SceneSnapshot snapshotOf(const SceneDesc& scene, std::vector<MeshRef> meshes,
                         std::vector<AssetRef> assets, uint32_t seq) {
    if (meshes.size() != scene.meshes.size())
        throw std::logic_error("snapshotOf: " + std::to_string(meshes.size()) + " mesh refs for " +
                               std::to_string(scene.meshes.size()) + " meshes");
    SceneSnapshot s;
    s.updateSeq = seq;
    s.meshes = std::move(meshes);
    s.materials = scene.materials;
    s.instances = scene.instances;
    s.lights = scene.lights;
    s.settings = scene.settings;
    s.bvh = scene.bvh;
    s.origin = scene.origin;
    s.assets = std::move(assets);
    s.sections = scene.sections;
    return s;
}

std::optional<SceneDesc> sceneOf(const SceneSnapshot& snapshot,
                                 const std::map<Hash128, std::shared_ptr<const TriangleMesh>>& meshes,
                                 const std::map<Hash128, FileBytes>& files) {
    SceneDesc d;
    for (const MeshRef& ref : snapshot.meshes) {
        auto it = meshes.find(ref.hash);
        if (it == meshes.end()) return std::nullopt;
        d.meshes.push_back({ref.name, ref.source, it->second});
    }
    for (const AssetRef& ref : snapshot.assets) {
        auto it = files.find(ref.hash);
        if (it == files.end()) return std::nullopt;
        d.files[ref.path] = it->second;
    }
    d.materials = snapshot.materials;
    d.instances = snapshot.instances;
    d.lights = snapshot.lights;
    d.settings = snapshot.settings;
    d.bvh = snapshot.bvh;
    d.origin = snapshot.origin;
    d.sections = snapshot.sections;
    return d;
}

void applyChange(SceneDesc& scene, const Change& change) {
    apply({scene.materials, scene.instances, scene.lights, scene.settings, scene.sections, nullptr}, change);
}

void applyChange(SceneSnapshot& snapshot, const Change& change) {
    apply({snapshot.materials, snapshot.instances, snapshot.lights, snapshot.settings,
           snapshot.sections, &snapshot.assets},
          change);
}

uint64_t objectOf(const Change& change) {
    struct Visitor {
        uint32_t operator()(const TransformChange& c) const { return c.instance; }
        uint32_t operator()(const MaterialChange& c) const { return c.material; }
        uint32_t operator()(const LightChange& c) const { return c.light; }
        uint32_t operator()(const SettingsChange&) const { return 0; }  // one set of settings
        uint32_t operator()(const SectionChange& c) const { return c.section; }
        uint32_t operator()(const VisibilityChange& c) const { return c.instance; }
    };
    return uint64_t(change.index()) << 32 | std::visit(Visitor{}, change);
}

void MergedUpdate::add(Update&& update) {
    if (empty()) update_.baseSeq = update.baseSeq;
    update_.seq = update.seq;
    for (Change& c : update.changes) {
        const auto [it, fresh] = index_.try_emplace(objectOf(c), update_.changes.size());
        if (fresh) {
            update_.changes.push_back(std::move(c));
            continue;
        }
        Change& old = update_.changes[it->second];
        // A file a replaced material change brought stays: a later change (to this material or
        // another) may use it without naming it, since the state already held it by then.
        if (auto* later = std::get_if<MaterialChange>(&c))
            for (AssetRef& file : std::get<MaterialChange>(old).files) {
                bool named = false;
                for (const AssetRef& f : later->files) named = named || f.path == file.path;
                if (!named) later->files.push_back(std::move(file));
            }
        old = std::move(c);
    }
}

Update MergedUpdate::take() {
    Update out = std::move(update_);
    update_ = Update{};
    index_.clear();
    return out;
}

}  // namespace rtwall::cluster
