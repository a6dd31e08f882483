#include "material.h"
#include "sampling.h"
#include "scene_files.h"
#include "scene_impl.h"

#include <rtwall/engine_embree.h>
#include <rtwall/vec.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
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

}  // namespace

void checkDevice(RTCDevice device, const std::string& lastError, const char* what) {
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE || !lastError.empty())
        throw std::runtime_error(std::string("while ") + what + ": " + lastError);
}

namespace {

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

}  // namespace

// RTC_SCENE_FLAG_ROBUST, where the scene asks for it, goes on every mesh BVH and on the top
// level: it makes traversal conservative, so rays along shared edges of thin triangles (common
// in CAD) do not slip through between boxes. A mesh BVH of quads is always robust: Embree's
// fast quad test is not watertight on the diagonal (a ray exactly along it, as pixel centres
// of an axis-aligned view of a symmetric part are, passes between the two triangles), and a
// line of missing pixels is not a speed/accuracy trade a user chose.
// Every level carries RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION: Embree runs the context filter
// that skips stale copies in the static top level (scene_impl.h, part moves) from inside the
// instanced mesh scenes, and asserts that the flag is set there.
RTCSceneFlags sceneFlags(const BvhSettings& b, bool quads) {
    int f = RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION;
    if (b.compact) f |= RTC_SCENE_FLAG_COMPACT;
    if (b.robust || quads) f |= RTC_SCENE_FLAG_ROBUST;
    return RTCSceneFlags(f);
}

