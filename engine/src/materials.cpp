// The materials. Each is a MaterialModel (material.h); makeMaterialModel() is the one place
// that maps a MaterialType to its class.
#include "material.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rtwall {

namespace {

constexpr float kInvPi = float(1.0 / std::numbers::pi);
constexpr float kInv2Pi = float(0.5 / std::numbers::pi);

Float3 reflect(const Float3& d, const Float3& n) { return d - n * (2.0f * dot(d, n)); }
Color expColor(const Color& c) { return {std::exp(c.x), std::exp(c.y), std::exp(c.z)}; }

// Random dimensions used by the materials (directLight uses 64 and up).
enum Dim : uint32_t { kLobe = 0, kDir1 = 1, kDir2 = 2, kVolumeJitter = 3 };

// The parts of shade() every material shares: emission and the constant ambient term.
void addEmissionAndAmbient(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp, const Material& m,
                           const Color& albedo) {
    if (maxComponent(m.emission) > 0.0f) c.addEmission(ray, sp, ray.weight * m.emission, m.twoSided);
    if (maxComponent(c.ctx.settings.ambient) > 0.0f) c.add(ray.weight * c.ctx.settings.ambient * albedo);
}

// Sampling densities per solid angle, for weighing light samples against bounces (multiple
// importance sampling): cosine-weighted around n, and a Phong lobe of exponent e around axis r.
float cosinePdf(const Float3& n, const Float3& d) { return std::max(0.0f, dot(n, d)) * kInvPi; }
float phongLobePdf(const Float3& r, float e, const Float3& d) {
    return (e + 1.0f) * kInv2Pi * std::pow(std::max(0.0f, dot(r, d)), e);
}

class LambertModel : public MaterialModel {
public:
    using MaterialModel::MaterialModel;
    void shade(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp) const override {
        const Color a = albedo(sp);
        addEmissionAndAmbient(c, ray, sp, desc_, a);
        const bool bounce = c.ctx.settings.gi && c.canSpawn(ray);
        const bool weigh = bounce && c.weighsLightFaces();
        auto pdf = [&](const Float3& d) { return weigh ? cosinePdf(sp.ns, d) : 0.0f; };
        c.directLight(ray, sp, [&](const Float3& l) { return a * (kInvPi * std::max(0.0f, dot(sp.ns, l))); }, pdf);
        // Path tracing: indirect light by one cosine-sampled bounce (pdf cos/pi cancels the BRDF).
        if (bounce) {
            const Float3 d = keepAbove(sampleCosine(sp.ns, c.random(ray, kDir1), c.random(ray, kDir2)), sp.ng);
            c.spawn(ray, offsetOrigin(sp.p, sp.ng, 1.0f), d, ray.weight * a, 0, pdf(d));
        }
    }
};

// Lambert plus normalised Blinn-Phong. With GI the bounce picks the diffuse lobe (cosine) or the
// specular one (a half vector from the Blinn-Phong lobe cos^n around the normal, the ray
// reflected about it) in proportion to their weights, and weighs the direction with the BRDF
// itself over the mixture's density: light samples and bounces see the same surface, so the two
// find a lamp with the same expectation (multiple importance sampling needs that; until issue
// 15 the specular bounce followed a Phong lobe around the mirror direction, a different BRDF).
class PhongModel : public MaterialModel {
public:
    using MaterialModel::MaterialModel;
    void shade(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp) const override {
        const Color a = albedo(sp);
        addEmissionAndAmbient(c, ray, sp, desc_, a);
        const Float3 wo = -ray.dir;
        const float n = desc_.shininess;
        auto brdfCos = [&](const Float3& l) {
            const float cosN = std::max(0.0f, dot(sp.ns, l));
            const Float3 hv = normalize(l + wo);
            const float spec = std::pow(std::max(0.0f, dot(sp.ns, hv)), n) * (n + 8.0f) * (0.125f * kInvPi);
            return (a * kInvPi + desc_.specular * spec) * cosN;
        };
        const float wd = maxComponent(a), ws = maxComponent(desc_.specular);
        const bool bounce = c.ctx.settings.gi && c.canSpawn(ray) && wd + ws > 0.0f;
        const float pd = bounce ? wd / (wd + ws) : 0.0f;
        auto mixturePdf = [&](const Float3& l) {
            float p = pd * cosinePdf(sp.ns, l);
            const Float3 hv = normalize(l + wo);
            const float oh = dot(wo, hv);
            if (pd < 1.0f && oh > 0.0f) p += (1.0f - pd) * phongLobePdf(sp.ns, n, hv) / (4.0f * oh);
            return p;
        };
        const bool weigh = bounce && c.weighsLightFaces();
        c.directLight(ray, sp, brdfCos, [&](const Float3& l) { return weigh ? mixturePdf(l) : 0.0f; });
        if (!bounce) return;
        Float3 d;
        if (c.random(ray, kLobe) < pd) {
            d = sampleCosine(sp.ns, c.random(ray, kDir1), c.random(ray, kDir2));
        } else {
            const Float3 h = samplePhongLobe(sp.ns, n, c.random(ray, kDir1), c.random(ray, kDir2));
            d = reflect(ray.dir, h);
        }
        // A direction into the surface is lost (light samples skip those too), rather than
        // mirrored: the estimate stays the integral of this BRDF.
        if (!(dot(d, sp.ng) > 0.0f)) return;
        const float p = mixturePdf(d);
        if (!(p > 0.0f)) return;
        c.spawn(ray, offsetOrigin(sp.p, sp.ng, 1.0f), d, ray.weight * brdfCos(d) * (1.0f / p), 0, weigh ? p : 0.0f);
    }
};

class MirrorModel : public MaterialModel {
public:
    using MaterialModel::MaterialModel;
    void shade(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp) const override {
        addEmissionAndAmbient(c, ray, sp, desc_, {0, 0, 0});
        if (c.canSpawn(ray))
            c.spawn(ray, offsetOrigin(sp.p, sp.ng, 1.0f), keepAbove(reflect(ray.dir, sp.ns), sp.ng),
                    ray.weight * albedo(sp), 0);
    }
};

// Metal / reflector: reflectance `color`, a Phong lobe of exponent 2/r^2 - 2 around the mirror
// direction. The lobe is sampled exactly (weight = colour) and evaluated with the same density
// for light sources, so direct and indirect light agree; roughness 0 is a perfect mirror.
class MetalModel : public MaterialModel {
public:
    explicit MetalModel(const Material& d) : MaterialModel(d) {
        const float r = std::clamp(d.roughness, 0.0f, 1.0f);
        exponent_ = r > 0.0f ? std::max(0.0f, 2.0f / (r * r) - 2.0f) : -1.0f;
    }
    void shade(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp) const override {
        const Color a = albedo(sp);
        addEmissionAndAmbient(c, ray, sp, desc_, {0, 0, 0});
        const Float3 r = reflect(ray.dir, sp.ns);
        const Float3 org = offsetOrigin(sp.p, sp.ng, 1.0f);
        if (exponent_ < 0.0f) {
            if (c.canSpawn(ray)) c.spawn(ray, org, keepAbove(r, sp.ng), ray.weight * a, 0);
            return;
        }
        const float n = exponent_;
        // The lobe is sampled with or without GI, so light samples are weighed against it always.
        const bool bounce = c.canSpawn(ray);
        const bool weigh = bounce && c.weighsLightFaces();
        auto pdf = [&](const Float3& d) { return weigh ? phongLobePdf(r, n, d) : 0.0f; };
        c.directLight(
            ray, sp,
            [&](const Float3& l) {
                const float cosA = std::max(0.0f, dot(r, l));
                return a * ((n + 1.0f) * kInv2Pi * std::pow(cosA, n));
            },
            pdf);
        if (bounce) {
            const Float3 d = keepAbove(samplePhongLobe(r, n, c.random(ray, kDir1), c.random(ray, kDir2)), sp.ng);
            c.spawn(ray, org, d, ray.weight * a, 0, pdf(d));
        }
    }

private:
    float exponent_ = -1.0f;  // < 0: perfect mirror
};

// Glass: exact Fresnel, refraction, total internal reflection; Beer-Lambert absorption along
// the path inside (applied where the ray leaves or reflects inside, over the distance from
// where it entered).
class GlassModel : public MaterialModel {
public:
    using MaterialModel::MaterialModel;
    bool shadowTransparent() const override { return true; }

