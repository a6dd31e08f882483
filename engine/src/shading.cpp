#include "shading.h"

#include "material.h"

#include <rtwall/vec.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace rtwall {

namespace {

// `bump`: the shading normal bumped where the material says (false: as interpolated, for the
// denoiser's features, whose normal stop must see geometry, not a plaster's bumps).
SurfacePoint surfaceAt(const InstanceData& inst, const MaterialModel& model, const Float3& org, const Float3& dir,
                       const Hit& hit, bool bump = true) {
    SurfacePoint sp;
    sp.p = org + dir * hit.t;
    sp.t = hit.t;
    sp.instance = &inst;
    // Embree's geometric normal saves fetching the triangle's vertices; only meshes with
    // vertex normals (and materials that need the object-space position) read the mesh.
    Float3 ng = normalize(transformNormal(inst.normalMatrix, hit.ng));
    Float3 ns = ng;
    const TriangleMesh& mesh = *inst.mesh;
    const TriangleHit th = triangleHit(*inst.prims, hit.geom, hit.prim, hit.u, hit.v);
    if (mesh.hasNormals()) {
        const uint32_t* tri = mesh.indices() + 3 * size_t(th.prim);
        const float w = 1.0f - th.u - th.v;
        const Float3 n = mesh.normal(tri[0]) * w + mesh.normal(tri[1]) * th.u + mesh.normal(tri[2]) * th.v;
        ns = normalize(transformNormal(inst.normalMatrix, n));
        if (!isFinite(ns) || dot(ns, ns) == 0.0f) ns = ng;
    }
    sp.po = model.needsObjectPosition() ? objectPosition(mesh, th.prim, th.u, th.v) : Float3{};
    if (mesh.hasColors()) sp.tint = vertexColorAt(mesh, th.prim, th.u, th.v);
    sp.prim = th.prim;
    if (mesh.hasUVs()) {
        sp.hasUV = true;
        meshUVAt(mesh, th.prim, th.u, th.v, sp.uv);
    }
    sp.frontFace = dot(ng, dir) < 0.0f;
    if (!sp.frontFace) ng = -ng;
    if (dot(ns, ng) < 0.0f) ns = -ns;
    if (bump) ns = model.bumpedNormal(inst, sp, ns);
    if (dot(ns, ng) < 0.0f) ns = ng;
    sp.ng = ng;
    sp.ns = ns;
    return sp;
}

}  // namespace

Float3 offsetOrigin(const Float3& p, const Float3& ng, float side) {
    const float eps = (1.0f + maxAbsComponent(p)) * (1.0f / 65536.0f);
    return p + ng * (side * eps);
}

float fresnelDielectric(float cosI, float eta) {
    cosI = std::clamp(cosI, 0.0f, 1.0f);
    const float sin2T = eta * eta * (1.0f - cosI * cosI);
    if (sin2T >= 1.0f) return 1.0f;
    const float cosT = std::sqrt(1.0f - sin2T);
    const float rs = (eta * cosI - cosT) / (eta * cosI + cosT);
    const float rp = (cosI - eta * cosT) / (cosI + eta * cosT);
    return 0.5f * (rs * rs + rp * rp);
}

bool refractDirection(const Float3& d, const Float3& n, float eta, Float3& out) {
    const float cosI = -dot(d, n);
    const float sin2T = eta * eta * (1.0f - cosI * cosI);
    if (sin2T >= 1.0f) return false;
    const float cosT = std::sqrt(1.0f - sin2T);
    out = normalize(d * eta + n * (eta * cosI - cosT));
    return true;
}

void shadeHit(const ShadingContext& ctx, const RayTask& ray, const Hit& hit, Color& pixel,
              std::vector<ShadowTask>& shadows, std::vector<RayTask>& next) {
    if (hit.inst == kNoHit) {
        pixel += ray.weight * ctx.settings.background;
        return;
    }
    ShadeContext c(ctx, pixel, shadows, next);
    if (hit.inst == kCapHit) {
        // A section plane's cap: a flat opaque surface facing the cut-away side (the ray came
        // from there), lit and shadowed like any other.
        SurfacePoint sp;
        sp.p = ray.org + ray.dir * hit.t;
        sp.t = hit.t;
        sp.ng = sp.ns = hit.ng;
        sp.instance = &ctx.scene.capInstance;
        ctx.scene.capModels[hit.prim]->shade(c, ray, sp);
        return;
    }
    const InstanceData& inst = ctx.scene.instances[hit.inst];
    const MaterialModel& model = *ctx.scene.models[inst.material];
    SurfacePoint sp = surfaceAt(inst, model, ray.org, ray.dir, hit);
    if (inst.highlighted) {  // seen directly or in a reflection alike
        sp.tint = sp.tint * kHighlightTint;
        pixel += ray.weight * kHighlightGlow;
    }
    model.shade(c, ray, sp);
}

