// Embree tracing for the tile renderer (kernel.cpp, its only includer): rays handed to Embree
// as packets of 4, 8 or 16 or one by one, the closest-hit and shadow queries over ray streams,
// and section planes (ray intervals clipped to the kept region, caps where a cut meets the back
// of a surface). The two kernels differ only here, in how a batch is handed over.
#pragma once

#include "scene_impl.h"
#include "shading.h"

#include <rtwall/vec.h>

#include <cmath>

namespace rtwall {

namespace {

template <int K> struct Packet;
template <> struct Packet<4> {
    using RayHit = RTCRayHit4;
    using Ray = RTCRay4;
    static constexpr int blockW = 2, blockH = 2;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) {
        withTies(c, *r, [&] { rtcIntersect4(v, s, c, r); });
    }
    static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded4(v, s, c, r); }
};
template <> struct Packet<8> {
    using RayHit = RTCRayHit8;
    using Ray = RTCRay8;
    static constexpr int blockW = 4, blockH = 2;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) {
        withTies(c, *r, [&] { rtcIntersect8(v, s, c, r); });
    }
    static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded8(v, s, c, r); }
};

// Embree without AVX-512 kernels has no native 16-wide packets and serves rtcIntersect16 and
// rtcOccluded16 another way, which gave other hits than the same rays one by one or in packets
// of 8 (Section.PacketsOfEveryWidthMatchTheSingleRayKernel: about 5,000 of 18,432 bytes on an
// AMD EPYC with AVX2, with section planes, alpha masks and instances). There a packet of 16 goes
// to Embree as two native packets of 8: the same rays, so the same hits as every other width,
// and packets of 16 stay selectable (and tested) on every CPU.
inline bool nativeRay16(RTCScene scene) {
    static const bool native = [scene] {
        RTCDevice device = rtcGetSceneDevice(scene);  // retains the device
        const bool n = rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
        rtcReleaseDevice(device);
        return n;
    }();
    return native;
}

// Lanes [8 * half, 8 * half + 8) of a 16-wide ray (or its hit) to or from an 8-wide one.
template <class R16, class R8> void copyRayLanes(R16& wide, R8& narrow, int half, bool toNarrow) {
    for (int k = 0; k < 8; ++k) {
        const int w = 8 * half + k;
        auto move = [&](auto& a, auto& b) { toNarrow ? void(b[k] = a[w]) : void(a[w] = b[k]); };
        move(wide.org_x, narrow.org_x), move(wide.org_y, narrow.org_y), move(wide.org_z, narrow.org_z);
        move(wide.dir_x, narrow.dir_x), move(wide.dir_y, narrow.dir_y), move(wide.dir_z, narrow.dir_z);
        move(wide.tnear, narrow.tnear), move(wide.tfar, narrow.tfar), move(wide.time, narrow.time);
        move(wide.mask, narrow.mask), move(wide.id, narrow.id), move(wide.flags, narrow.flags);
    }
}
inline void copyHitLanes(RTCHit16& wide, RTCHit8& narrow, int half, bool toNarrow) {
    for (int k = 0; k < 8; ++k) {
        const int w = 8 * half + k;
        auto move = [&](auto& a, auto& b) { toNarrow ? void(b[k] = a[w]) : void(a[w] = b[k]); };
        move(wide.Ng_x, narrow.Ng_x), move(wide.Ng_y, narrow.Ng_y), move(wide.Ng_z, narrow.Ng_z);
        move(wide.u, narrow.u), move(wide.v, narrow.v), move(wide.primID, narrow.primID);
        move(wide.geomID, narrow.geomID), move(wide.instID[0], narrow.instID[0]);
    }
}

