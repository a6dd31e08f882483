#include "material.h"
#include "scene_files.h"
#include "scene_impl.h"
#include "vec.h"

#include <rtwall/engine_embree.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <memory>
#include <stdexcept>
#include <string>

namespace rtwall {

namespace {

void embreeErrorHandler(void* userPtr, RTCError code, const char* message) {
    auto* last = static_cast<std::string*>(userPtr);
    *last = "Embree error " + std::to_string(int(code)) + ": " + (message ? message : "(no message)");
}

void checkDevice(RTCDevice device, const std::string& lastError, const char* what) {
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE || !lastError.empty())
        throw std::runtime_error(std::string("while ") + what + ": " + lastError);
}

// Inverse transpose of the upper 3x3, in double precision, so normals stay perpendicular
// under non-uniform scaling.
void normalMatrixOf(const Transform& t, float out[9]) {
    const auto& m = t.m;
    double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
    double D = -(b * i - c * h), E = a * i - c * g, F = -(a * h - b * g);
    double G = b * f - c * e, H = -(a * f - c * d), I = a * e - b * d;
    double det = a * A + b * B + c * C;
    if (det == 0.0 || !std::isfinite(det))
        throw std::runtime_error("instance transform is singular");
    // inverse = adj^T / det; its transpose is the cofactor matrix / det.
    double cof[9] = {A, B, C, D, E, F, G, H, I};
    for (int k = 0; k < 9; ++k) out[k] = float(cof[k] / det);
}

bool memoryMonitor(void* userPtr, ssize_t bytes, bool) {
    static_cast<std::atomic<int64_t>*>(userPtr)->fetch_add(int64_t(bytes), std::memory_order_relaxed);
    return true;
}

// Embree reports each mesh's build from 0 to 1; the whole build is weighted by triangles.
bool buildProgress(void* userPtr, double n) {
    auto& s = *static_cast<Scene::Impl*>(userPtr);
    if (s.cancelled) return false;
    if (s.progress && s.trianglesTotal > 0 &&
        !s.progress((s.trianglesBuilt + n * s.currentMesh) / s.trianglesTotal)) {
        s.cancelled = true;
        return false;
    }
    return true;
}

// Embree 3 (scene.cpp, createTriangleAccel) picks its triangle BVH from the scene's flags
// before the quality: only a scene that is neither robust nor compact gets the spatial-split
// builder for RTC_BUILD_QUALITY_HIGH; a robust or compact scene is built by the same builder
// as medium, so "high" then changes nothing (the same bytes, the same BVH). The per-geometry
// quality only matters for dynamic two-level scenes, which rtwall does not use.
RTCBuildQuality buildQuality(BvhSettings::Quality q) {
    switch (q) {
    case BvhSettings::Quality::Low: return RTC_BUILD_QUALITY_LOW;
    case BvhSettings::Quality::High: return RTC_BUILD_QUALITY_HIGH;
    default: return RTC_BUILD_QUALITY_MEDIUM;
    }
}

// RTC_SCENE_FLAG_ROBUST, where the scene asks for it, goes on every mesh BVH and on the top
// level: it makes traversal conservative, so rays along shared edges of thin triangles (common
// in CAD) do not slip through between boxes.
RTCSceneFlags sceneFlags(const BvhSettings& b) {
    int f = RTC_SCENE_FLAG_NONE;
    if (b.compact) f |= RTC_SCENE_FLAG_COMPACT;
    if (b.robust) f |= RTC_SCENE_FLAG_ROBUST;
    return RTCSceneFlags(f);
}

// Inverse of the affine object-to-world transform, in double precision.
void worldToObjectOf(const Transform& t, float out[12]) {
    const auto& m = t.m;
    const double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    const double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
    const double D = -(b * i - c * h), E = a * i - c * g, F = -(a * h - b * g);
    const double G = b * f - c * e, H = -(a * f - c * d), I = a * e - b * d;
    const double det = a * A + b * B + c * C;
    const double inv[9] = {A / det, D / det, G / det, B / det, E / det, H / det, C / det, F / det, I / det};
    for (int r = 0; r < 3; ++r) {
        const double tr = -(inv[3 * r] * m[3] + inv[3 * r + 1] * m[7] + inv[3 * r + 2] * m[11]);
        out[4 * r] = float(inv[3 * r]);
        out[4 * r + 1] = float(inv[3 * r + 1]);
        out[4 * r + 2] = float(inv[3 * r + 2]);
        out[4 * r + 3] = float(tr);
    }
}

// Alpha masks: Embree calls this for every candidate hit of camera, secondary and shadow rays
// (intersection and occlusion filter alike); a hit where the mask is below its cutoff is
// rejected, so the ray goes on through the hole. Accepting or rejecting depends on the hit
// alone, so packet and single-ray traversal still agree.
void alphaFilter(const RTCFilterFunctionNArguments* args) {
    const auto* s = static_cast<const Scene::Impl*>(args->geometryUserPtr);
    const unsigned inst = args->context->instID[0];
    if (inst >= s->instances.size()) return;
    const InstanceData& data = s->instances[inst];
    const MaterialModel& model = *s->models[data.material];
    if (!model.alphaMasked()) return;
    for (unsigned k = 0; k < args->N; ++k) {
        if (args->valid[k] != -1) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, k);
        const float u = RTCHitN_u(args->hit, args->N, k), v = RTCHitN_v(args->hit, args->N, k);
        if (!model.alphaAt(objectPosition(*data.mesh, prim, u, v))) args->valid[k] = 0;
    }
}

