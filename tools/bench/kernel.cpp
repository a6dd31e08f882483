// rtwall bench kernel: primary-ray throughput of the packet and single-ray kernels against a
// bare rtcIntersectK loop (K = the packet kernel's width) over the very same Embree scene. Rounds are interleaved (bare,
// packet, single, bare, ...) so that machine noise hits all three alike; medians are reported.
#include "bench.h"
#include "bench_util.h"
#include "tile_failure.h"

#include <rtwall/engine.h>
#include <rtwall/engine_embree.h>

#include <toml++/toml.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <iostream>
#include <memory>
#include <thread>

namespace rtwall::bench {

namespace {

template <int K> struct BarePacket;
template <> struct BarePacket<4> {
    using RayHit = RTCRayHit4;
    static constexpr int w = 2;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect4(v, s, c, r); }
};
template <> struct BarePacket<8> {
    using RayHit = RTCRayHit8;
    static constexpr int w = 4;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect8(v, s, c, r); }
};
template <> struct BarePacket<16> {
    using RayHit = RTCRayHit16;
    static constexpr int w = 4;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHit* r) { rtcIntersect16(v, s, c, r); }
};

// The reference: tiles handed out exactly as renderFrame does, pixel blocks of the packet
// kernel's shape and width, one rtcIntersectK per block, and nothing else but storing the
// primitive ID.
template <int K>
void bareFrame(RTCScene scene, const Camera& camera, int width, int height, int tileSize, int threads,
               std::vector<uint32_t>& ids) {
    using P = BarePacket<K>;
    constexpr int bw = P::w, bh = K / P::w;
    const std::vector<TileRect> tiles = makeTiles(width, height, tileSize);
    std::atomic<size_t> next{0};
    auto worker = [&] {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        alignas(64) typename P::RayHit rh;
        alignas(64) int valid[K];
        const Float3 org = camera.origin();
        for (size_t t; (t = next.fetch_add(1)) < tiles.size();) {
            const TileRect& r = tiles[t];
            for (int by = r.y0; by < r.y1; by += bh)
                for (int bx = r.x0; bx < r.x1; bx += bw) {
                    for (int k = 0; k < K; ++k) {
                        const int x = bx + k % bw, y = by + k / bw;
                        valid[k] = (x < r.x1 && y < r.y1) ? -1 : 0;
                        const Float3 d = camera.direction(float(x) + 0.5f, float(y) + 0.5f);
                        rh.ray.org_x[k] = org.x;
                        rh.ray.org_y[k] = org.y;
                        rh.ray.org_z[k] = org.z;
                        rh.ray.dir_x[k] = d.x;
                        rh.ray.dir_y[k] = d.y;
                        rh.ray.dir_z[k] = d.z;
                        rh.ray.tnear[k] = 0.0f;
                        rh.ray.tfar[k] = INFINITY;
                        rh.ray.time[k] = 0.0f;
                        rh.ray.mask[k] = 0xFFFFFFFFu;
                        rh.ray.id[k] = 0;
                        rh.ray.flags[k] = 0;
                        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                        rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
                    }
                    P::intersect(valid, scene, &ctx, &rh);
                    for (int k = 0; k < K; ++k)
                        if (valid[k]) ids[size_t(by + k / bw) * width + bx + k % bw] = rh.hit.primID[k];
                }
        }
    };
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
}

void bareFrameFor(int packetWidth, RTCScene scene, const Camera& camera, int width, int height, int tileSize, int threads,
                  std::vector<uint32_t>& ids) {
    if (packetWidth == 16) bareFrame<16>(scene, camera, width, height, tileSize, threads, ids);
    else if (packetWidth == 8) bareFrame<8>(scene, camera, width, height, tileSize, threads, ids);
    else bareFrame<4>(scene, camera, width, height, tileSize, threads, ids);
}

}  // namespace