namespace {

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

// Pairs triangles (2k, 2k+1) into quads (see MeshPrimitives). Two triangles pair when they
// share an edge walked in opposite directions (same orientation) and have four distinct corners.
// Quads are used when at least 3/4 of the pairs pair; below that the degenerate quads (a slot
// for one triangle, and one more for its unpaired neighbour) would cost more than the quads save.
MeshPrimitives pairIntoQuads(const TriangleMesh& mesh) {
    MeshPrimitives mp;
    const size_t pairs = mesh.triangleCount() / 2;
    if (pairs == 0) return mp;
    const uint32_t* idx = mesh.indices();
    std::vector<uint8_t> codes(pairs);
    constexpr uint8_t kUnpaired = 0xFF;
    // Pass 1: the code of every pair (or kUnpaired), and how many pair.
    size_t paired = 0;
    for (size_t k = 0; k < pairs; ++k) {
        const uint32_t* a = idx + 6 * k;
        const uint32_t* b = a + 3;
        uint8_t code = kUnpaired;
        if (a[0] != a[1] && a[1] != a[2] && a[0] != a[2])
            for (unsigned i = 0; i < 3 && code == kUnpaired; ++i)
                for (unsigned j = 0; j < 3; ++j)
                    // a's edge a[i+1]->a[i+2] is b's edge b[j+1]->b[j+2] walked backwards; a[i], b[j] are off it.
                    if (b[(j + 1) % 3] == a[(i + 2) % 3] && b[(j + 2) % 3] == a[(i + 1) % 3] && b[j] != a[0] &&
                        b[j] != a[1] && b[j] != a[2]) {
                        code = uint8_t(i | (j << 2));
                        break;
                    }
        codes[k] = code;
        paired += code != kUnpaired;
    }
    mp.pairsSharingEdge = paired;
    if (4 * paired < 3 * pairs) return mp;

    // An unpaired pair's quad is degenerate, (a0,a1,a2,a2): triangle 2k alone, with code
    // kQuadWithoutSecondTriangle (q0 at corner 0, no second triangle), so that a hit on it rounded just past its
    // diagonal (u + v a hair over 1) is not taken for triangle 2k+1.
    for (uint8_t& c : codes)
        if (c == kUnpaired) c = kQuadWithoutSecondTriangle;
    const bool uniform = std::all_of(codes.begin(), codes.end(), [&](uint8_t c) { return c == codes[0]; });
    mp.quads = uint32_t(pairs);
    if (uniform) mp.code = codes[0];
    else mp.codes = codes;
    // The window layout (code 1: first corner of 2k at 1, of 2k+1 at 0) lets Embree read the
    // quads straight from the triangle index array: no quad buffer at all.
    const bool window = uniform && codes[0] == 1;
    if (!window) {
        mp.quadIndex.resize(4 * pairs + 4);  // + 16 bytes of tail padding for Embree's SIMD loads
        for (size_t k = 0; k < pairs; ++k) {
            const uint32_t* a = idx + 6 * k;
            const uint32_t* b = a + 3;
            uint32_t* q = mp.quadIndex.data() + 4 * k;
            if (codes[k] == kQuadWithoutSecondTriangle) {
                q[0] = a[0], q[1] = a[1], q[2] = a[2], q[3] = a[2];
                mp.single.push_back(uint32_t(2 * k + 1));
            } else {
                const unsigned i = codes[k] & 3u, j = codes[k] >> 2;
                q[0] = a[i], q[1] = a[(i + 1) % 3], q[2] = b[j], q[3] = a[(i + 2) % 3];
            }
        }
    }
    if (mesh.triangleCount() % 2) mp.single.push_back(uint32_t(mesh.triangleCount() - 1));
    // The triangles no pair holds, as degenerate quads (t0,t1,t2,t2) in a second quad geometry:
    // Embree builds one BVH per primitive type in a scene, so a triangle geometry here would give
    // the mesh two BVHs to traverse; quads of both geometries share one.
    if (!mp.single.empty()) {
        mp.singleIndex.resize(4 * mp.single.size() + 4);
        for (size_t t = 0; t < mp.single.size(); ++t) {
            const uint32_t* tri = idx + 3 * size_t(mp.single[t]);
            uint32_t* q = mp.singleIndex.data() + 4 * t;
            q[0] = tri[0], q[1] = tri[1], q[2] = tri[2], q[3] = tri[2];
        }
    }
    return mp;
}

// A hashed alpha's coin: uniform in [0, 1) from the ray's origin and direction (their bits) and
// the instance and triangle hit. The same ray meets the same decision in packets and alone, on
// every machine; rays of other samples (jittered, or bounced elsewhere) meet independent ones.
float rayTriangleHash(RTCRayN* ray, unsigned N, unsigned k, unsigned inst, uint32_t prim) {
    const float f[6] = {RTCRayN_org_x(ray, N, k), RTCRayN_org_y(ray, N, k), RTCRayN_org_z(ray, N, k),
                        RTCRayN_dir_x(ray, N, k), RTCRayN_dir_y(ray, N, k), RTCRayN_dir_z(ray, N, k)};
    uint32_t h = hashCombine(fmix32(inst + 0x3C6EF372u), prim);
    for (float x : f) {
        uint32_t bits;
        std::memcpy(&bits, &x, 4);
        h = hashCombine(h, bits);
    }
    return float(h >> 8) * (1.0f / 16777216.0f);
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
        const TriangleHit h = triangleHit(*data.prims, RTCHitN_geomID(args->hit, args->N, k),
                                          RTCHitN_primID(args->hit, args->N, k), RTCHitN_u(args->hit, args->N, k),
                                          RTCHitN_v(args->hit, args->N, k));
        float uv[2];
        const bool hasUV = data.mesh->hasUVs();
        if (hasUV) meshUVAt(*data.mesh, h.prim, h.u, h.v, uv);
        const float hash = model.alphaHashed() ? rayTriangleHash(args->ray, args->N, k, inst, h.prim) : 0.0f;
        if (!model.alphaAt(objectPosition(*data.mesh, h.prim, h.u, h.v), hasUV ? uv : nullptr, hash)) args->valid[k] = 0;
    }
}

void setAlphaFilter(RTCGeometry g, Scene::Impl& s) {
    rtcSetGeometryUserData(g, &s);
    rtcSetGeometryIntersectFilterFunction(g, alphaFilter);
    rtcSetGeometryOccludedFilterFunction(g, alphaFilter);
}

