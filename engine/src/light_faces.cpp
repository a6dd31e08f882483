// The visible faces of area lights.
//
// An area light is a parallelogram that only next-event estimation finds (directLight samples a
// point on it); rays do not see it. To see the lamp, a scene puts an emitting surface where the
// light is (configs/README.md). Without more, a path-traced bounce that hits that surface and the
// light sample taken at the same vertex both count the lamp: twice its light. So an emitter that
// lies on an area light's parallelogram is recognised as that light's visible face:
//
// - Covered (its front faces, or both sides when two-sided, cover the whole parallelogram on
//   every side the light shines to): light samples and bounce hits on the face are weighted by
//   multiple importance sampling (the power heuristic), so each direction counts once, and a
//   glossy surface sees the lamp with the lower-noise strategy.
// - Partial (it covers part of it): light samples count in full, and a bounce hit on the face
//   counts only where no light sample could have found it (the ray does not cross the light).
//
// Camera rays, mirrors, glass and smooth metal see the face in full either way: no light sample
// finds those paths. The recognition is geometric, so a scene file needs no extra key, and it is
// recomputed whenever instances, materials or lights change (identically on every render client).
#include "scene_impl.h"

#include <rtwall/double3.h>
#include <rtwall/vec.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rtwall {

namespace {

Double3 applyPoint(const Transform& t, const Float3& p) {
    const auto& m = t.m;
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

// An area light's parallelogram as a frame: a point's (u, v) along the edges (the unit square
// is the light) and its height h along the unit normal (the side the light shines to).
struct LightFrame {
    Double3 corner, n, du, dv;  // u = dot(p - corner, du), v = dot(p - corner, dv), h = dot(p - corner, n)
    double tolU = 0, tolV = 0, tolH = 0;

    explicit LightFrame(const Light& l) {
        const Double3 e1 = Double3::of(l.edge1), e2 = Double3::of(l.edge2);
        const Double3 c = e1.cross(e2);
        const double area = c.length();
        corner = Double3::of(l.position);
        n = c * (1.0 / area);
        du = e2.cross(n) * (1.0 / area);  // the dual basis of (edge1, edge2) in the plane
        dv = n.cross(e1) * (1.0 / area);
        // How far off the parallelogram an emitter may lie and still be its face: 2% of the
        // longer edge, along the normal and along each edge (the office demo's lamp panel is 0.01
        // behind a 1.2-wide light).
        const double tol = 0.02 * std::max(e1.length(), e2.length());
        tolH = tol;
        tolU = tol / e1.length();
        tolV = tol / e2.length();
    }
    void uvh(const Double3& p, double& u, double& v, double& h) const {
        const Double3 d = p - corner;
        u = d.dot(du);
        v = d.dot(dv);
        h = d.dot(n);
    }
    bool near(const Double3& p) const {
        double u, v, h;
        uvh(p, u, v, h);
        return std::fabs(h) <= tolH && u >= -tolU && u <= 1.0 + tolU && v >= -tolV && v <= 1.0 + tolV;
    }
};

// Whether every point of the instance's mesh lies near the light: its object-space bounding box,
// transformed, does (the region is convex, so the box's corners decide).
bool onLight(const LightFrame& f, const InstanceDesc& in, const Bounds3& b) {
    if (!(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z)) return false;  // an empty mesh
    for (int k = 0; k < 8; ++k) {
        const Float3 p{k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z};
        if (!f.near(applyPoint(in.transform, p))) return false;
    }
    return true;
}

// Area of a triangle in (u, v) clipped to the unit square (Sutherland-Hodgman, then the shoelace).
double clippedArea(const double (&tri)[3][2]) {
    double poly[2][8][2];
    int count = 3;
    for (int i = 0; i < 3; ++i) {
        poly[0][i][0] = tri[i][0];
        poly[0][i][1] = tri[i][1];
    }
    int cur = 0;
    for (int edge = 0; edge < 4 && count > 0; ++edge) {
        const int axis = edge & 1;
        const bool upper = edge >= 2;  // keep x >= 0, y >= 0, then x <= 1, y <= 1
        auto inside = [&](const double* p) { return upper ? p[axis] <= 1.0 : p[axis] >= 0.0; };
        const double bound = upper ? 1.0 : 0.0;
        int out = 0;
        for (int i = 0; i < count; ++i) {
            const double* a = poly[cur][i];
            const double* b = poly[cur][(i + 1) % count];
            const bool ina = inside(a), inb = inside(b);
            if (ina) {
                poly[1 - cur][out][0] = a[0];
                poly[1 - cur][out][1] = a[1];
                ++out;
            }
            if (ina != inb) {
                const double s = (bound - a[axis]) / (b[axis] - a[axis]);
                poly[1 - cur][out][0] = a[0] + s * (b[0] - a[0]);
                poly[1 - cur][out][1] = a[1] + s * (b[1] - a[1]);
                ++out;
            }
        }
        count = out;
        cur = 1 - cur;
    }
    double twice = 0;
    for (int i = 0; i < count; ++i) {
        const double* a = poly[cur][i];
        const double* b = poly[cur][(i + 1) % count];
        twice += a[0] * b[1] - b[0] * a[1];
    }
    return 0.5 * std::fabs(twice);
}

// The fraction of the light's parallelogram that the instance's emitting sides cover, seen from
// the side `side` (+1: the side the light shines to, -1: the other). A side emits where it is
// the triangle's front (the side its winding faces, as shading's SurfacePoint::frontFace says),
// or either side when the material is two-sided. Overlapping triangles are counted twice.
double coverage(const LightFrame& f, const InstanceDesc& in, const InstanceData& data, bool twoSided, int side) {
    const TriangleMesh& mesh = *data.mesh;
    const uint32_t* idx = mesh.indices();
    double sum = 0;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const Float3 a = mesh.position(idx[3 * t]), b = mesh.position(idx[3 * t + 1]), c = mesh.position(idx[3 * t + 2]);
        // The front normal as shading sees it: the object-space winding normal through the
        // normal matrix (so a mirroring transform keeps the side the winding calls outside).
        const Float3 no = cross(b - a, c - a);
        const Double3 nw = Double3::of(Float3{data.normalMatrix[0] * no.x + data.normalMatrix[1] * no.y + data.normalMatrix[2] * no.z,
                                  data.normalMatrix[3] * no.x + data.normalMatrix[4] * no.y + data.normalMatrix[5] * no.z,
                                  data.normalMatrix[6] * no.x + data.normalMatrix[7] * no.y + data.normalMatrix[8] * no.z});
        const double len = nw.length();
        if (!(len > 0.0)) continue;
        const double facing = nw.dot(f.n) * side / len;  // > 0: the front faces this side of the light
        if (!(facing > 0.999 || (twoSided && facing < -0.999))) continue;
        double tri[3][2];
        const Float3* corners[3] = {&a, &b, &c};
        for (int k = 0; k < 3; ++k) {
            double h;
            f.uvh(applyPoint(in.transform, *corners[k]), tri[k][0], tri[k][1], h);
        }
        sum += clippedArea(tri);
    }
    return sum;
}

bool emits(const Material& m) { return m.type != MaterialType::Volume && maxComponent(m.emission) > 0.0f; }

}  // namespace

