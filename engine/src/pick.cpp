// Picking for the display's object selection: one ray, the first instance it hits.
#include "scene_impl.h"

namespace rtwall {

std::optional<PickResult> pick(const Scene& scene, const Camera& camera, float px, float py) {
    const Float3 o = camera.origin(), d = camera.direction(px, py);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = o.x;
    rh.ray.org_y = o.y;
    rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x;
    rh.ray.dir_y = d.y;
    rh.ray.dir_z = d.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene.impl().top, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    PickResult r;
    r.instance = rh.hit.instID[0];
    r.t = rh.ray.tfar;
    r.point = {o.x + d.x * r.t, o.y + d.y * r.t, o.z + d.z * r.t};
    return r;
}

}  // namespace rtwall