void installAlphaFilters(Scene::Impl& s) {
    for (size_t mi = 0; mi < s.meshScenes.size(); ++mi) {
        // rtcGetGeometry does not check its ID (release builds): ask only for what was attached.
        const unsigned count = s.meshPrims[mi].geometries;
        for (unsigned id = 0; id < count; ++id) {
            RTCGeometry g = rtcGetGeometry(s.meshScenes[mi], id);
            setAlphaFilter(g, s);
            rtcCommitGeometry(g);
        }
        if (count > 0) rtcCommitScene(s.meshScenes[mi]);
    }
    s.filtersInstalled = true;
}

}  // namespace

unsigned instanceMask(const Scene::Impl& s, const InstanceData& data) {
    return s.models[data.material]->shadowTransparent() ? kMaskShadowTransparent : kMaskOpaque;
}

namespace {

void updateShadowTransparency(Scene::Impl& s) {
    s.anyShadowTransparent = false;
    for (const InstanceData& d : s.instances) s.anyShadowTransparent |= s.models[d.material]->shadowTransparent();
}

}  // namespace

namespace {

// The copies of instance i in the top levels, for a change that applies to both.
template <class F> void forEachCopy(Scene::Impl& s, uint32_t i, F&& f) {
    if (s.inTop[i]) {
        f(rtcGetGeometry(s.top, i));
        s.dirty = true;
        ++s.topGeneration;
    }
    if (s.inMoving[i]) {
        f(rtcGetGeometry(s.moving, i));
        s.movingDirty = true;
    }
}

}  // namespace

namespace {

void checkSection(uint32_t index, const SectionPlane& plane) {
    const Float3& p = plane.point;
    const Float3& n = plane.normal;
    const Color& c = plane.capColor;
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(n.x) && std::isfinite(n.y) &&
          std::isfinite(n.z) && std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z)))
        throw std::invalid_argument("section " + std::to_string(index) + " is not finite");
    if (!(n.x * n.x + n.y * n.y + n.z * n.z > 0.0f))
        throw std::invalid_argument("section " + std::to_string(index) + " has a zero normal");
}

// desc.sections as the kernel reads them, and a cap material per enabled plane. O(kMaxSections):
// nothing else in the scene depends on the planes.
void updateSections(Scene::Impl& s) {
    SectionState st;
    std::vector<std::unique_ptr<MaterialModel>> caps;
    for (uint32_t i = 0; i < uint32_t(kMaxSections); ++i) {
        const SectionPlane& plane = s.desc.sections[i];
        checkSection(i, plane);
        if (!plane.enabled) continue;
        const Float3 n = normalize(plane.normal);
        st.n[st.count] = n;
        st.d[st.count] = dot(n, plane.point);
        st.caps[st.count] = plane.caps;
        st.capColor[st.count] = plane.capColor;
        Material cap;
        cap.name = "section cap " + std::to_string(i);
        cap.type = MaterialType::Lambert;
        cap.color = plane.capColor;
        caps.push_back(makeMaterialModel(cap));
        ++st.count;
    }
    s.sections = st;
    s.capModels = std::move(caps);
}