    void shade(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp) const override {
        addEmissionAndAmbient(c, ray, sp, desc_, {0, 0, 0});
        if (!c.canSpawn(ray)) return;
        Color w = ray.weight;
        if (!sp.frontFace && maxComponent(desc_.absorption) > 0.0f) w = w * expColor(desc_.absorption * -sp.t);
        // Entering when we hit the outside of the surface; the normal faces the incoming ray.
        const float eta = sp.frontFace ? 1.0f / desc_.ior : desc_.ior;
        const float cosI = -dot(ray.dir, sp.ns);
        const float fr = fresnelDielectric(cosI, eta);
        Float3 t;
        const bool refracts = fr < 1.0f && refractDirection(ray.dir, sp.ns, eta, t);
        c.spawn(ray, offsetOrigin(sp.p, sp.ng, 1.0f), reflect(ray.dir, sp.ns), w * (refracts ? fr : 1.0f), 0);
        // The refracted ray keeps the density of the bounce it goes on (and how far it came), as
        // a volume's does: that bounce's light sample passed straight through this glass
        // (shadowPass), so a lamp's face it reaches is weighed against that sample by multiple
        // importance sampling, as if the glass were not there, instead of counted a second time
        // (issue 28). A reflection keeps none: no light sample finds the lamp in a reflection.
        if (refracts)
            c.spawn(ray, offsetOrigin(sp.p, sp.ng, -1.0f), t, w * albedo(sp) * (1.0f - fr), 1, ray.bsdfPdf,
                    ray.bsdfPdf > 0.0f ? ray.travelled + sp.t : 0.0f);
    }

