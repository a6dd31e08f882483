// Shading: turns one hit into contributions, shadow rays and secondary rays. Scalar code used
// unchanged by the packet and single-ray kernels. The materials themselves live behind the
// MaterialModel interface (material.h); this file holds what every material shares.
#pragma once

#include "scene_impl.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace rtwall {

inline constexpr uint32_t kNoHit = 0xFFFFFFFFu;
// Hit::inst of a section plane's cap; Hit::prim is then the plane's index in Impl::sections.
inline constexpr uint32_t kCapHit = 0xFFFFFFFEu;

// Embree ray masks: shadow rays first test only opaque instances with the fast occlusion
// query, then walk the shadow-transparent ones (glass, volumes) hit by hit.
inline constexpr uint32_t kMaskOpaque = 1u;
inline constexpr uint32_t kMaskShadowTransparent = 2u;
inline constexpr uint32_t kMaskAll = 0xFFFFFFFFu;

struct RayTask {
    Float3 org, dir;  // dir is unit length
    float tfar;
    Color weight;     // throughput from the pixel to this ray, including the sample weight
    uint32_t pixel;   // index into the tile's accumulation buffer
    int depth;        // 1 for primary rays
    uint32_t seed;    // random-number seed of this path vertex (sampling.h)
    // Seed of the pruning roulette along this path: per frame with GI (progressive frames
    // average its noise away), the same every frame without (a still Whitted view is stable).
    uint32_t rouletteSeed;
    // Multiple importance sampling (light_faces.cpp): the density per solid angle with which the
    // vertex that chose this direction sampled it, where that vertex also sampled the area lights
    // (next-event estimation); 0 for camera rays and specular rays, whose emission counts in
    // full. `travelled` is how far this ray's origin lies from that vertex along the same line
    // (a ray that went on through a volume keeps its direction and its density).
    float bsdfPdf = 0.0f;
    float travelled = 0.0f;
    // Section planes (clipRays in kernel.cpp): where the traced interval starts (tnear > tfar:
    // nothing of the ray is kept), and the plane it enters the kept region through (-1: none).
    float tnear = 0.0f;
    int32_t enter = -1;
};

struct Hit {
    float t, u, v;  // Embree's distance and primitive parametrisation (triangleHit() maps it)
    Float3 ng;      // Embree's unnormalised geometric normal, in the instance's object space
    uint32_t inst;  // instance index, kNoHit for a miss
    uint32_t prim;  // Embree's primID and geomID in the instance's mesh scene
    uint32_t geom;
};

struct ShadowTask {
    Float3 org, dir;
    float tfar;
    Color contribution;  // added to the pixel if the light is visible, times what passes
    uint32_t pixel;
    float tnear = 0.0f;  // section planes, as RayTask::tnear
};

struct ShadingContext {
    const Scene::Impl& scene;
    const RenderSettings& settings;
    float sampleWeight = 1.0f;  // weight of one primary sample in its pixel (pruning is relative to it)
};

// A mesh's vertex colour at barycentrics (u, v) of triangle `prim`: the three 8-bit sRGB colours
// decoded to linear and interpolated there (colour in linear light, like everything shaded).
inline Color vertexColorAt(const TriangleMesh& mesh, uint32_t prim, float u, float v);

inline Float3 transformNormal(const float n[9], const Float3& v) {
    return {n[0] * v.x + n[1] * v.y + n[2] * v.z, n[3] * v.x + n[4] * v.y + n[5] * v.z,
            n[6] * v.x + n[7] * v.y + n[8] * v.z};
}

// Preview shading from what Embree returned alone (no mesh data is touched): the colour
// times the cosine between the geometric normal and the ray, for a whole primary packet in
// structure-of-arrays form so that the square roots and divisions vectorise.
template <int K, class RayHitK>
inline void shadeEyeLightPacket(const ShadingContext& ctx, const RayHitK& rh, const int* valid, const uint32_t* pixel,
                                float weight, Color* accum) {
    alignas(64) float nx[K], ny[K], nz[K], cr[K], cg[K], cb[K], cosine[K];
    for (int k = 0; k < K; ++k) {
        if (valid[k] && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID && rh.hit.instID[0][k] == kCapHit) {
            nx[k] = rh.hit.Ng_x[k];
            ny[k] = rh.hit.Ng_y[k];
            nz[k] = rh.hit.Ng_z[k];
            const Color& cap = ctx.scene.sections.capColor[rh.hit.primID[k]];
            cr[k] = cap.x;
            cg[k] = cap.y;
            cb[k] = cap.z;
            continue;
        }
        if (!valid[k] || rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
            // A miss (or an unused lane) takes the background at cosine 1.
            nx[k] = rh.ray.dir_x[k];
            ny[k] = rh.ray.dir_y[k];
            nz[k] = rh.ray.dir_z[k];
            cr[k] = ctx.settings.background.x;
            cg[k] = ctx.settings.background.y;
            cb[k] = ctx.settings.background.z;
            continue;
        }
        const InstanceData& inst = ctx.scene.instances[rh.hit.instID[0][k]];
        const Float3 ng = transformNormal(inst.normalMatrix, {rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]});
        nx[k] = ng.x;
        ny[k] = ng.y;
        nz[k] = ng.z;
        const Material& m = ctx.scene.desc.materials[inst.material];
        cr[k] = m.color.x;
        cg[k] = m.color.y;
        cb[k] = m.color.z;
        if (inst.mesh->hasColors()) {
            const TriangleHit th = triangleHit(*inst.prims, rh.hit.geomID[k], rh.hit.primID[k], rh.hit.u[k], rh.hit.v[k]);
            const Color tint = vertexColorAt(*inst.mesh, th.prim, th.u, th.v);
            cr[k] *= tint.x;
            cg[k] *= tint.y;
            cb[k] *= tint.z;
        }
        if (inst.highlighted) {
            cr[k] *= kHighlightTint.x;
            cg[k] *= kHighlightTint.y;
            cb[k] *= kHighlightTint.z;
        }
    }
    for (int k = 0; k < K; ++k) {
        const float nn = nx[k] * nx[k] + ny[k] * ny[k] + nz[k] * nz[k];
        cosine[k] = std::fabs(nx[k] * rh.ray.dir_x[k] + ny[k] * rh.ray.dir_y[k] + nz[k] * rh.ray.dir_z[k]) / std::sqrt(nn);
    }
    for (int k = 0; k < K; ++k) {
        if (!valid[k]) continue;
        // A miss uses cosine 1 exactly, whatever rounding the division above did.
        const float c = rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID ? 1.0f : cosine[k];
        Color& p = accum[pixel[k]];
        p.x += weight * cr[k] * c;
        p.y += weight * cg[k] * c;
        p.z += weight * cb[k] * c;
        if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID && rh.hit.instID[0][k] != kCapHit &&  // a cap is no instance
            ctx.scene.instances[rh.hit.instID[0][k]].highlighted) {
            p.x += weight * kHighlightGlow.x;
            p.y += weight * kHighlightGlow.y;
            p.z += weight * kHighlightGlow.z;
        }
    }
}