// Mesh `mi`'s own BVH (an Embree scene of its triangles, or of its triangles paired into quads),
// appended to s.meshScenes.
void buildMeshScene(Scene::Impl& s, size_t mi, bool anyAlpha) {
    const MeshDesc& md = s.desc.meshes[mi];
    const TriangleMesh& mesh = *md.mesh;
    MeshPrimitives& mp = s.meshPrims[mi];
    if (s.desc.bvh.primitives == BvhSettings::Primitives::Auto) mp = pairIntoQuads(mesh);
    RTCScene ms = rtcNewScene(s.device);
    s.meshScenes.push_back(ms);
    rtcSetSceneBuildQuality(ms, buildQuality(s.desc.bvh.quality));
    rtcSetSceneFlags(ms, sceneFlags(s.desc.bvh, mp.quads > 0));
    rtcSetSceneProgressMonitorFunction(ms, buildProgress, &s);
    s.currentMesh = double(mesh.triangleCount());
    // Shared buffers: Embree reads the mesh's arrays in place, whether the importer
    // filled them or they are the pages of a mapped cache file (TriangleMesh's
    // MeshArray); both carry the 16 bytes of tail padding Embree's SIMD loads need.
    auto attach = [&](RTCGeometryType type, RTCFormat format, const uint32_t* index, size_t byteOffset,
                      size_t byteStride, size_t count, unsigned id) {
        RTCGeometry g = rtcNewGeometry(s.device, type);
        rtcSetGeometryBuildQuality(g, buildQuality(s.desc.bvh.quality));
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, mesh.positions(), 0,
                                   3 * sizeof(float), mesh.vertexCount());
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, format, index, byteOffset, byteStride, count);
        rtcSetGeometryMask(g, kMaskAll);  // instances carry the masks that matter
        if (anyAlpha) setAlphaFilter(g, s);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(ms, g, id);
        mp.geometries = id + 1;
        rtcReleaseGeometry(g);
    };
    if (mp.quads > 0) {
        if (mp.quadIndex.empty())  // the window view of the triangle index array
            attach(RTC_GEOMETRY_TYPE_QUAD, RTC_FORMAT_UINT4, mesh.indices(), sizeof(uint32_t),
                   6 * sizeof(uint32_t), mp.quads, 0);
        else
            attach(RTC_GEOMETRY_TYPE_QUAD, RTC_FORMAT_UINT4, mp.quadIndex.data(), 0, 4 * sizeof(uint32_t),
                   mp.quads, 0);
        if (!mp.single.empty())
            attach(RTC_GEOMETRY_TYPE_QUAD, RTC_FORMAT_UINT4, mp.singleIndex.data(), 0, 4 * sizeof(uint32_t),
                   mp.single.size(), 1);
    } else if (mesh.triangleCount() > 0) {
        attach(RTC_GEOMETRY_TYPE_TRIANGLE, RTC_FORMAT_UINT3, mesh.indices(), 0, 3 * sizeof(uint32_t),
               mesh.triangleCount(), 0);
    }
    rtcCommitScene(ms);
    if (s.cancelled) throw Cancelled();
    checkDevice(s.device, s.lastError, ("building the BVH of mesh '" + md.name + "'").c_str());
}

}  // namespace

Scene::Scene(const SceneDesc& desc) : Scene(desc, ProgressFn{}) {}