void installAlphaFilters(Scene::Impl& s) {
    for (RTCScene ms : s.meshScenes) {
        RTCGeometry g = rtcGetGeometry(ms, 0);
        if (!g) continue;
        rtcSetGeometryUserData(g, &s);
        rtcSetGeometryIntersectFilterFunction(g, alphaFilter);
        rtcSetGeometryOccludedFilterFunction(g, alphaFilter);
        rtcCommitGeometry(g);
        rtcCommitScene(ms);
    }
    s.filtersInstalled = true;
}

unsigned instanceMask(const Scene::Impl& s, const InstanceData& data) {
    return s.models[data.material]->shadowTransparent() ? kMaskShadowTransparent : kMaskOpaque;
}

void updateShadowTransparency(Scene::Impl& s) {
    s.anyShadowTransparent = false;
    for (const InstanceData& d : s.instances) s.anyShadowTransparent |= s.models[d.material]->shadowTransparent();
}

}  // namespace

Scene::Impl::~Impl() = default;

Scene::Scene(const SceneDesc& desc) : Scene(desc, ProgressFn{}) {}

Scene::Scene(const SceneDesc& desc, const ProgressFn& progress) : impl_(std::make_unique<Impl>()) {
    Impl& s = *impl_;
    s.desc = desc;
    s.progress = progress;
    std::string& lastError = s.lastError;
    s.device = rtcNewDevice(nullptr);
    if (!s.device) throw std::runtime_error("cannot create an Embree device (rtcNewDevice failed)");
    rtcSetDeviceErrorFunction(s.device, embreeErrorHandler, &lastError);
    rtcSetDeviceMemoryMonitorFunction(s.device, memoryMonitor, &s.embreeBytes);
    for (const MeshDesc& md : s.desc.meshes) s.trianglesTotal += double(md.mesh->triangleCount());

    try {
        s.models.reserve(s.desc.materials.size());
        bool anyAlpha = false;
        const ScopedSceneFiles files(&s.desc.files);  // textures and volumes given in memory
        for (const Material& m : s.desc.materials) {
            s.models.push_back(makeMaterialModel(m));
            anyAlpha |= s.models.back()->alphaMasked();
        }
        std::vector<Bounds3> meshBounds(s.desc.meshes.size());
        for (size_t i = 0; i < s.desc.meshes.size(); ++i) meshBounds[i] = s.desc.meshes[i].mesh->bounds();
        s.meshScenes.reserve(s.desc.meshes.size());
        for (const MeshDesc& md : s.desc.meshes) {
            const TriangleMesh& mesh = *md.mesh;
            RTCScene ms = rtcNewScene(s.device);
            s.meshScenes.push_back(ms);
            rtcSetSceneBuildQuality(ms, buildQuality(s.desc.bvh.quality));
            rtcSetSceneFlags(ms, sceneFlags(s.desc.bvh));
            rtcSetSceneProgressMonitorFunction(ms, buildProgress, &s);
            s.currentMesh = double(mesh.triangleCount());
            if (mesh.triangleCount() > 0) {
                RTCGeometry g = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
                rtcSetGeometryBuildQuality(g, buildQuality(s.desc.bvh.quality));
                // Shared buffers: Embree reads the mesh's arrays in place, whether the importer
                // filled them or they are the pages of a mapped cache file (TriangleMesh's
                // MeshArray); both carry the 16 bytes of tail padding Embree's SIMD loads need.
                rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, mesh.positions(), 0,
                                           3 * sizeof(float), mesh.vertexCount());
                rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices(), 0,
                                           3 * sizeof(uint32_t), mesh.triangleCount());
                rtcSetGeometryMask(g, kMaskAll);  // instances carry the masks that matter
                if (anyAlpha) {
                    rtcSetGeometryUserData(g, &s);
                    rtcSetGeometryIntersectFilterFunction(g, alphaFilter);
                    rtcSetGeometryOccludedFilterFunction(g, alphaFilter);
                }
                rtcCommitGeometry(g);
                rtcAttachGeometryByID(ms, g, 0);
                rtcReleaseGeometry(g);
            }
            rtcCommitScene(ms);
            if (s.cancelled) throw Cancelled();
            checkDevice(s.device, lastError, ("building the BVH of mesh '" + md.name + "'").c_str());
            s.trianglesBuilt += s.currentMesh;
        }
        s.progress = nullptr;
        s.meshBvhBytes = s.embreeBytes.load();
        s.filtersInstalled = anyAlpha;

        s.top = rtcNewScene(s.device);
        rtcSetSceneFlags(s.top, sceneFlags(s.desc.bvh));
        s.instances.resize(s.desc.instances.size());
        for (size_t i = 0; i < s.desc.instances.size(); ++i) {
            const InstanceDesc& in = s.desc.instances[i];
            InstanceData& data = s.instances[i];
            data.mesh = s.desc.meshes.at(in.mesh).mesh.get();
            if (in.material >= s.desc.materials.size())
                throw std::out_of_range("instance " + std::to_string(i) + ": material " + std::to_string(in.material) +
                                        " does not exist");
            data.material = in.material;
            data.meshBounds = meshBounds[in.mesh];
            for (int k = 0; k < 12; ++k) data.objectToWorld[k] = float(in.transform.m[k]);
            normalMatrixOf(in.transform, data.normalMatrix);
            worldToObjectOf(in.transform, data.worldToObject);

            RTCGeometry g = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(g, s.meshScenes[in.mesh]);
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, data.objectToWorld);
            rtcSetGeometryMask(g, instanceMask(s, data));
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(s.top, g, unsigned(i));
            rtcReleaseGeometry(g);
        }
        updateShadowTransparency(s);
        rtcCommitScene(s.top);
        checkDevice(s.device, lastError, "building the top-level BVH");