// Adds what is known now to `pixel`, appends the shadow rays whose contribution depends on
// visibility to `shadows`, and the secondary rays to `next`.
void shadeHit(const ShadingContext& ctx, const RayTask& ray, const Hit& hit, Color& pixel,
              std::vector<ShadowTask>& shadows, std::vector<RayTask>& next);

// The first hit's features for a denoiser (FeatureView in rtwall/engine.h): the material's
// reflectance at the hit, the shading normal facing the ray, the instance + 1. A miss: white,
// zero, 0.
struct HitFeatures {
    Color albedo{1, 1, 1};
    Float3 normal{0, 0, 0};
    uint32_t id = 0;
};
HitFeatures featuresAt(const ShadingContext& ctx, const Float3& org, const Float3& dir, const Hit& hit);

// What part of a shadow ray's light passes its hit `hit`, and where the walk goes on (the
// ray parameter to continue from). Used only for instances whose material is shadow-transparent.
struct ShadowPass {
    Color transmittance{0, 0, 0};
    float continueAt = 0.0f;
};
ShadowPass shadowPassAt(const ShadingContext& ctx, const ShadowTask& ray, const Hit& hit);

// The density per solid angle with which next-event estimation samples the direction `dir` from
// `org` on area light `light` (uniform over its area), or 0 where it cannot: the ray misses the
// parallelogram, meets its dark side, or something at `tBlock` or nearer would block the shadow
// ray (which stops at 0.9999 of the light's distance). `travelled` is added to both distances.
float areaLightPdf(const Light& light, const Float3& org, const Float3& dir, float tBlock, float travelled = 0.0f);

// Scale-aware offset for secondary-ray origins: a fixed epsilon is too small far from the
// origin and too large for small models. 2^-16 relative to the coordinate magnitude is about
// 128 float ulps, well above intersection error and well below any modelled feature.
Float3 offsetOrigin(const Float3& p, const Float3& ng, float side);

// Correctly rounded linear-to-sRGB quantisation: a bucket table gives the code at the start of
// each of 4096 equal linear intervals. Codes are at least 1/(12.92*255) = 3.0e-4 apart in
// linear terms (the spacing is smallest near black), wider than a bucket (2.4e-4), so at most
// one threshold falls inside a bucket and one branch-free compare finishes the job: exact,
// without pow() or a search.
struct SrgbTables {
    static constexpr int kBuckets = 4096;
    float thresholds[257];  // [c]: linear value halfway (in sRGB) between codes c-1 and c; [256] = +inf
    float toLinear[256];
    uint8_t bucketStart[kBuckets];
    SrgbTables();
};
extern const SrgbTables kSrgb;

inline uint8_t linearToSrgb8(float linear) {
    if (!(linear > 0.0f)) return 0;  // also maps NaN to black
    if (linear >= 1.0f) return 255;
    const int c = kSrgb.bucketStart[int(linear * float(SrgbTables::kBuckets))];
    return uint8_t(c + (linear >= kSrgb.thresholds[c + 1]));
}
inline float srgb8ToLinear(uint8_t value) { return kSrgb.toLinear[value]; }

inline Color vertexColorAt(const TriangleMesh& mesh, uint32_t prim, float u, float v) {
    const uint32_t* tri = mesh.indices() + 3 * size_t(prim);
    const uint8_t* c = mesh.colors();
    const float w[3] = {1.0f - u - v, u, v};
    Color out{0, 0, 0};
    for (int k = 0; k < 3; ++k) {
        const uint8_t* ck = c + 3 * size_t(tri[k]);
        out.x += w[k] * srgb8ToLinear(ck[0]);
        out.y += w[k] * srgb8ToLinear(ck[1]);
        out.z += w[k] * srgb8ToLinear(ck[2]);
    }
    return out;
}

// Exact dielectric Fresnel reflectance for unpolarised light; cosI > 0 is the cosine on the
// incident side, eta = n_incident / n_transmitted. Returns 1 for total internal reflection.
float fresnelDielectric(float cosI, float eta);

// Refracts unit direction d through unit normal n (facing against d). Returns false on total
// internal reflection.
bool refractDirection(const Float3& d, const Float3& n, float eta, Float3& out);

}  // namespace rtwall