Scene::Scene(const SceneDesc& desc, const ProgressFn& progress) : impl_(std::make_unique<Impl>()) {
    Impl& s = *impl_;
    s.desc = desc;
    s.randomContent = samplesRandomly(s.desc);
    s.progress = progress;
    std::string& lastError = s.lastError;
    s.device = rtcNewDevice(nullptr);
    if (!s.device) throw std::runtime_error("cannot create an Embree device (rtcNewDevice failed)");
    rtcSetDeviceErrorFunction(s.device, embreeErrorHandler, &lastError);
    rtcSetDeviceMemoryMonitorFunction(s.device, memoryMonitor, &s.embreeBytes);
    s.coherentOcclusion = coherentOcclusionIsSafe(s.device);
    for (const MeshDesc& md : s.desc.meshes) s.trianglesTotal += double(md.mesh->triangleCount());

    try {
        s.models.reserve(s.desc.materials.size());
        bool anyAlpha = false;
        const ScopedSceneFiles files(&s.desc.files);  // textures and volumes given in memory
        for (const Material& m : s.desc.materials) {
            s.models.push_back(makeMaterialModel(m));
            anyAlpha |= s.models.back()->alphaMasked();
        }
        updateSections(s);
        std::vector<Bounds3> meshBounds(s.desc.meshes.size());
        for (size_t i = 0; i < s.desc.meshes.size(); ++i) meshBounds[i] = s.desc.meshes[i].mesh->bounds();
        s.meshScenes.reserve(s.desc.meshes.size());
        s.meshPrims.resize(s.desc.meshes.size());  // not resized again: instances point into it
        for (size_t mi = 0; mi < s.desc.meshes.size(); ++mi) {
            buildMeshScene(s, mi, anyAlpha);
            s.trianglesBuilt += s.currentMesh;
        }
        s.progress = nullptr;
        s.meshBvhBytes = s.embreeBytes.load();
        s.filtersInstalled = anyAlpha;

        s.top = rtcNewScene(s.device);
        rtcSetSceneFlags(s.top, sceneFlags(s.desc.bvh));
        s.moving = rtcNewScene(s.device);
        rtcSetSceneFlags(s.moving, sceneFlags(s.desc.bvh));
        rtcCommitScene(s.moving);
        const size_t n = s.desc.instances.size();
        s.inTop.assign(n, 1);
        s.inMoving.assign(n, 0);
        s.staleInTop.assign(n, 0);
        s.movedStamp.assign(n, 0);
        s.movedCommit.assign(n, 0);
        s.instances.resize(s.desc.instances.size());
        for (size_t i = 0; i < s.desc.instances.size(); ++i) {
            const InstanceDesc& in = s.desc.instances[i];
            InstanceData& data = s.instances[i];
            data.mesh = s.desc.meshes.at(in.mesh).mesh.get();
            data.prims = &s.meshPrims[in.mesh];
            if (in.material >= s.desc.materials.size())
                throw std::out_of_range("instance " + std::to_string(i) + ": material " + std::to_string(in.material) +
                                        " does not exist");
            data.material = in.material;
            data.meshBounds = meshBounds[in.mesh];
            for (int k = 0; k < 12; ++k) data.objectToWorld[k] = float(in.transform.m[k]);
            normalMatrixOf(in.transform, data.normalMatrix);
            worldToObjectOf(in.transform, data.worldToObject);

            data.hidden = in.visibility == Visibility::Hidden;
            data.highlighted = in.visibility == Visibility::Highlighted;
            RTCGeometry g = instanceGeometry(s.device, s.meshScenes[in.mesh], data.objectToWorld, instanceMask(s, data), data.hidden);
            // A movable instance lives in the moving top level from the start: moving it never
            // makes the static one stale.
            if (in.movable) {
                rtcAttachGeometryByID(s.moving, g, unsigned(i));
                s.inTop[i] = 0;
                s.inMoving[i] = 1;
                ++s.movingCount;
            } else {
                rtcAttachGeometryByID(s.top, g, unsigned(i));
            }
            rtcReleaseGeometry(g);
        }
        updateShadowTransparency(s);
        findLightFaces(s);
        rtcCommitScene(s.top);
        if (s.movingCount > 0) rtcCommitScene(s.moving);
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
        if (s.moving) rtcReleaseScene(s.moving);
        rtcReleaseDevice(s.device);
        throw;
    }
}

Scene::~Scene() {
    if (!impl_) return;
    dropRebuild(*impl_);  // joins a rebuild in flight
    if (impl_->top) rtcReleaseScene(impl_->top);
    if (impl_->moving) rtcReleaseScene(impl_->moving);
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
    // The change goes to the instance's copy in `moving` (made on its first move); its copy in
    // `top` goes stale, and the next commit starts a rebuild of `top` without it.
    if (s.inMoving[instance]) {
        RTCGeometry g = rtcGetGeometry(s.moving, instance);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, data.objectToWorld);
        rtcCommitGeometry(g);
    } else {
        RTCGeometry g = instanceGeometry(s.device, s.meshScenes[s.desc.instances[instance].mesh], data.objectToWorld,
                                         instanceMask(s, data), data.hidden);
        rtcAttachGeometryByID(s.moving, g, instance);
        rtcReleaseGeometry(g);
        s.inMoving[instance] = 1;
        ++s.movingCount;
    }
    if (s.inTop[instance] && !s.staleInTop[instance]) {
        s.staleInTop[instance] = 1;
        ++s.staleCount;
    }
    s.movedStamp[instance] = ++s.changeStamp;
    s.movedCommit[instance] = s.commits;
    s.movingDirty = true;
    if (mayBeLightFace(s, data)) findLightFaces(s);  // a lamp panel moved onto or off an area light
}