#ifdef __GLIBC__
        // The builds free hundreds of MB of scratch (primitive arrays, per-thread blocks) in
        // pieces below glibc's mmap threshold; glibc keeps such freed memory resident unless it
        // sits at the top of the heap. Hand it back once, now that the scene holds what it needs.
        ::malloc_trim(0);
#endif
    } catch (...) {
        for (RTCScene ms : s.meshScenes) rtcReleaseScene(ms);
        if (s.top) rtcReleaseScene(s.top);
        rtcReleaseDevice(s.device);
        throw;
    }
}

Scene::~Scene() {
    if (!impl_) return;
    if (impl_->top) rtcReleaseScene(impl_->top);
    for (RTCScene ms : impl_->meshScenes) rtcReleaseScene(ms);
    if (impl_->device) rtcReleaseDevice(impl_->device);
}

const SceneDesc& Scene::desc() const { return impl_->desc; }

void Scene::setInstanceTransform(uint32_t instance, const Transform& transform) {
    Impl& s = *impl_;
    if (instance >= s.instances.size()) throw std::out_of_range("instance " + std::to_string(instance) + " does not exist");
    InstanceData& data = s.instances[instance];
    float normal[9];
    normalMatrixOf(transform, normal);  // throws for a singular transform before anything changes
    s.desc.instances[instance].transform = transform;
    for (int k = 0; k < 12; ++k) data.objectToWorld[k] = float(transform.m[k]);
    std::copy(normal, normal + 9, data.normalMatrix);
    worldToObjectOf(transform, data.worldToObject);
    RTCGeometry g = rtcGetGeometry(s.top, instance);
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, data.objectToWorld);
    rtcCommitGeometry(g);
    s.dirty = true;
}

