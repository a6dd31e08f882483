#include "shading.h"

#include "vec.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace rtwall {

namespace {

constexpr float kInvPi = float(1.0 / std::numbers::pi);

Float3 reflect(const Float3& d, const Float3& n) { return d - n * (2.0f * dot(d, n)); }

// Scale-aware offset for secondary-ray origins: a fixed epsilon is too small far from the
// origin and too large for small models. 2^-16 relative to the coordinate magnitude is about
// 128 float ulps, well above intersection error and well below any modelled feature.
Float3 offsetOrigin(const Float3& p, const Float3& ng, float side) {
    const float eps = (1.0f + maxAbsComponent(p)) * (1.0f / 65536.0f);
    return p + ng * (side * eps);
}

struct SurfacePoint {
    Float3 p;   // world position
    Float3 ng;  // unit geometric normal, facing the incoming ray
    Float3 ns;  // unit shading normal, same hemisphere as ng
    bool frontFace;  // the ray hit the side the triangle's winding calls "outside"
};

SurfacePoint surfaceAt(const InstanceData& inst, const RayTask& ray, const Hit& hit) {
    SurfacePoint sp;
    sp.p = ray.org + ray.dir * hit.t;
    // Embree's geometric normal saves fetching the triangle's vertices; only meshes with
    // vertex normals need the index and normal buffers.
    Float3 ng = normalize(transformNormal(inst.normalMatrix, hit.ng));
    Float3 ns = ng;
    const TriangleMesh& mesh = *inst.mesh;
    if (mesh.hasNormals()) {
        const uint32_t* tri = mesh.indices() + 3 * size_t(hit.prim);
        const float w = 1.0f - hit.u - hit.v;
        const Float3 n = mesh.normal(tri[0]) * w + mesh.normal(tri[1]) * hit.u + mesh.normal(tri[2]) * hit.v;
        ns = normalize(transformNormal(inst.normalMatrix, n));
        if (!isFinite(ns) || dot(ns, ns) == 0.0f) ns = ng;
    }
    sp.frontFace = dot(ng, ray.dir) < 0.0f;
    if (!sp.frontFace) ng = -ng;
    if (dot(ns, ng) < 0.0f) ns = -ns;
    sp.ng = ng;
    sp.ns = ns;
    return sp;
}

void directLight(const ShadingContext& ctx, const RayTask& ray, const SurfacePoint& sp, const Material& m,
                 Color& pixel, std::vector<ShadowTask>& shadows) {
    const RenderSettings& settings = ctx.settings;
    pixel += ray.weight * settings.ambient * m.color;
    const Float3 wo = -ray.dir;
    for (const Light& light : ctx.scene.desc.lights) {
        Float3 l;
        float dist = INFINITY;
        Color e = light.color * light.intensity;
        if (light.type == LightType::Point) {
            const Float3 toLight = light.position - sp.p;
            dist = length(toLight);
            if (!(dist > 0.0f)) continue;
            l = toLight * (1.0f / dist);
            e = e * (1.0f / (dist * dist));
        } else {
            l = normalize(-light.direction);
        }
        const float cosN = dot(sp.ns, l);
        if (cosN <= 0.0f || dot(sp.ng, l) <= 0.0f) continue;

        Color f = m.color * kInvPi;
        if (m.type == MaterialType::Phong) {
            // Normalised Blinn-Phong, so the highlight keeps its energy as shininess changes.
            const Float3 hv = normalize(l + wo);
            const float spec = std::pow(std::max(0.0f, dot(sp.ns, hv)), m.shininess) * (m.shininess + 8.0f) *
                               (0.125f * kInvPi);
            f += m.specular * spec;
        }
        const Color contribution = ray.weight * f * e * cosN;
        if (!settings.shadows) {
            pixel += contribution;
            continue;
        }
        ShadowTask st;
        st.org = offsetOrigin(sp.p, sp.ng, 1.0f);
        st.dir = l;
        st.tfar = std::isinf(dist) ? INFINITY : dist * 0.9999f;
        st.contribution = contribution;
        st.pixel = ray.pixel;
        shadows.push_back(st);
    }
}

void spawn(std::vector<RayTask>& next, const RayTask& parent, const Float3& org, const Float3& dir, const Color& w) {
    if (maxComponent(w) <= 0.0f) return;
    RayTask r;
    r.org = org;
    r.dir = dir;
    r.tfar = INFINITY;
    r.weight = w;
    r.pixel = parent.pixel;
    r.depth = parent.depth + 1;
    next.push_back(r);
}

}  // namespace

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
    const RenderSettings& settings = ctx.settings;
    if (hit.inst == kNoHit) {
        pixel += ray.weight * settings.background;
        return;
    }
    const InstanceData& inst = ctx.scene.instances[hit.inst];
    const Material& m = *inst.material;

    const SurfacePoint sp = surfaceAt(inst, ray, hit);

    const bool canSpawn = ray.depth < settings.maxDepth;
    switch (m.type) {
    case MaterialType::Lambert:
    case MaterialType::Phong:
        directLight(ctx, ray, sp, m, pixel, shadows);
        break;
    case MaterialType::Mirror:
        if (canSpawn) spawn(next, ray, offsetOrigin(sp.p, sp.ng, 1.0f), reflect(ray.dir, sp.ns), ray.weight * m.color);
        break;
    case MaterialType::Glass: {
        if (!canSpawn) break;
        // Entering when we hit the outside of the surface; the normal faces the incoming ray.
        const float eta = sp.frontFace ? 1.0f / m.ior : m.ior;
        const float cosI = -dot(ray.dir, sp.ns);
        const float fr = fresnelDielectric(cosI, eta);
        Float3 t;
        const bool refracts = fr < 1.0f && refractDirection(ray.dir, sp.ns, eta, t);
        spawn(next, ray, offsetOrigin(sp.p, sp.ng, 1.0f), reflect(ray.dir, sp.ns),
              ray.weight * (refracts ? fr : 1.0f));
        if (refracts) spawn(next, ray, offsetOrigin(sp.p, sp.ng, -1.0f), t, ray.weight * m.color * (1.0f - fr));
        break;
    }
    }
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