toml::table kernel(const KernelOptions& o) {
    SceneDesc desc = builtinScene("knots", o.triangles);
    if (o.sections > 0) {
        const Bounds3 b = desc.worldBounds();
        const Float3 centre{0.5f * (b.lo.x + b.hi.x), 0.5f * (b.lo.y + b.hi.y), 0.5f * (b.lo.z + b.hi.z)};
        const Float3 normals[kMaxSections] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
        for (int i = 0; i < std::min(o.sections, kMaxSections); ++i) {
            SectionPlane& p = desc.sections[size_t(i)];
            p.enabled = true;
            p.normal = normals[i];
            // Outside the bounds on the side the normal points away from: it keeps everything.
            const Float3 n = normals[i];
            p.point = {n.x > 0 ? b.lo.x - 1 : n.x < 0 ? b.hi.x + 1 : centre.x, n.y > 0 ? b.lo.y - 1 : n.y < 0 ? b.hi.y + 1 : centre.y,
                       n.z > 0 ? b.lo.z - 1 : n.z < 0 ? b.hi.z + 1 : centre.z};
            if (i == 0 && o.cut) p.point = centre;
        }
    }
    int64_t tris = 0;
    for (const MeshDesc& m : desc.meshes) tris += int64_t(m.mesh->triangleCount());
    Scene scene(desc);
    const int threads = o.threads > 0 ? o.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    const Camera camera(desc.cameras.front(), o.width, o.height);
    const int lanes = o.packetWidth > 0 ? o.packetWidth : packetWidth();

    TraceOptions trace;
    trace.packetWidth = lanes;
    RenderSettings s = desc.settings;
    s.width = o.width;
    s.height = o.height;
    s.tileSize = o.tile;
    s.threads = threads;
    s.shading = ShadingMode::EyeLight;  // primary rays only, as in the bare loop
    RenderSettings single = s;
    single.kernel = KernelType::Single;
    RenderSettings full = s;  // for scale: the whole frame with Phong shading and shadows
    full.shading = ShadingMode::Full;

    std::vector<uint32_t> ids(size_t(o.width) * o.height);
    std::vector<double> bare, packet, one, shaded;
    TileStats fullStats;
    // A tile that fails is reported with the command that renders it again.
    auto frame = [&](const RenderSettings& settings, TileStats* stats = nullptr) {
        try {
            renderFrame(scene, camera, settings, 0, stats, trace);
        } catch (const TileError& e) {
            throw withReplay(e, {"builtin:knots", o.triangles, desc.origin, desc.cameras.front(), settings, trace, 0, {}});
        }
    };
    // Warm-up: page in the BVH and the scratch buffers.
    bareFrameFor(lanes, embreeScene(scene), camera, o.width, o.height, o.tile, threads, ids);
    frame(s);
    frame(single);
    for (int r = 0; r < o.rounds; ++r) {
        bare.push_back(secondsOf([&] { bareFrameFor(lanes, embreeScene(scene), camera, o.width, o.height, o.tile, threads, ids); }));
        packet.push_back(secondsOf([&] { frame(s); }));
        one.push_back(secondsOf([&] { frame(single); }));
        shaded.push_back(secondsOf([&] { frame(full, &fullStats); }));
    }
    const double rays = double(o.width) * o.height;
    const double mBare = rays / median(bare) * 1e-6, mPacket = rays / median(packet) * 1e-6,
                 mSingle = rays / median(one) * 1e-6;
    auto arr = [](const std::vector<double>& v) {
        toml::array a;
        for (double x : v) a.push_back(x);
        return a;
    };
    toml::table out{{"benchmark", "kernel"},
                    {"width", o.width},
                    {"height", o.height},
                    {"threads", threads},
                    {"packet_width", lanes},
                    {"cpu_packet_width", packetWidth()},
                    {"coherent_occlusion", coherentOcclusion(scene)},
                    {"triangles", tris},
                    {"sections", o.sections},
                    {"sections_cut", o.cut},
                    {"rounds", o.rounds},
                    {"bare_mrays_per_s", mBare},
                    {"packet_mrays_per_s", mPacket},
                    {"single_mrays_per_s", mSingle},
                    {"packet_over_bare", mPacket / mBare},
                    {"packet_over_single", mPacket / mSingle},
                    {"full_shading_frame_s", median(shaded)},
                    {"full_shading_mrays_per_s", double(fullStats.rays + fullStats.shadowRays) / median(shaded) * 1e-6},
                    {"frame_seconds", toml::table{{"bare", arr(bare)}, {"packet", arr(packet)}, {"single", arr(one)}, {"full_shading", arr(shaded)}}}};
    if (o.text)
        std::fprintf(o.text, "%dx%d, %lld triangles, %d threads, %d section planes%s, packets of %d (%s occlusion): bare %.2f, "
                    "packet %.2f, single %.2f Mrays/s (packet/bare %.3f, packet/single %.3f); full shading %.3f s/frame\n",
                    o.width, o.height, (long long)tris, threads, o.sections, o.cut ? " (one cutting)" : "", lanes,
                    coherentOcclusion(scene) ? "coherent" : "incoherent", mBare, mPacket, mSingle,
                    mPacket / mBare, mPacket / mSingle, median(shaded));
    return out;
}

}  // namespace rtwall::bench
