// Internal view of a built scene, shared by the kernel and the benchmarks.
#pragma once

#include <rtwall/engine.h>

#include <embree3/rtcore.h>

#include <atomic>
#include <memory>
#include <string>
#include <vector>

namespace rtwall {

class MaterialModel;

struct InstanceData {
    const TriangleMesh* mesh = nullptr;
    uint32_t material = 0;       // index into desc.materials and models
    float normalMatrix[9] = {};  // row-major inverse transpose of the object-to-world 3x3
    float objectToWorld[12] = {};
    float worldToObject[12] = {};  // for materials that work in object space (volumes)
    Bounds3 meshBounds;            // object-space bounds of the mesh (the box a volume fills)
};

struct Scene::Impl {
    SceneDesc desc;  // meshes are shared pointers: no second copy of any geometry
    std::string lastError;  // written by Embree's error callback
    RTCDevice device = nullptr;
    RTCScene top = nullptr;
    std::vector<RTCScene> meshScenes;      // one BVH per unique mesh
    std::vector<InstanceData> instances;   // indexed by the instance geometry ID in `top`
    std::atomic<int64_t> embreeBytes{0};   // Embree's memory monitor: BVHs, instances, build scratch
    int64_t meshBvhBytes = 0;              // embreeBytes once every mesh BVH is built
    ProgressFn progress;                   // during construction only
    double trianglesBuilt = 0, trianglesTotal = 0, currentMesh = 0;
    bool cancelled = false;
    std::vector<std::unique_ptr<MaterialModel>> models;  // one per desc.materials entry
    bool anyShadowTransparent = false;     // some instance lets shadow rays through (glass, volume)
    bool filtersInstalled = false;         // alpha-mask filter functions are set on the mesh geometries
    bool dirty = false;                    // instance transforms or masks changed since the last commit

    ~Impl();
};

}  // namespace rtwall
