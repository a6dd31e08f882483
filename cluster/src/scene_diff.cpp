// diffScenes: a scene file edited at run time, as differential updates.
#include "fields.h"
#include "scene_state.h"

#include <rtwall/cluster.h>

#include <cstring>

namespace rtwall {

using namespace cluster;

namespace {

template <class T> bool sameArray(const T* a, const T* b, size_t n) {
    if ((a == nullptr) != (b == nullptr)) return false;
    return a == b || n == 0 || std::memcmp(a, b, n * sizeof(T)) == 0;
}

bool sameMesh(const MeshDesc& a, const MeshDesc& b) {
    if (a.name != b.name || a.source != b.source) return false;
    if (a.mesh == b.mesh) return true;
    if (!a.mesh || !b.mesh) return false;
    const TriangleMesh &x = *a.mesh, &y = *b.mesh;
    return x.vertexCount() == y.vertexCount() && x.triangleCount() == y.triangleCount() && x.origin() == y.origin() &&
           sameArray(x.positions(), y.positions(), x.vertexCount() * 3) &&
           sameArray(x.indices(), y.indices(), x.triangleCount() * 3) &&
           sameArray(x.normals(), y.normals(), x.vertexCount() * 3) &&
           sameArray(x.colors(), y.colors(), x.vertexCount() * 3) &&
           sameArray(x.uvs(), y.uvs(), x.vertexCount() * 2);
}

std::string countChange(const char* what, size_t before, size_t after) {
    return std::to_string(before) + " " + what + " became " + std::to_string(after) +
           ": changing the number needs a restart";
}

}  // namespace

SceneEdit diffScenes(const SceneDesc& before, const SceneDesc& after) {
    // Every member of SceneDesc is either an update below or a restart; the snapshot's mapping
    // (scene_state.cpp) asserts the same count. sourceFile and files (bytes by path) are the
    // scene file's own business: a material naming another file is a material edit. parts (an
    // assembly's names) are the master's alone: the clients render without them.
    static_assert(fieldCount<SceneDesc>() == 13, "SceneDesc has a member diffScenes does not compare");
    SceneEdit e;
    if (before.meshes.size() != after.meshes.size()) {
        e.refused.push_back(countChange("meshes", before.meshes.size(), after.meshes.size()));
    } else {
        for (size_t i = 0; i < before.meshes.size(); ++i)
            if (!sameMesh(before.meshes[i], after.meshes[i]))
                e.refused.push_back("mesh '" + after.meshes[i].name + "' (" + after.meshes[i].source +
                                    ") changed: new geometry needs a restart");
    }
    if (before.origin != after.origin) e.refused.push_back("the scene's origin moved: that needs a restart");
    if (before.bvh != after.bvh)
        e.refused.push_back("[bvh] changed: rebuilding the BVHs needs a restart");

    if (before.materials.size() != after.materials.size()) {
        e.refused.push_back(countChange("materials", before.materials.size(), after.materials.size()));
    } else {
        for (uint32_t i = 0; i < after.materials.size(); ++i)
            if (!sameOnWire(before.materials[i], after.materials[i]))
                e.materials.emplace_back(i, after.materials[i]);
    }
    if (before.lights.size() != after.lights.size()) {
        e.refused.push_back(countChange("lights", before.lights.size(), after.lights.size()));
    } else {
        for (uint32_t i = 0; i < after.lights.size(); ++i)
            if (!sameOnWire(before.lights[i], after.lights[i]))
                e.lights.emplace_back(i, after.lights[i]);
    }
    if (before.instances.size() != after.instances.size()) {
        e.refused.push_back(countChange("instances", before.instances.size(), after.instances.size()));
    } else {
        for (uint32_t i = 0; i < after.instances.size(); ++i) {
            const InstanceDesc &a = before.instances[i], &b = after.instances[i];
            if (a.mesh != b.mesh || a.material != b.material)
                e.refused.push_back("instance " + std::to_string(i) +
                                    " has another mesh or material: that needs a restart");
            else {
                if (!(a.transform == b.transform)) e.transforms.emplace_back(i, b.transform);
                if (a.visibility != b.visibility) e.visibility.emplace_back(i, b.visibility);
            }
        }
    }
    if (!sameOnWire(before.settings, after.settings)) e.settings = after.settings;
    if (before.denoise != after.denoise) e.denoise = after.denoise;
    for (uint32_t i = 0; i < after.sections.size(); ++i)
        if (!sameOnWire(before.sections[i], after.sections[i])) e.sections.emplace_back(i, after.sections[i]);
    if (!after.cameras.empty() && (before.cameras.empty() || !sameOnWire(before.cameras.front(), after.cameras.front())))
        e.camera = after.cameras.front();
    return e;
}

}  // namespace rtwall