HitFeatures featuresAt(const ShadingContext& ctx, const Float3& org, const Float3& dir, const Hit& hit) {
    HitFeatures f;
    if (hit.inst == kNoHit) return f;
    if (hit.inst == kCapHit) {
        f.albedo = ctx.scene.sections.capColor[hit.prim];
        const Float3 n = normalize(hit.ng);
        f.normal = dot(n, dir) > 0.0f ? -n : n;
        f.id = kCapFeatureId - hit.prim;
        return f;
    }
    const InstanceData& inst = ctx.scene.instances[hit.inst];
    const MaterialModel& model = *ctx.scene.models[inst.material];
    SurfacePoint sp = surfaceAt(inst, model, org, dir, hit, false);
    if (inst.highlighted) sp.tint = sp.tint * kHighlightTint;
    f.albedo = model.albedo(sp);
    f.normal = sp.ns;
    f.id = hit.inst + 1;
    return f;
}

ShadowPass shadowPassAt(const ShadingContext& ctx, const ShadowTask& ray, const Hit& hit) {
    const InstanceData& inst = ctx.scene.instances[hit.inst];
    const MaterialModel& model = *ctx.scene.models[inst.material];
    const SurfacePoint sp = surfaceAt(inst, model, ray.org, ray.dir, hit);
    return model.shadowPass(ctx, ray, sp);
}

float areaLightPdf(const Light& light, const Float3& org, const Float3& dir, float tBlock, float travelled) {
    if (light.type != LightType::Area) return 0.0f;
    const Float3 c = cross(light.edge1, light.edge2);
    const float area = length(c);
    const float facing = dot(dir, c);
    if (!(area > 0.0f) || facing == 0.0f) return 0.0f;
    const float t = dot(light.position - org, c) / facing;
    if (!(t > 0.0f)) return 0.0f;
    // directLight's shadow ray stops at 0.9999 of the light's distance: whatever lies beyond
    // (the emitter of a visible face just behind the light) does not block it.
    const float dist = travelled + t;
    if (travelled + tBlock < 0.9999f * dist) return 0.0f;
    // (u, v) of the crossing in the parallelogram, by the dual basis of (edge1, edge2).
    const Float3 n = c * (1.0f / area);
    const Float3 q = org + dir * t - light.position;
    const float u = dot(q, cross(light.edge2, n)) / area, v = dot(q, cross(n, light.edge1)) / area;
    if (!(u >= 0.0f && u <= 1.0f && v >= 0.0f && v <= 1.0f)) return 0.0f;
    float cosL = -facing / area;
    if (light.twoSided) cosL = std::fabs(cosL);
    if (!(cosL > 0.0f)) return 0.0f;  // the dark side of a one-sided light
    return dist * dist / (cosL * area);
}

float lightFaceWeight(const ShadingContext& ctx, const RayTask& ray, const SurfacePoint& sp) {
    const uint32_t index = uint32_t(sp.instance->areaLight);
    const float pl = areaLightPdf(ctx.scene.desc.lights[index], ray.org, ray.dir, sp.t, ray.travelled);
    if (!(pl > 0.0f)) return 1.0f;  // no light sample finds this path: the bounce is all there is
    if (ctx.scene.lightFaces[index] != LightFace::Covered) return 0.0f;  // the light sample counted it
    const float r = pl / ray.bsdfPdf;
    return 1.0f / (1.0f + r * r);
}

namespace {
double srgbToLinearD(double s) { return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4); }
}  // namespace

SrgbTables::SrgbTables() {
    thresholds[0] = -INFINITY;
    for (int c = 1; c < 256; ++c) thresholds[c] = float(srgbToLinearD((c - 0.5) / 255.0));
    thresholds[256] = INFINITY;
    for (int c = 0; c < 256; ++c) toLinear[c] = float(srgbToLinearD(c / 255.0));
    int c = 0;
    for (int b = 0; b < kBuckets; ++b) {
        const float lo = float(b) / kBuckets;
        while (c < 255 && thresholds[c + 1] <= lo) ++c;
        bucketStart[b] = uint8_t(c);
    }
}

const SrgbTables kSrgb;

}  // namespace rtwall
