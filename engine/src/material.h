// The material interface. A material is one class: the kernel knows only this interface, so a
// new material plugs in by adding a class and a line in makeMaterialModel() (materials.cpp).
//
//   shade()        evaluates the material at a hit: adds what is known now (emission, ambient),
//                  asks for shadow rays (directLight) and spawns secondary rays (spawn).
//   shadowPass()   how much light a shadow ray keeps when it crosses this surface; opaque
//                  materials never see shadow rays (Embree's mask skips the fast path for them).
//   alphaAt()      alpha-masked materials: whether the surface exists at a point (for a
//                  hashed alpha: for this ray); Embree's intersection and occlusion filter
//                  functions call it, so holes are holes for camera, secondary and shadow rays
//                  alike.
#pragma once

#include "sampling.h"
#include "shading.h"
#include "texture.h"
#include "volume.h"

#include <memory>
#include <vector>

namespace rtwall {

struct SurfacePoint {
    Float3 p;        // world position
    Float3 ng;       // unit geometric normal, facing the incoming ray
    Float3 ns;       // unit shading normal, same hemisphere as ng (bumped where the material says)
    Float3 po;       // object-space position (textures, bumps, volumes)
    bool frontFace = true;  // the ray hit the side the triangle's winding calls "outside"
    float t = 0;            // hit distance
    const InstanceData* instance = nullptr;
    Color tint{1, 1, 1};  // the mesh's interpolated vertex colour (linear), white without one
    uint32_t prim = 0;    // the triangle hit (for the UV tangent frame)
    bool hasUV = false;   // the mesh has texture coordinates; then uv holds them at the hit
    float uv[2] = {0, 0};
    const float* uvOrNull() const { return hasUV ? uv : nullptr; }
};

// Object-space position from barycentrics: exact whatever space Embree traversed in.
inline Float3 objectPosition(const TriangleMesh& mesh, uint32_t prim, float u, float v) {
    const uint32_t* tri = mesh.indices() + 3 * size_t(prim);
    return mesh.position(tri[0]) * (1.0f - u - v) + mesh.position(tri[1]) * u + mesh.position(tri[2]) * v;
}

// The weight of a hit by `ray` on the visible face of an area light (sp.instance->areaLight),
// where the ray's origin also sampled that light (ray.bsdfPdf > 0): 1 where no light sample could
// have found the same path, else the power heuristic's share of the bounce (Covered) or 0
// (Partial: the light sample counted it in full).
float lightFaceWeight(const ShadingContext& ctx, const RayTask& ray, const SurfacePoint& sp);

// What a material's shade() may do. Spawned rays are pruned here by their contribution.
class ShadeContext {
public:
    // The random dimension of a path vertex's seed that decides its roulette (materials use
    // 0..63, directLight 64 and up).
    static constexpr uint32_t kRouletteDim = 0x7F000001u;

    ShadeContext(const ShadingContext& c, Color& pixel, std::vector<ShadowTask>& shadows, std::vector<RayTask>& next)
        : ctx(c), pixel_(pixel), shadows_(shadows), next_(next) {}

    const ShadingContext& ctx;

    float random(const RayTask& ray, uint32_t dim) const { return randomFloat(ray.seed, dim); }
    bool canSpawn(const RayTask& ray) const { return ray.depth < ctx.settings.maxDepth; }
    void add(const Color& c) { pixel_ += c; }
    // Whether some area light has a visible face (light_faces.cpp): only then do the sampling
    // densities of bounces matter, so materials compute them only then.
    bool weighsLightFaces() const { return ctx.scene.anyLightFace; }

    // Emission seen by `ray` at `sp`: `contribution` is the ray's weight times the radiance. The
    // back of a one-sided emitter is dark. A hit on the visible face of an area light, by a ray
    // whose origin also sampled that light, counts with the multiple importance sampling weight
    // that makes the two ways of finding the light add up to it once (lightFaceWeight).
    void addEmission(const RayTask& ray, const SurfacePoint& sp, const Color& contribution, bool twoSided) {
        if (!sp.frontFace && !twoSided) return;
        if (ray.bsdfPdf > 0.0f && sp.instance->areaLight >= 0) {
            const float w = lightFaceWeight(ctx, ray, sp);
            if (w < 1.0f) {
                if (w > 0.0f) pixel_ += contribution * w;
                return;
            }
        }
        pixel_ += contribution;
    }

