// Internal view of a built scene, shared by the kernel and the benchmarks.
#pragma once

#include <rtwall/engine.h>

#include <embree3/rtcore.h>

#include <atomic>
#include <string>
#include <vector>

namespace rtwall {

struct InstanceData {
    const TriangleMesh* mesh = nullptr;
    const Material* material = nullptr;
    float normalMatrix[9] = {};  // row-major inverse transpose of the object-to-world 3x3
    float objectToWorld[12] = {};
};

struct Scene::Impl {
    SceneDesc desc;  // meshes are shared pointers: no second copy of any geometry
    std::string lastError;  // written by Embree's error callback
    RTCDevice device = nullptr;
    RTCScene top = nullptr;
    std::vector<RTCScene> meshScenes;      // one BVH per unique mesh
    std::vector<InstanceData> instances;   // indexed by the instance geometry ID in `top`
    bool dirty = false;                    // instance transforms changed since the last commit
    std::atomic<int64_t> embreeBytes{0};   // Embree's memory monitor: BVHs, instances, build scratch
    int64_t meshBvhBytes = 0;              // embreeBytes once every mesh BVH is built
    ProgressFn progress;                   // during construction only
    double trianglesBuilt = 0, trianglesTotal = 0, currentMesh = 0;
    bool cancelled = false;
};

}  // namespace rtwall