template <> struct Packet<16> {
    using RayHit = RTCRayHit16;
    using Ray = RTCRay16;
    static constexpr int blockW = 4, blockH = 4;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) {
        if (nativeRay16(s)) return withTies(c, *r, [&] { rtcIntersect16(v, s, c, r); });
        for (int half = 0; half < 2; ++half) {
            alignas(32) RTCRayHit8 n;
            copyRayLanes(r->ray, n.ray, half, true);
            copyHitLanes(r->hit, n.hit, half, true);
            withTies(c, n, [&] { rtcIntersect8(v + 8 * half, s, c, &n); });
            copyRayLanes(r->ray, n.ray, half, false);
            copyHitLanes(r->hit, n.hit, half, false);
        }
    }
    static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) {
        if (nativeRay16(s)) return rtcOccluded16(v, s, c, r);
        for (int half = 0; half < 2; ++half) {
            alignas(32) RTCRay8 n;
            copyRayLanes(*r, n, half, true);
            rtcOccluded8(v + 8 * half, s, c, &n);
            copyRayLanes(*r, n, half, false);
        }
    }
};

template <class RayK>
inline void setRay(RayK& r, int k, const Float3& org, const Float3& dir, float tnear, float tfar,
                   uint32_t mask = kMaskAll) {
    r.org_x[k] = org.x;
    r.org_y[k] = org.y;
    r.org_z[k] = org.z;
    r.dir_x[k] = dir.x;
    r.dir_y[k] = dir.y;
    r.dir_z[k] = dir.z;
    r.tnear[k] = tnear;
    r.tfar[k] = tfar;
    r.time[k] = 0.0f;
    r.mask[k] = mask;
    r.id[k] = 0;
    r.flags[k] = 0;
}

// Lane k of an Embree packet's result, as the shading code reads it.
template <class RayHitK> inline Hit hitOf(const RayHitK& rh, int k) {
    Hit h;
    h.inst = rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID ? kNoHit : rh.hit.instID[0][k];
    h.prim = rh.hit.primID[k];
    h.geom = rh.hit.geomID[k];
    h.t = rh.ray.tfar[k];
    h.u = rh.hit.u[k];
    h.v = rh.hit.v[k];
    h.ng = {rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]};
    return h;
}

// Section planes: each ray's interval clipped to the kept region, the same for every kernel
// (they all trace the tasks this wrote). Nothing to do, and nothing done, without planes.
void clipRays(const SectionState& c, RayTask* rays, size_t n) {
    if (c.count == 0) return;
    for (size_t i = 0; i < n; ++i) {
        RayTask& r = rays[i];
        int enter = -1;
        if (!clipToSections(c, r.org, r.dir, r.tnear, r.tfar, enter)) r.tnear = INFINITY;
        r.enter = enter;
    }
}

void clipRays(const SectionState& c, ShadowTask* rays, size_t n) {
    if (c.count == 0) return;
    for (size_t i = 0; i < n; ++i) {
        ShadowTask& r = rays[i];
        int enter = -1;
        if (!clipToSections(c, r.org, r.dir, r.tnear, r.tfar, enter)) r.tnear = INFINITY;
    }
}

// A ray that entered the kept region through a plane and then first met the back of a surface
// was inside a closed part where it crossed the plane: it sees the plane's cap there instead.
inline bool seesCap(const Scene::Impl& s, int enter, uint32_t inst, const Float3& ng, const Float3& dir) {
    if (enter < 0 || !s.sections.caps[enter] || inst == kNoHit) return false;
    return !(dot(transformNormal(s.instances[inst].normalMatrix, ng), dir) < 0.0f);
}

void capHits(const Scene::Impl& s, const RayTask* rays, Hit* hits, size_t n) {
    if (s.sections.count == 0) return;
    for (size_t i = 0; i < n; ++i) {
        const RayTask& r = rays[i];
        Hit& h = hits[i];
        if (!seesCap(s, r.enter, h.inst, h.ng, r.dir)) continue;
        h.t = r.tnear;
        h.u = h.v = 0.0f;
        h.ng = -s.sections.n[r.enter];
        h.inst = kCapHit;
        h.prim = uint32_t(r.enter);
        h.geom = 0;
    }
}