    // A secondary ray with throughput `weight`; `branch` tells apart the rays one hit spawns.
    // `pdf`: the density per solid angle with which `dir` was sampled, when this vertex also
    // sampled the area lights with directLight (for multiple importance sampling); 0 otherwise.
    void spawn(const RayTask& parent, const Float3& org, const Float3& dir, const Color& weight, uint32_t branch,
               float pdf = 0.0f, float travelled = 0.0f) {
        const float m = maxComponent(weight);
        if (!(m > 0.0f)) return;
        const uint32_t rouletteSeed = hashCombine(parent.rouletteSeed, 0xB5297A4Du + branch);
        Color w = weight;
        // Ray-tree pruning by Russian roulette: a ray whose throughput to its pixel is below the
        // threshold (relative to one sample's share) survives with probability m / limit and
        // then carries the limit. Dropping such rays outright loses the energy of thousands of
        // tiny glass reflections (a systematically dark image); the roulette keeps the
        // expectation exact and bounds the work. The coin is a hash of the child's path seed
        // (RayTask::rouletteSeed): the same for every tile split and render client. At threshold 0 nothing is dropped.
        // A dominant child (at least half its parent's throughput: the refraction of a path at
        // the limit, total internal reflection, a mirror) that still carries at least half the
        // limit goes on without a coin: its roulette would be the largest noise of a limit
        // path (the whole path lost 4% of the time at every glass interface) for a saving of
        // 4% of its rays (headlight at the default: +0.75 dB, +10% rays).
        const float limit = ctx.settings.pruneThreshold * ctx.sampleWeight;
        const bool dominant = m >= 0.5f * limit && m >= 0.5f * maxComponent(parent.weight);
        if (m < limit && !dominant) {
            if (!(randomFloat(rouletteSeed, kRouletteDim) * limit < m)) return;
            w = weight * (limit / m);
        }
        RayTask r;
        r.org = org;
        r.dir = dir;
        r.tfar = INFINITY;
        r.weight = w;
        r.pixel = parent.pixel;
        r.depth = parent.depth + 1;
        r.seed = hashCombine(parent.seed, 0xB5297A4Du + branch);
        r.rouletteSeed = rouletteSeed;
        r.bsdfPdf = pdf;
        r.travelled = travelled;
        next_.push_back(r);
    }

    // Direct light from every light, with shadow rays. brdfCos(wi) returns the BRDF times the
    // cosine at the shading normal (the material decides how to treat the cosine). bsdfPdf(wi)
    // returns the density per solid angle with which this vertex's bounce (spawned after this
    // call) samples wi, 0 when it spawns none: light samples of an area light with a visible face
    // are weighted against it (multiple importance sampling, light_faces.cpp).
    template <class F, class P> void directLight(const RayTask& ray, const SurfacePoint& sp, F&& brdfCos, P&& bsdfPdf);

private:
    Color& pixel_;
    std::vector<ShadowTask>& shadows_;
    std::vector<RayTask>& next_;
};

class MaterialModel {
public:
    explicit MaterialModel(const Material& desc);
    virtual ~MaterialModel() = default;
    MaterialModel(const MaterialModel&) = delete;
    MaterialModel& operator=(const MaterialModel&) = delete;

    virtual void shade(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp) const = 0;
    virtual ShadowPass shadowPass(const ShadingContext&, const ShadowTask&, const SurfacePoint&) const { return {}; }
    virtual bool shadowTransparent() const { return false; }