    // Approximation (docs/shading.md): shadow rays go straight through, losing the Fresnel
    // reflection at each interface (computed as if entering, so no total internal reflection),
    // the tint, and Beer-Lambert absorption over the distance inside. No refraction of the
    // shadow ray, so no caustics.
    ShadowPass shadowPass(const ShadingContext&, const ShadowTask& ray, const SurfacePoint& sp) const override {
        ShadowPass p;
        const float cosI = std::fabs(dot(ray.dir, sp.ns));
        p.transmittance = albedo(sp) * (1.0f - fresnelDielectric(cosI, 1.0f / desc_.ior));
        if (!sp.frontFace && maxComponent(desc_.absorption) > 0.0f)
            p.transmittance = p.transmittance * expColor(desc_.absorption * -sp.t);
        p.continueAt = sp.t;
        return p;
    }
};

class EmissiveModel : public MaterialModel {
public:
    using MaterialModel::MaterialModel;
    void shade(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp) const override {
        c.addEmission(ray, sp, ray.weight * desc_.emission * albedo(sp), desc_.twoSided);
    }
};

// Volume: the instance's mesh bounding box holds a VTK scalar grid, ray-marched front to back
// with an emission-absorption model: the transfer function gives each value a colour (the
// light it sends towards the eye per unit of optical depth) and an extinction per object unit.
// Rays leave at the far side of the box with what passes; shadow rays are attenuated.
class VolumeModel : public MaterialModel {
public:
    explicit VolumeModel(const Material& d) : MaterialModel(d), grid_(loadVolume(d.volumeFile)) {
        needsObjectPosition_ = true;
        transfer_ = d.transfer;
        std::sort(transfer_.begin(), transfer_.end(), [](auto& a, auto& b) { return a.value < b.value; });
        if (transfer_.empty()) {
            transfer_.push_back({grid_->minValue, {1, 1, 1}, 0.0f});
            transfer_.push_back({grid_->maxValue, {1, 1, 1}, 1.0f});
        }
    }
    bool shadowTransparent() const override { return true; }

