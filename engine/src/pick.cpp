// Picking for the display's object selection: one ray, the first instance it hits.
#include "scene_impl.h"

#include <cmath>

namespace rtwall {

std::optional<PickResult> pick(const Scene& scene, const Camera& camera, float px, float py) {
    const Float3 o = camera.origin(), d = camera.direction(px, py);
    if (std::isnan(d.x + d.y + d.z)) return std::nullopt;  // a projector pixel on no screen (issue 30)
    RTCRayHit rh{};
    rh.ray.org_x = o.x;
    rh.ray.org_y = o.y;
    rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x;
    rh.ray.dir_y = d.y;
    rh.ray.dir_z = d.z;
    // Section planes: what they cut away cannot be picked; a cap picks the part it closes, at
    // the cap (so measuring works on the cut).
    float t0 = 0.0f, t1 = INFINITY;
    int enter = -1;
    const SectionState& sections = scene.impl().sections;
    if (!clipToSections(sections, o, d, t0, t1, enter)) return std::nullopt;
    rh.ray.tnear = t0;
    rh.ray.tfar = t1;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    // Both top levels (scene_impl.h, part moves): the static one skipping its stale copies.
    const Scene::Impl& s = scene.impl();
    TopLevels levels(s, true, true);
    levels.each(s, [&](RTCScene level, RTCIntersectContext* c) { withTies(c, rh, [&] { rtcIntersect1(level, c, &rh); }); });
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    PickResult r;
    r.instance = rh.hit.instID[0];
    r.t = rh.ray.tfar;
    if (enter >= 0 && sections.caps[enter]) {
        const InstanceData& inst = scene.impl().instances[r.instance];
        const float ng[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
        const float* m = inst.normalMatrix;
        const float facing = (m[0] * ng[0] + m[1] * ng[1] + m[2] * ng[2]) * d.x +
                             (m[3] * ng[0] + m[4] * ng[1] + m[5] * ng[2]) * d.y +
                             (m[6] * ng[0] + m[7] * ng[1] + m[8] * ng[2]) * d.z;
        if (!(facing < 0.0f)) r.t = t0;  // the inside of a closed part: its cap
    }
    r.point = {o.x + d.x * r.t, o.y + d.y * r.t, o.z + d.z * r.t};
    return r;
}

}  // namespace rtwall