bool mayBeLightFace(const Scene::Impl& s, const InstanceData& data) {
    if (!emits(s.desc.materials[data.material])) return false;
    for (const Light& light : s.desc.lights)
        if (light.type == LightType::Area) return true;
    return false;
}

void findLightFaces(Scene::Impl& s) {
    const SceneDesc& d = s.desc;
    s.lightFaces.assign(d.lights.size(), LightFace::None);
    s.anyLightFace = false;
    for (InstanceData& data : s.instances) data.areaLight = -1;
    std::vector<double> covered[2];
    covered[0].assign(d.lights.size(), 0.0);
    covered[1].assign(d.lights.size(), 0.0);
    for (size_t i = 0; i < s.instances.size(); ++i) {
        InstanceData& data = s.instances[i];
        const Material& m = d.materials[data.material];
        if (!emits(m) || data.hidden) continue;
        for (size_t li = 0; li < d.lights.size(); ++li) {
            const Light& light = d.lights[li];
            if (light.type != LightType::Area || !(length(cross(light.edge1, light.edge2)) > 0.0f)) continue;
            const LightFrame f(light);
            if (!onLight(f, d.instances[i], data.meshBounds)) continue;
            data.areaLight = int32_t(li);  // the first light it lies on
            covered[0][li] += coverage(f, d.instances[i], data, m.twoSided, +1);
            if (light.twoSided) covered[1][li] += coverage(f, d.instances[i], data, m.twoSided, -1);
            s.lightFaces[li] = LightFace::Partial;
            s.anyLightFace = true;
            break;
        }
    }
    // Covered: the whole parallelogram, on every side the light shines to (to rounding).
    for (size_t li = 0; li < d.lights.size(); ++li)
        if (s.lightFaces[li] == LightFace::Partial && covered[0][li] >= 0.999 &&
            (!d.lights[li].twoSided || covered[1][li] >= 0.999))
            s.lightFaces[li] = LightFace::Covered;
}

LightFace Scene::lightFace(uint32_t light) const {
    if (light >= impl_->lightFaces.size()) throw std::out_of_range("light " + std::to_string(light) + " does not exist");
    return impl_->lightFaces[light];
}

int32_t Scene::areaLightOf(uint32_t instance) const {
    if (instance >= impl_->instances.size())
        throw std::out_of_range("instance " + std::to_string(instance) + " does not exist");
    return impl_->instances[instance].areaLight;
}

}  // namespace rtwall