    void shade(ShadeContext& c, const RayTask& ray, const SurfacePoint& sp) const override {
        Interval iv;
        if (!interval(*sp.instance, ray.org, ray.dir, 0.0f, INFINITY, iv)) return;
        Color L{0, 0, 0}, T{1, 1, 1};
        march(iv, c.random(ray, kVolumeJitter), &L, T);
        c.add(ray.weight * L);
        if (c.canSpawn(ray)) {
            // The same line goes on: it keeps its sampling density, and how far it has come.
            const Float3 exit = ray.org + ray.dir * iv.t1;
            const float eps = (1.0f + maxAbsComponent(exit)) * (1.0f / 65536.0f);
            c.spawn(ray, exit + ray.dir * eps, ray.dir, ray.weight * T, 0, ray.bsdfPdf, ray.travelled + iv.t1 + eps);
        }
    }

    ShadowPass shadowPass(const ShadingContext&, const ShadowTask& ray, const SurfacePoint& sp) const override {
        ShadowPass p;
        Interval iv;
        if (!interval(*sp.instance, ray.org, ray.dir, 0.0f, ray.tfar, iv)) {
            p.transmittance = {1, 1, 1};
            p.continueAt = sp.t;
            return p;
        }
        Color T{1, 1, 1};
        march(iv, 0.5f, nullptr, T);
        p.transmittance = T;
        p.continueAt = std::max(sp.t, iv.t1);
        return p;
    }

private:
    struct Interval {
        float t0, t1;
        Float3 o, d;  // the ray in the grid's unit cube
    };

