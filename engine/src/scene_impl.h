// Internal view of a built scene, shared by the kernel and the benchmarks.
#pragma once

#include <rtwall/engine.h>

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace rtwall {

class MaterialModel;

// How one mesh was handed to Embree ([bvh] primitives), and what maps a hit back to one of its
// triangles. In quad form, geometry 0 holds quad k for the triangle pair (2k, 2k+1) when the two
// share an edge (Embree splits quad (q0,q1,q2,q3) into (q0,q1,q3) and (q2,q3,q1): the pair's two
// triangles exactly, same orientation), or a degenerate quad (q0,q1,q3,q3) holding 2k alone when
// they do not; geometry 1 holds the triangles no pair holds (2k+1 of such pairs, an odd last one)
// as degenerate quads (t0,t1,t2,t2), so the mesh keeps one BVH (Embree builds one per type).
inline constexpr uint8_t kQuadWithoutSecondTriangle = 3u << 2;  // code of an unpaired pair's quad
struct MeshPrimitives {
    uint32_t quads = 0;  // 0: the mesh went to Embree as plain triangles, primID is the triangle
    // Per quad, which corner of each triangle is not on the shared edge: bits 0-1 the position of
    // q0 in triangle 2k, bits 2-3 the position of q2 in triangle 2k+1 (3: there is no second
    // triangle, kQuadWithoutSecondTriangle). `code` when every quad has
    // the same (the usual case: one generator or importer makes every pair alike), else `codes`.
    uint8_t code = 0;
    std::vector<uint8_t> codes;
    // The quad index buffer, 4 per quad plus padding; empty when it is a view into the mesh's own
    // triangle index array: a pair stored as (q3,q0,q1),(q2,q3,q1) holds the quad's four indices
    // contiguously from its second index on (byte offset 4, stride 24), so it costs nothing.
    std::vector<uint32_t> quadIndex;
    std::vector<uint32_t> singleIndex;  // geometry 1: a degenerate quad per triangle, plus padding
    std::vector<uint32_t> single;       // geometry 1: the mesh triangle of each of its quads
    size_t pairsSharingEdge = 0;        // of the mesh's triangleCount()/2 pairs
    unsigned geometries = 0;            // Embree geometries in the mesh's scene: IDs 0 .. geometries-1
    size_t bytes() const {
        return codes.capacity() + 4 * (quadIndex.capacity() + singleIndex.capacity() + single.capacity());
    }
};

// Embree's hit (geometry in the mesh's scene, primID, u, v) as the mesh triangle and its
// barycentrics (u for the triangle's vertex 1, v for vertex 2). Everything that reads a hit's
// primitive goes through this: surface points (normals, colours, object positions), the
// eye-light preview and the alpha-mask filter. A quad's u, v are Embree's quad parametrisation:
// on (q0,q1,q3) the barycentrics of q1 and q3; on (q2,q3,q1), u = 1 - (weight of q3) and
// v = 1 - (weight of q1), so u + v >= 1 there. On the diagonal both readings give the same point.
struct TriangleHit {
    uint32_t prim;
    float u, v;
};
inline TriangleHit triangleHit(const MeshPrimitives& mp, uint32_t geom, uint32_t prim, float u, float v) {
    if (mp.quads == 0) return {prim, u, v};
    if (geom != 0) return {mp.single[prim], u, v};
    const unsigned code = mp.codes.empty() ? mp.code : mp.codes[prim];
    float w[3];  // weights of the corners starting at the triangle's corner off the shared edge
    unsigned first;
    if (u + v <= 1.0f || code == kQuadWithoutSecondTriangle) {
        w[0] = 1.0f - u - v;  // q0, then q1 (u) and q3 (v)
        w[1] = u;
        w[2] = v;
        first = code & 3u;
        prim = 2 * prim;
    } else {
        w[0] = u + v - 1.0f;  // q2, then q3 and q1
        w[1] = 1.0f - u;
        w[2] = 1.0f - v;
        first = (code >> 2) & 3u;
        prim = 2 * prim + 1;
    }
    // Corner c of the triangle carries w[(c - first) mod 3].
    return {prim, w[(4 - first) % 3], w[(5 - first) % 3]};
}

struct InstanceData {
    const TriangleMesh* mesh = nullptr;
    const MeshPrimitives* prims = nullptr;  // how the mesh went to Embree
    uint32_t material = 0;       // index into desc.materials and models
    float normalMatrix[9] = {};  // row-major inverse transpose of the object-to-world 3x3
    float objectToWorld[12] = {};
    float worldToObject[12] = {};  // for materials that work in object space (volumes)
    Bounds3 meshBounds;            // object-space bounds of the mesh (the box a volume fills)
    int32_t areaLight = -1;        // the area light this emitter is the visible face of (light_faces.cpp), or -1
    bool hidden = false;           // Visibility::Hidden: disabled in the top level, never hit
    bool highlighted = false;      // Visibility::Highlighted: shadeHit tints it (kHighlightTint, kHighlightGlow)
};

// True when the scene samples something at random whatever the settings: an area light, a rough
// metal or a volume in use (rendersStochastically adds path tracing and the view).
bool samplesRandomly(const SceneDesc& scene);
// The criterion of rendersStochastically(SceneDesc) for a scene whose content part is known:
// when it holds, frames differ and averaging them converges, so the kernel varies the sub-pixel
// position and the pruning roulette per frame too.
bool rendersStochastically(const RenderSettings& settings, bool randomContent);

// False where Embree's coherent occlusion traversal is known to hang: Embree 3 running its
// AVX-512 kernels (kernel.cpp).
bool coherentOcclusionIsSafe(RTCDevice device);
// Finds which emitting instances are the visible faces of which area lights and sets
// InstanceData::areaLight and Impl::lightFaces; run whenever instances, materials or lights
// change.
void findLightFaces(Scene::Impl& s);
// Whether moving, hiding or showing this instance can change what findLightFaces finds: only an
// emitter can be an area light's face, and only where the scene has an area light. The search
// goes over every instance, so an update of anything else skips it (bulk updates stay linear).
bool mayBeLightFace(const Scene::Impl& s, const InstanceData& data);

// The enabled section planes as the kernel reads them (SceneDesc::sections compacted): a point x
// is kept when dot(n, x) >= d for every plane. The ray interval is clipped to the kept region
// (convex, so one interval) before Embree sees the ray: every ray kind and both kernels clip the
// same way, instancing cannot get in the way, and no BVH changes when a plane moves.
struct SectionState {
    int count = 0;
    Float3 n[kMaxSections] = {};  // unit normals, towards the kept side
    float d[kMaxSections] = {};
    bool caps[kMaxSections] = {};
    Color capColor[kMaxSections] = {};
};

// Each plane's signed distance of a ray origin (positive on the kept side): what every ray from
// that origin shares (a tile's primary rays compute it once).
inline void sectionDistances(const SectionState& c, const Float3& org, float* dist) {
    for (int i = 0; i < c.count; ++i) {
        const Float3& n = c.n[i];
        dist[i] = n.x * org.x + n.y * org.y + n.z * org.z - c.d[i];
    }
}

// The ray interval [t0, t1] clipped to the kept region, given sectionDistances of its origin;
// false when nothing of it is left. `enter` becomes the plane through which the ray enters the
// kept region at t0 > its old value (the plane a cap would lie on), or stays -1 when it starts
// inside.
inline bool clipToSections(const SectionState& c, const float* dist, const Float3& dir, float& t0, float& t1,
                           int& enter) {
    for (int i = 0; i < c.count; ++i) {
        const Float3& n = c.n[i];
        const float dn = n.x * dir.x + n.y * dir.y + n.z * dir.z;
        if (dn > 0.0f) {
            if (dist[i] < 0.0f) {
                const float t = -dist[i] / dn;
                if (t > t0) {
                    t0 = t;
                    enter = i;
                }
            }
        } else if (dn < 0.0f) {
            const float t = dist[i] / -dn;  // negative when the origin is cut away: empty
            if (t < t1) t1 = t;
        } else if (dist[i] < 0.0f) {
            return false;  // parallel to the plane on its cut-away side
        }
    }
    return t0 <= t1;
}

inline bool clipToSections(const SectionState& c, const Float3& org, const Float3& dir, float& t0, float& t1,
                           int& enter) {
    float dist[kMaxSections];
    sectionDistances(c, org, dist);
    return clipToSections(c, dist, dir, t0, t1, enter);
}

// A background rebuild of the static top level (scene.cpp): the instances it holds, as they
// were when it started, and the scene it builds.
struct TopRebuild;

struct Scene::Impl {
    SceneDesc desc;  // meshes are shared pointers: no second copy of any geometry
    std::string lastError;  // written by Embree's error callback
    RTCDevice device = nullptr;
    RTCScene top = nullptr;
    std::vector<RTCScene> meshScenes;      // one BVH per unique mesh
    std::vector<MeshPrimitives> meshPrims; // per desc.meshes entry: quads or triangles
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
    bool randomContent = false;            // samplesRandomly(desc): kept current by setMaterial/setLight
    // Whether shadow packets may ask for Embree's coherent occlusion traversal: false where
    // Embree's AVX-512 kernels run (coherentOcclusionIsSafe in kernel.cpp says why).
    bool coherentOcclusion = true;
    std::vector<LightFace> lightFaces;     // per desc.lights entry (findLightFaces)
    bool anyLightFace = false;             // some entry of lightFaces is not None
    // Part moves (issue 29). `top` is the static top level, rebuilt only in the background; an
    // instance whose transform changes gets a copy in `moving` (a small top level committed with
    // every change) and its copy in `top` goes stale: rays traced through `top` skip stale copies
    // (a context filter function reads staleInTop) and then through `moving`, keeping the closer
    // hit. A rebuild of `top` starts when a copy goes stale; it leaves out the instances then
    // moving (movers that have not changed for kSettleCommits commits are folded back in) and a
    // later commit() publishes it.
    RTCScene moving = nullptr;
    std::vector<uint8_t> inTop, inMoving, staleInTop;  // per instance
    size_t staleCount = 0, movingCount = 0;
    std::vector<uint64_t> movedStamp;   // per instance: changeStamp at its last transform change
    std::vector<uint64_t> movedCommit;  // per instance: commits at its last transform change
    uint64_t changeStamp = 0, commits = 0;
    uint64_t topGeneration = 0;         // bumped by every change to `top` (visibility, masks)
    bool movingDirty = false;
    std::unique_ptr<TopRebuild> rebuild;  // in flight, or done and not yet published
    SectionState sections;                 // the enabled planes of desc.sections
    std::vector<std::unique_ptr<MaterialModel>> capModels;  // per sections entry: Lambert of its cap colour
    InstanceData capInstance;              // what a cap's surface point names as its instance (no mesh)

    Impl();  // out of line, as ~Impl: where TopRebuild is complete (top_levels.cpp)
    ~Impl();
};

// Shared by scene.cpp and top_levels.cpp.
void checkDevice(RTCDevice device, const std::string& lastError, const char* what);  // throws on an Embree error
RTCSceneFlags sceneFlags(const BvhSettings& b, bool quads = false);
unsigned instanceMask(const Scene::Impl& s, const InstanceData& data);  // Embree mask: opaque or shadow-transparent
// An instance of `mesh` for a top level, committed (the caller attaches it).
RTCGeometry instanceGeometry(RTCDevice device, RTCScene mesh, const float objectToWorld[12], unsigned mask, bool hidden);
void joinRebuild(Scene::Impl& s);  // waits for a rebuild's thread (before the mesh scenes change)
void dropRebuild(Scene::Impl& s);  // joins and discards a rebuild (the scene's end)

// The two top levels traced as one (Scene::Impl, "part moves"): rays go through the static top
// level, where a context filter skips the stale copies of moving instances, then through the
// moving instances' level, which keeps a hit only where it is closer. Without movers the
// second pass is left out.
//
// Closest-hit queries also settle ties by rule: of two hits at the same distance (coincident
// faces: a part resting on another, two copies overlapping), the one of the lower instance, then
// the lower triangle, wins. Embree keeps whichever it meets last where its own test lets the
// second one through at all (it compares the unnormalised distance with tfar scaled, so an equal
// distance passes or not by rounding): which one depends on the BVH and on which level holds the
// instance, and a part that moves and comes back could show other pixels than a full rebuild at
// the same state. So the filter sees every candidate hit (Embree has set the ray's tfar to the
// candidate's distance), keeps per lane the hit committed so far, and sets tfar a little beyond
// it (16 float steps, kTieReach), so that a candidate at the same distance always reaches the
// filter, and one beyond is refused there. withTies primes the committed hit before each Embree
// call from what the ray holds (a hit from the level before, or none) and puts the exact
// distance back afterwards.
struct TopContext {
    RTCIntersectContext ctx;  // first: Embree hands the filter this pointer
    const Scene::Impl* scene = nullptr;
    bool skipStale = false;  // the static level while some instance moves
    bool ties = false;       // a closest-hit query: the tie rule
    float tieT[16];          // per lane: the committed hit's distance (INFINITY: none yet),
    unsigned tieInst[16], tiePrim[16];  // its instance and triangle
};
inline float tieReach(float t) { return t + std::max(t * 0x1.0p-19f, 0x1.0p-126f); }
inline void topFilter(const RTCFilterFunctionNArguments* args) {
    auto* c = reinterpret_cast<TopContext*>(const_cast<RTCIntersectContext*>(args->context));
    const unsigned inst = args->context->instID[0];
    if (c->skipStale && inst < c->scene->staleInTop.size() && c->scene->staleInTop[inst]) {
        for (unsigned k = 0; k < args->N; ++k) args->valid[k] = 0;
        return;
    }
    if (!c->ties) return;
    for (unsigned k = 0; k < args->N; ++k) {
        if (!args->valid[k]) continue;
        float& tfar = RTCRayN_tfar(args->ray, args->N, k);
        const float t = tfar;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, k);
        if (t > c->tieT[k] || (t == c->tieT[k] && (inst > c->tieInst[k] || (inst == c->tieInst[k] && prim >= c->tiePrim[k])))) {
            args->valid[k] = 0;  // farther, or the committed hit wins the tie (Embree puts tfar back)
            continue;
        }
        c->tieT[k] = t;
        c->tieInst[k] = inst;
        c->tiePrim[k] = prim;
        tfar = tieReach(t);
    }
}
inline TopContext* tieContext(RTCIntersectContext* c) {
    return c->filter == topFilter && reinterpret_cast<TopContext*>(c)->ties ? reinterpret_cast<TopContext*>(c) : nullptr;
}
// call() is one Embree closest-hit call on `c` for `rh` (RTCRayHit4/8/16): the tie rule around
// it (nothing for any other context).
template <class RayHitK, class F>
inline void withTies(RTCIntersectContext* c, RayHitK& rh, F&& call) {
    TopContext* t = tieContext(c);
    constexpr int K = int(sizeof(rh.ray.tfar) / sizeof(float));
    if (t)
        for (int k = 0; k < K; ++k) {
            const bool hit = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
            t->tieT[k] = hit ? rh.ray.tfar[k] : INFINITY;
            t->tieInst[k] = rh.hit.instID[0][k];
            t->tiePrim[k] = rh.hit.primID[k];
            if (hit) rh.ray.tfar[k] = tieReach(rh.ray.tfar[k]);
        }
    call();
    if (t)
        for (int k = 0; k < K; ++k)
            if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) rh.ray.tfar[k] = t->tieT[k];
}
template <class F>
inline void withTies(RTCIntersectContext* c, RTCRayHit& rh, F&& call) {
    TopContext* t = tieContext(c);
    const bool hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    if (t) {
        t->tieT[0] = hit ? rh.ray.tfar : INFINITY;
        t->tieInst[0] = rh.hit.instID[0];
        t->tiePrim[0] = rh.hit.primID;
        if (hit) rh.ray.tfar = tieReach(rh.ray.tfar);
    }
    call();
    if (t && rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) rh.ray.tfar = t->tieT[0];
}
struct TopLevels {
    TopContext top, moving;
    // `closest`: for closest-hit queries (the tie rule); shadow queries leave it out.
    TopLevels(const Scene::Impl& s, bool coherent, bool closest) {
        const RTCIntersectContextFlags flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
        for (TopContext* c : {&top, &moving}) {
            rtcInitIntersectContext(&c->ctx);
            c->ctx.flags = flags;
            c->scene = &s;
            c->ties = closest;
        }
        top.skipStale = s.staleCount > 0;
        if (top.skipStale || closest) top.ctx.filter = topFilter;
        if (closest) moving.ctx.filter = topFilter;
    }
    // f(scene, context) for each level a ray must go through, static first.
    template <class F> void each(const Scene::Impl& s, F&& f) {
        f(s.top, &top.ctx);
        if (s.movingCount > 0) f(s.moving, &moving.ctx);
    }
};

}  // namespace rtwall