    bool alphaMasked() const { return alpha_.active() || desc_.opacity < 1.0f; }
    bool alphaHashed() const { return desc_.alphaMode == AlphaMode::Hashed; }
    // `hash`: uniform in [0, 1), a function of the ray and the triangle (read by Hashed only).
    bool alphaAt(const Float3& objectPos, const float* uv, float hash) const {
        const float a = desc_.opacity * (alpha_.active() ? alpha_.alpha(objectPos, uv, desc_.alphaChannel) : 1.0f);
        return alphaHashed() ? hash < a : a >= desc_.alphaCutoff;
    }
    bool needsObjectPosition() const { return needsObjectPosition_; }
    // The shading normal after bump mapping (unchanged without a bump).
    // Object mapping: the noise of the object-space position sp.po; Uv mapping: the noise of sp.uv
    // through the triangle's tangent frame (dP/du, dP/dv).
    Float3 bumpedNormal(const InstanceData& inst, const SurfacePoint& sp, const Float3& ns) const;
    // The material's colour (or texture) times the vertex colour at the point.
    Color albedo(const SurfacePoint& sp) const {
        return (texture_.active() ? texture_.color(sp.po, sp.uvOrNull()) : desc_.color) * sp.tint;
    }
    const Material& desc() const { return desc_; }

protected:
    Material desc_;
    Texture texture_, alpha_;
    bool needsObjectPosition_ = false;
};

// Throws InputError (naming the file) when a texture or volume cannot be read.
std::unique_ptr<MaterialModel> makeMaterialModel(const Material& desc);


// -- inline ------------------------------------------------------------------------------------

template <class F, class P>
void ShadeContext::directLight(const RayTask& ray, const SurfacePoint& sp, F&& brdfCos, P&& bsdfPdf) {
    const RenderSettings& settings = ctx.settings;
    // Shadow rays are pruned at a quarter of the path limit (see below): measured on the
    // headlight at the default, a quarter gives 10.5 shadow rays per pixel and 41.3 dB against
    // the unpruned image, the full limit 6.2 and 40.4 dB, no pruning 29.2.
    const float limit = 0.25f * settings.pruneThreshold * ctx.sampleWeight;
    uint32_t dim = 64;  // random dimensions 0..63 are the materials' own
    uint32_t lightIndex = 0;
    for (const Light& light : ctx.scene.desc.lights) {
        const uint32_t branch = lightIndex++;
        Float3 l;
        float dist = INFINITY;
        float lightPdf = 0.0f;  // area lights: density per solid angle of the sampled direction
        Color e = light.color * light.intensity;
        if (light.type == LightType::Point) {
            const Float3 toLight = light.position - sp.p;
            dist = length(toLight);
            if (!(dist > 0.0f)) continue;
            l = toLight * (1.0f / dist);
            e = e * (1.0f / (dist * dist));
        } else if (light.type == LightType::Directional) {
            l = normalize(-light.direction);
        } else {
            // Area light: one uniformly sampled point per shading point and path sample.
            const float u1 = randomFloat(ray.seed, dim++), u2 = randomFloat(ray.seed, dim++);
            const Float3 q = light.position + light.edge1 * u1 + light.edge2 * u2;
            const Float3 c = cross(light.edge1, light.edge2);
            const float area = length(c);
            const Float3 toLight = q - sp.p;
            const float d2 = dot(toLight, toLight);
            dist = std::sqrt(d2);
            if (!(dist > 0.0f) || !(area > 0.0f)) continue;
            l = toLight * (1.0f / dist);
            float cosL = -dot(l, c) / area;
            if (light.twoSided) cosL = std::fabs(cosL);
            if (cosL <= 0.0f) continue;  // the back of a one-sided light is dark
            e = e * (cosL * area / d2);
            lightPdf = d2 / (cosL * area);
        }
        if (dot(sp.ng, l) <= 0.0f) continue;
        const Color f = brdfCos(l);
        if (!(maxComponent(f) > 0.0f)) continue;
        Color contribution = ray.weight * f * e;
        // A light whose whole parallelogram is also a visible emitter is found by this vertex's
        // bounce too: the power heuristic splits each direction between the two strategies
        // (ShadeContext::addEmission gives the bounce the rest).
        if (lightPdf > 0.0f && ctx.scene.lightFaces[branch] == LightFace::Covered) {
            const float pb = bsdfPdf(l);
            if (pb > 0.0f) {
                const float r = pb / lightPdf;
                contribution = contribution * (1.0f / (1.0f + r * r));
            }
        }
        // Pruning by contribution, as for spawned rays, on what the shadow ray can add to the
        // pixel (an upper bound: what passes is at most all of it). Below the limit it plays
        // Russian roulette and carries the limit when it survives: the expectation is exact and
        // the noise of one shadow ray at most the limit, without the radiance factor a pruned
        // path's future carries. Paths at the limit deep in glass light the floor through
        // several layers of it: their shadow rays (and the walks through the glass) were most
        // of the shadow rays. The coin is hashed from the path's roulette seed and the light.
        const float m = maxComponent(contribution);
        if (m < limit) {
            if (!(randomFloat(hashCombine(ray.rouletteSeed, 0x51ED27A3u + branch), kRouletteDim) * limit < m)) continue;
            contribution = contribution * (limit / m);
        }
        if (!settings.shadows) {
            pixel_ += contribution;
            continue;
        }
        ShadowTask st;
        st.org = offsetOrigin(sp.p, sp.ng, 1.0f);
        st.dir = l;
        st.tfar = std::isinf(dist) ? INFINITY : dist * 0.9999f;
        st.contribution = contribution;
        st.pixel = ray.pixel;
        shadows_.push_back(st);
    }
}

}  // namespace rtwall