    // The ray's parameter interval inside the mesh's object-space box, and the ray in [0,1]^3.
    bool interval(const InstanceData& inst, const Float3& org, const Float3& dir, float tmin, float tmax,
                  Interval& iv) const {
        const float* m = inst.worldToObject;
        Float3 o{m[0] * org.x + m[1] * org.y + m[2] * org.z + m[3], m[4] * org.x + m[5] * org.y + m[6] * org.z + m[7],
                 m[8] * org.x + m[9] * org.y + m[10] * org.z + m[11]};
        Float3 d{m[0] * dir.x + m[1] * dir.y + m[2] * dir.z, m[4] * dir.x + m[5] * dir.y + m[6] * dir.z,
                 m[8] * dir.x + m[9] * dir.y + m[10] * dir.z};
        const Bounds3& b = inst.meshBounds;
        const Float3 ext = b.hi - b.lo;
        if (!(ext.x > 0.0f && ext.y > 0.0f && ext.z > 0.0f)) return false;
        o = {(o.x - b.lo.x) / ext.x, (o.y - b.lo.y) / ext.y, (o.z - b.lo.z) / ext.z};
        d = {d.x / ext.x, d.y / ext.y, d.z / ext.z};
        float t0 = tmin, t1 = tmax;
        const float os[3] = {o.x, o.y, o.z}, ds[3] = {d.x, d.y, d.z};
        for (int a = 0; a < 3; ++a) {
            if (ds[a] == 0.0f) {
                if (os[a] < 0.0f || os[a] > 1.0f) return false;
                continue;
            }
            float ta = (0.0f - os[a]) / ds[a], tb = (1.0f - os[a]) / ds[a];
            if (ta > tb) std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        if (!(t1 > t0)) return false;
        iv = {t0, t1, o, d};
        return true;
    }

    void lookup(float value, Color& color, float& density) const {
        const auto& tf = transfer_;
        if (value <= tf.front().value) {
            color = tf.front().color;
            density = tf.front().density;
            return;
        }
        for (size_t i = 1; i < tf.size(); ++i)
            if (value <= tf[i].value) {
                const float span = tf[i].value - tf[i - 1].value;
                const float f = span > 0.0f ? (value - tf[i - 1].value) / span : 1.0f;
                color = tf[i - 1].color * (1.0f - f) + tf[i].color * f;
                density = tf[i - 1].density * (1.0f - f) + tf[i].density * f;
                return;
            }
        color = tf.back().color;
        density = tf.back().density;
    }

    // Front-to-back compositing over [t0, t1] in steps of volumeStep voxels (in the unit cube:
    // step / (n - 1) along the most finely sampled axis); `jitter` in [0, 1) offsets the first
    // sample against banding. Densities are per unit of the cube's longest edge in object space.
    void march(const Interval& iv, float jitter, Color* L, Color& T) const {
        const float voxel = 1.0f / float(std::max({grid_->nx, grid_->ny, grid_->nz}) - 1);
        const float stepCube = std::max(1e-4f, desc_.volumeStep) * voxel;  // in cube units
        const float dLen = length(iv.d);
        if (!(dLen > 0.0f)) return;
        const float dt = stepCube / dLen;
        const int maxSteps = 1 << 14;
        float t = iv.t0 + dt * jitter;
        for (int i = 0; i < maxSteps && t < iv.t1; ++i, t += dt) {
            const float seg = std::min(dt, iv.t1 - t);
            const Float3 q = iv.o + iv.d * t;
            Color col;
            float sigma;
            lookup(grid_->sample(q.x, q.y, q.z), col, sigma);
            if (!(sigma > 0.0f)) continue;
            const float a = 1.0f - std::exp(-sigma * seg * dLen);
            if (L) *L += T * col * a;
            T = T * (1.0f - a);
            if (maxComponent(T) < 1e-4f) {
                T = {0, 0, 0};
                return;
            }
        }
    }

    std::shared_ptr<const VolumeGrid> grid_;
    std::vector<TransferPoint> transfer_;
};

}  // namespace

MaterialModel::MaterialModel(const Material& desc)
    : desc_(desc), texture_(desc.texture, desc.color), alpha_(desc.alpha, {1, 1, 1}) {
    needsObjectPosition_ = texture_.active() || desc_.bump > 0.0f;
}

Float3 MaterialModel::bumpedNormal(const InstanceData& inst, const SurfacePoint& sp, const Float3& ns) const {
    if (!(desc_.bump > 0.0f)) return ns;
    // Gradient of the height field h = bump * turbulence(p / scale), analytic, in object space;
    // a gradient is a covector, so it goes to world space with the normal matrix.
    const float s = std::max(1e-6f, desc_.bumpScale);
    Float3 gObj;
    if (readsMeshUVs(desc_.bumpMapping, sp.hasUV)) {
        // h = bump * turbulence((u, 0, v) / scale): its (u, v) derivatives, carried onto the
        // surface by the triangle's tangent frame.
        Float3 dPdu, dPdv;
        if (!sp.hasUV || !uvTangents(*inst.mesh, sp.prim, dPdu, dPdv)) return ns;
        Float3 gUV;
        turbulenceGrad(Float3{sp.uv[0], 0.0f, sp.uv[1]} * (1.0f / s), 4, gUV);
        gObj = uvSurfaceGradient(dPdu, dPdv, gUV.x, gUV.z);
    } else {
        turbulenceGrad(sp.po * (1.0f / s), 4, gObj);
    }
    const Float3 g = transformNormal(inst.normalMatrix, gObj * (desc_.bump / s));
    // The height field raises the surface along its outside normal; seen from behind, ns points
    // inside, and the same bump tilts the normal the other way round (n_back = -n_front).
    const Float3 tangential = g - ns * dot(g, ns);
    const Float3 n = normalize(sp.frontFace ? ns - tangential : ns + tangential);
    return isFinite(n) ? n : ns;
}

std::unique_ptr<MaterialModel> makeMaterialModel(const Material& desc) {
    switch (desc.type) {
    case MaterialType::Lambert: return std::make_unique<LambertModel>(desc);
    case MaterialType::Phong: return std::make_unique<PhongModel>(desc);
    case MaterialType::Mirror: return std::make_unique<MirrorModel>(desc);
    case MaterialType::Glass: return std::make_unique<GlassModel>(desc);
    case MaterialType::Metal: return std::make_unique<MetalModel>(desc);
    case MaterialType::Emissive: return std::make_unique<EmissiveModel>(desc);
    case MaterialType::Volume: return std::make_unique<VolumeModel>(desc);
    }
    return std::make_unique<LambertModel>(desc);
}

}  // namespace rtwall