void Scene::setInstanceVisibility(uint32_t instance, Visibility visibility) {
    Impl& s = *impl_;
    if (instance >= s.instances.size()) throw std::out_of_range("instance " + std::to_string(instance) + " does not exist");
    InstanceData& data = s.instances[instance];
    const bool hidden = visibility == Visibility::Hidden;
    s.desc.instances[instance].visibility = visibility;
    data.highlighted = visibility == Visibility::Highlighted;
    if (hidden == data.hidden) return;
    data.hidden = hidden;
    forEachCopy(s, instance, [&](RTCGeometry g) { hidden ? rtcDisableGeometry(g) : rtcEnableGeometry(g); });
    if (mayBeLightFace(s, data)) findLightFaces(s);  // a hidden lamp panel is no face of its area light
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
    if (s.models[material]->alphaMasked() && !s.filtersInstalled) {
        // The mesh scenes change: a rebuild of the top level reading them must end first.
        joinRebuild(s);
        installAlphaFilters(s);
    }
    // Shadow rays find shadow-transparent instances by their Embree mask.
    for (size_t i = 0; i < s.instances.size(); ++i) {
        if (s.instances[i].material != material) continue;
        const unsigned mask = instanceMask(s, s.instances[i]);
        forEachCopy(s, uint32_t(i), [&](RTCGeometry g) {
            rtcSetGeometryMask(g, mask);
            rtcCommitGeometry(g);
        });
    }
    updateShadowTransparency(s);
    s.randomContent = samplesRandomly(s.desc);
    findLightFaces(s);  // an emission turned on or off, or made two-sided
}

void Scene::addFile(const std::string& path, std::shared_ptr<const std::vector<uint8_t>> bytes) {
    impl_->desc.files[path] = std::move(bytes);
}

void Scene::setLight(uint32_t light, const Light& value) {
    Impl& s = *impl_;
    if (light >= s.desc.lights.size()) throw std::out_of_range("light " + std::to_string(light) + " does not exist");
    s.desc.lights[light] = value;
    s.randomContent = samplesRandomly(s.desc);
    findLightFaces(s);
}

void Scene::setSection(uint32_t index, const SectionPlane& plane) {
    Impl& s = *impl_;
    if (index >= uint32_t(kMaxSections))
        throw std::out_of_range("section " + std::to_string(index) + " does not exist (at most " +
                                std::to_string(kMaxSections) + ")");
    checkSection(index, plane);  // before anything changes
    s.desc.sections[index] = plane;
    updateSections(s);
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
    for (const MeshPrimitives& mp : impl_->meshPrims) bytes += mp.bytes();  // quad and leftover index buffers
    return bytes;
}

Scene::PrimitiveStats Scene::primitiveStats() const {
    PrimitiveStats st;
    for (size_t i = 0; i < impl_->meshPrims.size(); ++i) {
        const MeshPrimitives& mp = impl_->meshPrims[i];
        const size_t tris = impl_->desc.meshes[i].mesh->triangleCount();
        st.triangles += tris;
        st.pairs += tris / 2;
        st.pairsSharingEdge += mp.pairsSharingEdge;
        st.quads += mp.quads;
        st.separateTriangles += mp.quads > 0 ? mp.single.size() : tris;
        st.quadIndexBytes += mp.bytes();
        (mp.quads > 0 ? st.meshesAsQuads : st.meshesAsTriangles) += 1;
        st.quadsInPlace += mp.quads > 0 && mp.quadIndex.empty() ? mp.quads : 0;
    }
    return st;
}

RTCScene embreeScene(const Scene& scene) { return scene.impl().top; }
bool coherentOcclusion(const Scene& scene) { return scene.impl().coherentOcclusion; }

}  // namespace rtwall