template <int K>
void traceClosestPacket(const Scene::Impl& s, const RayTask* rays, Hit* hits, size_t n, bool coherent, uint32_t mask) {
    using P = Packet<K>;
    TopLevels levels(s, coherent, true);
    alignas(64) typename P::RayHit rh;
    alignas(64) int valid[K];
    for (size_t base = 0; base < n; base += K) {
        const int count = int(std::min<size_t>(K, n - base));
        for (int k = 0; k < K; ++k) {
            const RayTask& t = rays[base + (k < count ? k : 0)];
            valid[k] = k < count && t.tnear <= t.tfar ? -1 : 0;  // an empty interval misses
            setRay(rh.ray, k, t.org, t.dir, t.tnear, t.tfar, mask);
            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        levels.each(s, [&](RTCScene scene, RTCIntersectContext* ctx) { P::intersect(valid, scene, ctx, &rh); });
        for (int k = 0; k < count; ++k) hits[base + k] = hitOf(rh, k);
    }
}

void traceClosestSingle(const Scene::Impl& s, const RayTask* rays, Hit* hits, size_t n, bool coherent, uint32_t mask) {
    TopLevels levels(s, coherent, true);
    alignas(16) RTCRayHit rh;
    for (size_t i = 0; i < n; ++i) {
        const RayTask& t = rays[i];
        if (!(t.tnear <= t.tfar)) {  // an empty interval misses, as in the packet kernel
            hits[i] = Hit{t.tfar, 0.0f, 0.0f, {0, 0, 0}, kNoHit, RTC_INVALID_GEOMETRY_ID, RTC_INVALID_GEOMETRY_ID};
            continue;
        }
        rh.ray.org_x = t.org.x;
        rh.ray.org_y = t.org.y;
        rh.ray.org_z = t.org.z;
        rh.ray.dir_x = t.dir.x;
        rh.ray.dir_y = t.dir.y;
        rh.ray.dir_z = t.dir.z;
        rh.ray.tnear = t.tnear;
        rh.ray.tfar = t.tfar;
        rh.ray.time = 0.0f;
        rh.ray.mask = mask;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        levels.each(s, [&](RTCScene scene, RTCIntersectContext* ctx) { withTies(ctx, rh, [&] { rtcIntersect1(scene, ctx, &rh); }); });
        Hit& h = hits[i];
        h.inst = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? kNoHit : rh.hit.instID[0];
        h.prim = rh.hit.primID;
        h.geom = rh.hit.geomID;
        h.t = rh.ray.tfar;
        h.u = rh.hit.u;
        h.v = rh.hit.v;
        h.ng = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    }
}

template <int K>
void traceShadowPacket(const Scene::Impl& s, const ShadowTask* rays, uint8_t* occluded, size_t n, uint32_t mask, bool coherent) {
    using P = Packet<K>;
    TopLevels levels(s, coherent, false);
    alignas(64) typename P::Ray r;
    alignas(64) int valid[K];
    for (size_t base = 0; base < n; base += K) {
        const int count = int(std::min<size_t>(K, n - base));
        for (int k = 0; k < K; ++k) {
            const ShadowTask& t = rays[base + (k < count ? k : 0)];
            valid[k] = k < count && t.tnear <= t.tfar ? -1 : 0;  // an empty interval is not occluded
            setRay(r, k, t.org, t.dir, t.tnear, t.tfar, mask);
        }
        // A ray the static level occludes has tfar = -inf: the moving level skips it.
        levels.each(s, [&](RTCScene scene, RTCIntersectContext* ctx) { P::occluded(valid, scene, ctx, &r); });
        for (int k = 0; k < count; ++k) occluded[base + k] = r.tfar[k] == -INFINITY;
    }
}

void traceShadowSingle(const Scene::Impl& s, const ShadowTask* rays, uint8_t* occluded, size_t n, uint32_t mask, bool) {
    TopLevels levels(s, true, false);
    alignas(16) RTCRay r;
    for (size_t i = 0; i < n; ++i) {
        const ShadowTask& t = rays[i];
        if (!(t.tnear <= t.tfar)) {
            occluded[i] = 0;
            continue;
        }
        r.org_x = t.org.x;
        r.org_y = t.org.y;
        r.org_z = t.org.z;
        r.dir_x = t.dir.x;
        r.dir_y = t.dir.y;
        r.dir_z = t.dir.z;
        r.tnear = t.tnear;
        r.tfar = t.tfar;
        r.time = 0.0f;
        r.mask = mask;
        r.id = 0;
        r.flags = 0;
        levels.each(s, [&](RTCScene scene, RTCIntersectContext* ctx) { rtcOccluded1(scene, ctx, &r); });
        occluded[i] = r.tfar == -INFINITY;
    }
}

struct Tracer {
    void (*closest)(const Scene::Impl&, const RayTask*, Hit*, size_t, bool, uint32_t);
    void (*shadow)(const Scene::Impl&, const ShadowTask*, uint8_t*, size_t, uint32_t, bool coherent);
};

template <int K> Tracer packetTracer() {
    return {traceClosestPacket<K>, traceShadowPacket<K>};
}

// A packet traced lane by lane (rtcIntersect1), the results written back into the packet: the
// single-ray kernel's primary pass.
template <int K>
inline void intersectLanes(const int* traceValid, RTCScene scene, RTCIntersectContext* context, typename Packet<K>::RayHit& rh) {
    RTCIntersectContext& ctx = *context;
    for (int k = 0; k < K; ++k) {
        if (!traceValid[k]) continue;
        RTCRayHit one;
        one.ray = {rh.ray.org_x[k], rh.ray.org_y[k], rh.ray.org_z[k], rh.ray.tnear[k],
                   rh.ray.dir_x[k], rh.ray.dir_y[k], rh.ray.dir_z[k], 0.0f, rh.ray.tfar[k],
                   kMaskAll, 0, 0};
        // The lane's hit from the level before, whole: the tie rule starts from it, and a miss
        // in this level keeps it.
        one.hit.Ng_x = rh.hit.Ng_x[k];
        one.hit.Ng_y = rh.hit.Ng_y[k];
        one.hit.Ng_z = rh.hit.Ng_z[k];
        one.hit.u = rh.hit.u[k];
        one.hit.v = rh.hit.v[k];
        one.hit.primID = rh.hit.primID[k];
        one.hit.geomID = rh.hit.geomID[k];
        one.hit.instID[0] = rh.hit.instID[0][k];
        withTies(&ctx, one, [&] { rtcIntersect1(scene, &ctx, &one); });
        if (one.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        rh.ray.tfar[k] = one.ray.tfar;
        rh.hit.Ng_x[k] = one.hit.Ng_x;
        rh.hit.Ng_y[k] = one.hit.Ng_y;
        rh.hit.Ng_z[k] = one.hit.Ng_z;
        rh.hit.u[k] = one.hit.u;
        rh.hit.v[k] = one.hit.v;
        rh.hit.primID[k] = one.hit.primID;
        rh.hit.geomID[k] = one.hit.geomID;
        rh.hit.instID[0][k] = one.hit.instID[0];
    }
}

// The lanes of a clipped primary packet (`traced`, entering through plane `enter`) that see a
// cap: their hit becomes the cap's.
template <int K>
inline void capPacket(const Scene::Impl& s, const int* traced, const int* enter, typename Packet<K>::RayHit& rh) {
    const SectionState& sections = s.sections;
    for (int k = 0; k < K; ++k) {
        if (!traced[k] || rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
        const Float3 ng{rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]};
        const Float3 d{rh.ray.dir_x[k], rh.ray.dir_y[k], rh.ray.dir_z[k]};
        if (!seesCap(s, enter[k], rh.hit.instID[0][k], ng, d)) continue;
        const Float3 n = -sections.n[enter[k]];
        rh.ray.tfar[k] = rh.ray.tnear[k];
        rh.hit.Ng_x[k] = n.x;
        rh.hit.Ng_y[k] = n.y;
        rh.hit.Ng_z[k] = n.z;
        rh.hit.instID[0][k] = kCapHit;
        rh.hit.primID[k] = uint32_t(enter[k]);
        rh.hit.geomID[k] = 0;
    }
}

}  // namespace

}  // namespace rtwall