void Scene::setMaterial(uint32_t material, const Material& value) {
    Impl& s = *impl_;
    if (material >= s.desc.materials.size())
        throw std::out_of_range("material " + std::to_string(material) + " does not exist");
    // Built first: a texture or volume that cannot be read throws before anything changes.
    const ScopedSceneFiles files(&s.desc.files);
    std::unique_ptr<MaterialModel> model = makeMaterialModel(value);
    s.desc.materials[material] = value;
    s.models[material] = std::move(model);
    if (s.models[material]->alphaMasked() && !s.filtersInstalled) installAlphaFilters(s);
    // Shadow rays find shadow-transparent instances by their Embree mask.
    for (size_t i = 0; i < s.instances.size(); ++i) {
        if (s.instances[i].material != material) continue;
        RTCGeometry g = rtcGetGeometry(s.top, unsigned(i));
        rtcSetGeometryMask(g, instanceMask(s, s.instances[i]));
        rtcCommitGeometry(g);
    }
    updateShadowTransparency(s);
    s.dirty = true;
}

void Scene::addFile(const std::string& path, std::shared_ptr<const std::vector<uint8_t>> bytes) {
    impl_->desc.files[path] = std::move(bytes);
}

void Scene::setLight(uint32_t light, const Light& value) {
    Impl& s = *impl_;
    if (light >= s.desc.lights.size()) throw std::out_of_range("light " + std::to_string(light) + " does not exist");
    s.desc.lights[light] = value;
}

void Scene::commit() {
    Impl& s = *impl_;
    if (!s.dirty) return;
    rtcCommitScene(s.top);
    s.dirty = false;
    checkDevice(s.device, s.lastError, "refitting the top-level BVH");
}

size_t Scene::embreeBytes() const { return size_t(std::max<int64_t>(0, impl_->embreeBytes.load())); }

size_t Scene::embreeTopLevelBytes() const {
    return size_t(std::max<int64_t>(0, impl_->embreeBytes.load() - impl_->meshBvhBytes));
}

size_t Scene::geometryBytes() const {
    // Meshes named by several [[mesh]] entries share one TriangleMesh: count it once.
    std::set<const TriangleMesh*> seen;
    size_t bytes = 0;
    for (const MeshDesc& md : impl_->desc.meshes)
        if (seen.insert(md.mesh.get()).second) bytes += md.mesh->residentBytes();
    return bytes;
}

RTCScene embreeScene(const Scene& scene) { return scene.impl().top; }

}  // namespace rtwall
