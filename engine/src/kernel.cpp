// The tile renderer.
//
// A tile is rendered as a stream of ray generations: all primary rays of the tile (ordered in
// small 2D blocks so that each Embree packet is coherent), then all shadow rays the hits asked
// for, then the reflection/refraction rays they spawned, and so on. Only the two "trace a
// batch" functions differ between the packet kernel (rtcIntersectK/rtcOccludedK) and the
// single-ray kernel (rtcIntersect1/rtcOccluded1); everything else, including the order in which
// each pixel's contributions are summed, is shared. That is what makes the two kernels give
// bit-identical images.
#include "sampling.h"
#include "scene_impl.h"
#include "shading.h"
#include "trace.h"

#include <rtwall/engine_testing.h>
#include <rtwall/vec.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <type_traits>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace rtwall {

namespace {

struct Scratch {
    std::vector<RayTask> rays, next;
    std::vector<Hit> hits;
    std::vector<ShadowTask> shadows, walk, walkNext;
    std::vector<RayTask> walkRays;
    std::vector<uint8_t> occluded;
    std::vector<Color> accum;
    std::vector<uint32_t> pixelRays;   // false-colour views: rays per pixel
    std::vector<uint16_t> pixelDepth;  // and the deepest ray of each pixel
    // Depth with the tile (issue 27): each pixel's primary-ray hit distance, null when the
    // caller asked for none (then nothing is recorded and the colour path is unchanged).
    std::vector<float> distance;
    float* distanceOut = nullptr;
    // The denoiser's features with the tile (issue 28, FeatureView): sums over the pixel's
    // samples, each weighted as its colour; ids of the first sample. Unused without features.
    bool features = false;
    std::vector<Color> albedo, normal;
    std::vector<uint32_t> id;
};

// Per-thread scratch buffers: grown to the largest tile once, then reused, so the hot path
// does not allocate.
thread_local Scratch tScratch;

// Each valid lane's primary hit distance, the nearest of the pixel's samples (a pixel's
// sub-pixel samples may hit different surfaces; the warp moves the pixel with its nearest one,
// so a foreground edge is never pushed behind what it covers). Lanes that hit nothing, or that
// section planes cut away entirely, keep kBackgroundDepth. Both kernels write the same tfar and
// geomID into the packet, so they record the same distances.
template <int K, class RayHitK>
void recordDistances(const RayHitK& rh, const int* valid, const uint32_t* pixel, float* distance) {
    for (int k = 0; k < K; ++k) {
        if (!valid[k] || rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
        distance[pixel[k]] = std::min(distance[pixel[k]], rh.ray.tfar[k]);
    }
}

// Each valid lane's first-hit features (featuresAt) added to its pixel's sums with the sample's
// weight; the pixel's first sample (`first`) also gives its id. Both kernels write the same hits
// into the packet, so they record the same features.
template <int K, class RayHitK>
void recordFeatures(const ShadingContext& shading, const RayHitK& rh, const int* valid, const uint32_t* pixel,
                    const Float3& org, float weight, bool first, Scratch& sc) {
    for (int k = 0; k < K; ++k) {
        if (!valid[k]) continue;
        const HitFeatures f = featuresAt(shading, org, {rh.ray.dir_x[k], rh.ray.dir_y[k], rh.ray.dir_z[k]}, hitOf(rh, k));
        sc.albedo[pixel[k]] += f.albedo * weight;
        sc.normal[pixel[k]] += f.normal * weight;
        if (first) sc.id[pixel[k]] = f.id;
    }
}

// The primary-ray pass of one tile. Both kernels run this same code and differ only in how
// the packet is handed to Embree: whole (rtcIntersectK) or lane by lane (rtcIntersect1, with
// the results written back into the packet), so every value downstream is identical.
// kWarped: the camera has projector warps (issue 30). The flat instantiation's ray generation
// stays as bare as the benchmark's reference loop (a per-lane branch there, or a lambda holding
// both loops, cost the packet kernel 3-7 % against bare Embree).
template <int K, bool kUsePackets, bool kWarped>
void primaryPassK(const Scene::Impl& s, const Camera& camera, const TileRect& rect, uint32_t frame,
                  const ShadingContext& shading, Scratch& sc) {
    using P = Packet<K>;
    constexpr int bw = P::blockW, bh = P::blockH;
    const RenderSettings& settings = shading.settings;
    const int w = rect.width(), h = rect.height();
    const int ss = std::max(1, settings.supersample);
    const int spp = std::max(1, settings.samples);
    const float sampleWeight = shading.sampleWeight;
    const bool eyeLight = settings.shading == ShadingMode::EyeLight;
    // Where frames differ anyway (path tracing, area lights, a rough metal, a volume: what the
    // master averages while the view is still), each frame also takes its own sub-pixel
    // positions and pruning coins, so that the average anti-aliases and every pruned ray tree
    // is drawn anew: it converges to the box-filtered, unpruned image. A deterministic scene
    // samples pixel centres and frame 0's coins every frame, so its frames do not flicker.
    const bool perFrame = rendersStochastically(settings, s.randomContent);
    const Float3 org = camera.origin();

    TopLevels levels(s, true, true);
    alignas(64) typename P::RayHit rh;
    alignas(64) int valid[K];
    alignas(64) int traced[K];  // section planes: the lanes with something left to trace
    int enter[K];
    const SectionState& sections = s.sections;
    const bool clipping = sections.count > 0;
    const int* traceValid = clipping ? traced : valid;
    float originDist[kMaxSections];  // every primary ray of the tile starts at the camera
    sectionDistances(sections, org, originDist);
    uint32_t pixel[K], seed[K] = {}, rouletteSeed[K] = {};
    float ox[K], oy[K];
    for (int k = 0; k < K; ++k) {
        rh.ray.org_x[k] = org.x;
        rh.ray.org_y[k] = org.y;
        rh.ray.org_z[k] = org.z;
        rh.ray.tnear[k] = 0.0f;
        rh.ray.time[k] = 0.0f;
        rh.ray.mask[k] = kMaskAll;
        rh.ray.id[k] = 0;
        rh.ray.flags[k] = 0;
    }
    for (int sy = 0; sy < ss; ++sy)
        for (int sx = 0; sx < ss; ++sx)
            for (int si = 0; si < spp; ++si) {
                const uint32_t sampleIndex = uint32_t((sy * ss + sx) * spp + si);
                const float cx = (float(sx) + 0.5f) / float(ss), cy = (float(sy) + 0.5f) / float(ss);
                for (int by = 0; by < h; by += bh)
                    for (int bx = 0; bx < w; bx += bw) {
                        // Random numbers only where they are used: eyelight previews keep the
                        // generation loop below as bare as the benchmark's reference loop.
                        if (!eyeLight)
                            for (int k = 0; k < K; ++k) {
                                const uint32_t px = uint32_t(rect.x0 + bx + k % bw), py = uint32_t(rect.y0 + by + k / bw);
                                seed[k] = pixelSeed(px, py, frame, sampleIndex);
                                rouletteSeed[k] = perFrame ? seed[k] : pixelSeed(px, py, 0, sampleIndex);
                            }
                        for (int k = 0; k < K; ++k) {
                            ox[k] = perFrame ? (float(sx) + randomFloat(seed[k], 1000)) / float(ss) : cx;
                            oy[k] = perFrame ? (float(sy) + randomFloat(seed[k], 1001)) / float(ss) : cy;
                        }
                        for (int k = 0; k < K; ++k) {
                            const int i = bx + k % bw, j = by + k / bw;
                            const bool inside = i < w && j < h;
                            const float px = float(rect.x0 + i) + ox[k], py = float(rect.y0 + j) + oy[k];
                            Float3 d = kWarped ? camera.direction(px, py) : camera.flatDirection(px, py);
                            bool onScreen = true;
                            if constexpr (kWarped) {  // a sample on no screen is not traced: black
                                onScreen = !std::isnan(d.x + d.y + d.z);
                                if (!onScreen) d = {0.0f, 0.0f, 1.0f};
                            }
                            valid[k] = inside && onScreen ? -1 : 0;
                            pixel[k] = inside ? uint32_t(j * w + i) : 0;
                            const float inv = 1.0f / std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
                            rh.ray.dir_x[k] = d.x * inv;
                            rh.ray.dir_y[k] = d.y * inv;
                            rh.ray.dir_z[k] = d.z * inv;
                            rh.ray.tfar[k] = INFINITY;
                            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                            rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
                        }
                        if (clipping)
                            for (int k = 0; k < K; ++k) {
                                float t0 = 0.0f, t1 = INFINITY;
                                enter[k] = -1;
                                const Float3 d{rh.ray.dir_x[k], rh.ray.dir_y[k], rh.ray.dir_z[k]};
                                const bool kept = clipToSections(sections, originDist, d, t0, t1, enter[k]);
                                traced[k] = valid[k] && kept ? -1 : 0;
                                rh.ray.tnear[k] = kept ? t0 : 0.0f;
                                rh.ray.tfar[k] = kept ? t1 : INFINITY;
                            }
                        levels.each(s, [&](RTCScene scene, RTCIntersectContext* ctx) {
                            if constexpr (kUsePackets) P::intersect(traceValid, scene, ctx, &rh);
                            else intersectLanes<K>(traceValid, scene, ctx, rh);
                        });
                        if (clipping) capPacket<K>(s, traced, enter, rh);
                        if (sc.distanceOut) recordDistances<K>(rh, valid, pixel, sc.distanceOut);
                        if (sc.features) recordFeatures<K>(shading, rh, valid, pixel, org, sampleWeight, sampleIndex == 0, sc);
                        if (eyeLight) {
                            shadeEyeLightPacket<K>(shading, rh, valid, pixel, sampleWeight, sc.accum.data());
                            continue;
                        }
                        for (int k = 0; k < K; ++k) {
                            if (!valid[k]) continue;
                            RayTask t;
                            t.org = org;
                            t.dir = {rh.ray.dir_x[k], rh.ray.dir_y[k], rh.ray.dir_z[k]};
                            t.tfar = INFINITY;
                            t.weight = {sampleWeight, sampleWeight, sampleWeight};
                            t.pixel = pixel[k];
                            t.depth = 1;
                            t.seed = seed[k];
                            t.rouletteSeed = rouletteSeed[k];
                            shadeHit(shading, t, hitOf(rh, k), sc.accum[t.pixel], sc.shadows, sc.next);
                        }
                    }
            }
}

template <bool kUsePackets>
void primaryPassFor(int width, const Scene::Impl& s, const Camera& camera, const TileRect& rect, uint32_t frame,
                    const ShadingContext& shading, Scratch& sc) {
    const auto pass = [&](auto warped) {
        constexpr bool w = decltype(warped)::value;
        if (width == 16) primaryPassK<16, kUsePackets, w>(s, camera, rect, frame, shading, sc);
        else if (width == 8) primaryPassK<8, kUsePackets, w>(s, camera, rect, frame, shading, sc);
        else primaryPassK<4, kUsePackets, w>(s, camera, rect, frame, shading, sc);
    };
    if (camera.warped()) pass(std::true_type{});
    else pass(std::false_type{});
}

int detectPacketWidth() {
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f")) return 16;
    if (__builtin_cpu_supports("avx")) return 8;
    return 4;
}

// The packet width a tile is traced with: the option, or this CPU's widest.
int widthFor(const TraceOptions& trace) {
    const int w = trace.packetWidth == 0 ? packetWidth() : trace.packetWidth;
    if (w != 4 && w != 8 && w != 16)
        throw std::invalid_argument("packet width " + std::to_string(trace.packetWidth) + " is not 0, 4, 8 or 16");
    return w;
}

// Shadow rays: first the fast occlusion query against opaque instances only; the survivors
// then walk the shadow-transparent instances (glass, volumes) hit by hit, in order, each
// taking away its share of the light. Walking in order keeps every product in the same order
// for both kernels, so they stay bit-identical.
void traceShadows(const Tracer& tracer, const ShadingContext& shading, Scratch& sc, TileStats& stats,
                  bool trackRays) {
    const Scene::Impl& s = shading.scene;
    sc.occluded.resize(sc.shadows.size());
    const uint32_t firstMask = s.anyShadowTransparent ? kMaskOpaque : kMaskAll;
    clipRays(s.sections, sc.shadows.data(), sc.shadows.size());
    tracer.shadow(s, sc.shadows.data(), sc.occluded.data(), sc.shadows.size(), firstMask, s.coherentOcclusion);
    stats.shadowRays += sc.shadows.size();
    if (trackRays)
        for (const ShadowTask& t : sc.shadows) ++sc.pixelRays[t.pixel];
    if (!s.anyShadowTransparent) {
        for (size_t i = 0; i < sc.shadows.size(); ++i)
            if (!sc.occluded[i]) sc.accum[sc.shadows[i].pixel] += sc.shadows[i].contribution;
        return;
    }
    sc.walk.clear();
    for (size_t i = 0; i < sc.shadows.size(); ++i)
        if (!sc.occluded[i]) sc.walk.push_back(sc.shadows[i]);
    for (int step = 0; step < 256 && !sc.walk.empty(); ++step) {
        sc.walkRays.resize(sc.walk.size());
        for (size_t i = 0; i < sc.walk.size(); ++i) {
            const ShadowTask& t = sc.walk[i];
            sc.walkRays[i] = RayTask{t.org, t.dir, t.tfar, t.contribution, t.pixel, 0, 0, 0};
        }
        sc.hits.resize(sc.walk.size());
        clipRays(s.sections, sc.walkRays.data(), sc.walkRays.size());
        tracer.closest(s, sc.walkRays.data(), sc.hits.data(), sc.walk.size(), false, kMaskShadowTransparent);
        capHits(s, sc.walkRays.data(), sc.hits.data(), sc.walk.size());
        stats.shadowRays += sc.walk.size();
        sc.walkNext.clear();
        for (size_t i = 0; i < sc.walk.size(); ++i) {
            ShadowTask t = sc.walk[i];
            const Hit& hit = sc.hits[i];
            if (hit.inst == kNoHit) {
                sc.accum[t.pixel] += t.contribution;
                continue;
            }
            if (hit.inst == kCapHit) continue;  // caps are opaque
            const ShadowPass pass = shadowPassAt(shading, t, hit);
            t.contribution = t.contribution * pass.transmittance;
            if (!(maxComponent(t.contribution) > 0.0f)) continue;
            const float at = std::max(hit.t, pass.continueAt);
            const Float3 p = t.org + t.dir * at;
            const float eps = (1.0f + maxAbsComponent(p)) * (1.0f / 65536.0f);
            if (!(at + eps < t.tfar)) {
                sc.accum[t.pixel] += t.contribution;
                continue;
            }
            t.org = p + t.dir * eps;
            t.tfar -= at + eps;
            sc.walkNext.push_back(t);
        }
        sc.walk.swap(sc.walkNext);
    }
}

// False colours: a blue-to-red ramp over [0, 1] (red at 1 and above).
Color ramp(float x) {
    x = std::clamp(x, 0.0f, 1.0f);
    if (x < 0.25f) return {0.0f, 4.0f * x, 1.0f};
    if (x < 0.5f) return {0.0f, 1.0f, 1.0f - 4.0f * (x - 0.25f)};
    if (x < 0.75f) return {4.0f * (x - 0.5f), 1.0f, 0.0f};
    return {1.0f, 1.0f - 4.0f * (x - 0.75f), 0.0f};
}

// The whole tile into sc.accum (linear RGB), and the per-pixel counts a false-colour view needs.
// With `depth`, also each pixel's primary hit distance into sc.distance.
// With `features`, also the denoiser's features into sc.albedo, sc.normal and sc.id.
TileStats renderTileInto(const Scene::Impl& s, const Camera& camera, const TileRect& rect, uint32_t frame,
                         const RenderSettings& settings, const TraceOptions& trace, bool depth, Scratch& sc,
                         bool features = false);
// The same, then quantised (or false-coloured) into `out`, and the distances into `depth`.
TileStats renderTileTo(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                       const RenderSettings& settings, TileView out, DepthView depth, const TraceOptions& trace);

// sc.distance (w x h) into the caller's rows.
void copyDistances(const Scratch& sc, int w, int h, DepthView depth) {
    for (int j = 0; j < h; ++j)
        std::copy_n(sc.distance.data() + size_t(j) * size_t(w), size_t(w), depth.data + size_t(j) * depth.stride);
}

// sc's features (w x h) into the caller's rows: those it asked for.
void copyFeatures(const Scratch& sc, int w, int h, FeatureView f) {
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const size_t from = size_t(j) * size_t(w) + size_t(i), to = size_t(j) * f.stride + size_t(i);
            if (f.albedo) {
                const Color& a = sc.albedo[from];
                f.albedo[3 * to] = a.x, f.albedo[3 * to + 1] = a.y, f.albedo[3 * to + 2] = a.z;
            }
            if (f.normal) {
                const Float3& n = sc.normal[from];
                f.normal[3 * to] = n.x, f.normal[3 * to + 1] = n.y, f.normal[3 * to + 2] = n.z;
            }
            if (f.id) f.id[to] = sc.id[from];
        }
}

// Runs one tile's work; whatever it throws leaves as a TileError that says which tile of which
// frame failed (renderFrame's threads, a render client's threads and the CLI all report it).
// A try block costs nothing until something throws.
template <class Work>
TileStats asTileWork(const TileRect& rect, uint32_t frame, const TraceOptions& trace, Work&& work) {
    try {
        if (trace.fault && trace.fault->frame == frame && trace.fault->x >= rect.x0 && trace.fault->x < rect.x1 &&
            trace.fault->y >= rect.y0 && trace.fault->y < rect.y1)
            throw std::runtime_error("injected fault at pixel " + std::to_string(trace.fault->x) + "," +
                                     std::to_string(trace.fault->y));
        return work();
    } catch (const TileError&) {
        throw;
    } catch (const std::exception& e) {
        throw TileError(frame, rect, e.what());
    } catch (...) {
        throw TileError(frame, rect, "an exception that is no std::exception");
    }
}

Tracer tracerFor(KernelType kernel, int width) {
    if (kernel == KernelType::Single) return {traceClosestSingle, traceShadowSingle};
    if (width == 16) return packetTracer<16>();
    if (width == 8) return packetTracer<8>();
    return packetTracer<4>();
}

}  // namespace

int packetWidth() {
    static const int width = detectPacketWidth();
    return width;
}

// Embree 3's coherent occlusion traversal (BVHNIntersectorKHybrid::occludedCoherent, chosen by
// RTC_INTERSECT_CONTEXT_FLAG_COHERENT) keeps the bits of its active rays in a size_t filled
// from an AVX-512 mask register. GCC before 14 can leave garbage in the bits above the packet
// width there, so the loop over octants never runs out of rays: rtcOccluded16 spins for ever,
// depending on what the registers held before the call, which made the hang come and go with
// the stack's address (11 of 16 stack offsets hung one tile of builtin:knots).
// Debian's Embree 3.13.5 is built with GCC 12; upstream worked around it in Embree 4.4.1
// (RenderKit/embree#574), whose API rtwall does not use. The incoherent path has no such loop.
// 8- and 4-wide packets run the same function in the AVX-512 kernels; they never hung in our
// trials, but the incoherent path costs nothing measurable there (docs/benchmarks.md), so no
// width bets on it. Closest-hit queries keep the coherent path: its source has the same loop,
// but upstream had to mend only the occlusion function once its CI built AVX-512 with GCC, and
// rtcIntersect16 on the very packets that hung rtcOccluded16 here never hung. Where Embree
// does not run AVX-512 kernels (no native 16-wide packets) nothing changes.
bool coherentOcclusionIsSafe(RTCDevice device) {
    const bool avx512Kernels = rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
    const long version = rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION);
    return !avx512Kernels || version >= 40401;
}

TileError::TileError(uint32_t frame, const TileRect& rect, const std::string& reason)
    : std::runtime_error("frame " + std::to_string(frame) + ", tile " + std::to_string(rect.x0) + "," +
                         std::to_string(rect.y0) + "," + std::to_string(rect.x1) + "," + std::to_string(rect.y1) + ": " +
                         reason),
      frame_(frame), rect_(rect), reason_(reason) {}

TileStats renderTile(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                     const RenderSettings& settings, TileView out, const TraceOptions& trace) {
    return renderTile(scene, camera, rect, frame, settings, out, DepthView{}, trace);
}

TileStats renderTile(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                     const RenderSettings& settings, TileView out, DepthView depth, const TraceOptions& trace) {
    return asTileWork(rect, frame, trace,
                      [&] { return renderTileTo(scene, camera, rect, frame, settings, out, depth, trace); });
}

TileStats renderTileLinear(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                           const RenderSettings& settings, float* out, size_t stride, const TraceOptions& trace) {
    return renderTileLinear(scene, camera, rect, frame, settings, out, stride, DepthView{}, trace);
}

TileStats renderTileLinear(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                           const RenderSettings& settings, float* out, size_t stride, DepthView depth,
                           const TraceOptions& trace) {
    return renderTileLinear(scene, camera, rect, frame, settings, out, stride, depth, FeatureView{}, trace);
}

TileStats renderTileLinear(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                           const RenderSettings& settings, float* out, size_t stride, DepthView depth,
                           FeatureView features, const TraceOptions& trace) {
    return asTileWork(rect, frame, trace, [&] {
        Scratch& sc = tScratch;
        const TileStats stats =
            renderTileInto(scene.impl(), camera, rect, frame, settings, trace, depth.data != nullptr, sc, features.any());
        const int w = rect.width(), h = rect.height();
        if (depth.data) copyDistances(sc, w, h, depth);
        if (features.any()) copyFeatures(sc, w, h, features);
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i) {
                const Color& c = sc.accum[size_t(j) * w + i];
                float* o = out + size_t(j) * stride + 3 * size_t(i);
                o[0] = c.x;
                o[1] = c.y;
                o[2] = c.z;
            }
        return stats;
    });
}

namespace {

TileStats renderTileTo(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                       const RenderSettings& settings, TileView out, DepthView depth, const TraceOptions& trace) {
    Scratch& sc = tScratch;
    const auto t0 = std::chrono::steady_clock::now();
    const TileStats stats = renderTileInto(scene.impl(), camera, rect, frame, settings, trace, depth.data != nullptr, sc);
    const int w = rect.width(), h = rect.height();
    if (w <= 0 || h <= 0) return stats;
    if (depth.data) copyDistances(sc, w, h, depth);

    // False-colour views replace the shaded colour.
    Color tileColor{0, 0, 0};
    if (settings.view == ViewMode::TileTime) {
        // Log scale: 0.1 ms blue ... 100 ms and more red.
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        tileColor = ramp(float((std::log10(std::max(ms, 1e-3)) + 1.0) / 3.0));
    } else if (settings.view == ViewMode::Client) {
        const uint32_t hsh = fmix32(trace.clientId + 1u);
        tileColor = ramp(float(hsh & 0xFFFF) / 65535.0f);
    }
    const int spp = std::max(1, settings.supersample) * std::max(1, settings.supersample) * std::max(1, settings.samples);
    for (int j = 0; j < h; ++j) {
        uint8_t* row = out.data + size_t(j) * out.stride;
        for (int i = 0; i < w; ++i) {
            const size_t px = size_t(j) * w + i;
            Color c = sc.accum[px];
            switch (settings.view) {
            case ViewMode::Shaded: break;
            case ViewMode::Depth: c = ramp(float(sc.pixelDepth[px]) / 25.0f); break;
            case ViewMode::Rays: c = ramp(float(std::log2(1.0 + double(sc.pixelRays[px]) / spp) / 6.0)); break;
            case ViewMode::TileTime:
            case ViewMode::Client: c = tileColor; break;
            }
            row[3 * i + 0] = linearToSrgb8(c.x);
            row[3 * i + 1] = linearToSrgb8(c.y);
            row[3 * i + 2] = linearToSrgb8(c.z);
        }
    }
    return stats;
}

TileStats renderTileInto(const Scene::Impl& s, const Camera& camera, const TileRect& rect, uint32_t frame,
                         const RenderSettings& settings, const TraceOptions& trace, bool depth, Scratch& sc,
                         bool features) {
    const int width = widthFor(trace);
    const Tracer tracer = tracerFor(settings.kernel, width);
    TileStats stats;

    const int w = rect.width(), h = rect.height();
    if (w <= 0 || h <= 0) return stats;
    const int ss = std::max(1, settings.supersample);
    const int spp = std::max(1, settings.samples);
    ShadingContext shading{s, settings, 1.0f / float(ss * ss * spp)};
    const bool trackDepth = settings.view == ViewMode::Depth, trackRays = settings.view == ViewMode::Rays;

    sc.accum.assign(size_t(w) * h, Color{0, 0, 0});
    sc.shadows.clear();
    sc.next.clear();
    if (trackDepth) sc.pixelDepth.assign(size_t(w) * h, uint16_t(1));
    if (trackRays) sc.pixelRays.assign(size_t(w) * h, uint32_t(ss * ss * spp));
    if (depth) sc.distance.assign(size_t(w) * h, kBackgroundDepth);
    sc.distanceOut = depth ? sc.distance.data() : nullptr;
    sc.features = features;
    if (features) {
        sc.albedo.assign(size_t(w) * h, Color{0, 0, 0});
        sc.normal.assign(size_t(w) * h, Float3{0, 0, 0});
        sc.id.assign(size_t(w) * h, 0u);
    }
    // Primary rays: sub-pixel sample outermost, then one coherent packet-shaped pixel block
    // per batch, generated straight into Embree's SoA packet, traced and shaded while hot in L1.
    if (settings.kernel == KernelType::Packet) primaryPassFor<true>(width, s, camera, rect, frame, shading, sc);
    else primaryPassFor<false>(width, s, camera, rect, frame, shading, sc);
    stats.rays += uint64_t(w) * h * ss * ss * spp;

    // Then generation by generation: the shadow rays of the last one, and the rays it spawned.
    for (;;) {
        if (!sc.shadows.empty()) {
            traceShadows(tracer, shading, sc, stats, trackRays);
            sc.shadows.clear();
        }
        if (sc.next.empty()) break;
        sc.rays.swap(sc.next);
        sc.next.clear();
        sc.hits.resize(sc.rays.size());
        clipRays(s.sections, sc.rays.data(), sc.rays.size());
        tracer.closest(s, sc.rays.data(), sc.hits.data(), sc.rays.size(), false, kMaskAll);
        capHits(s, sc.rays.data(), sc.hits.data(), sc.rays.size());
        stats.rays += sc.rays.size();
        if (trackDepth)
            for (const RayTask& r : sc.rays)
                sc.pixelDepth[r.pixel] = std::max<uint16_t>(sc.pixelDepth[r.pixel], uint16_t(r.depth));
        if (trackRays)
            for (const RayTask& r : sc.rays) ++sc.pixelRays[r.pixel];
        for (size_t i = 0; i < sc.rays.size(); ++i)
            shadeHit(shading, sc.rays[i], sc.hits[i], sc.accum[sc.rays[i].pixel], sc.shadows, sc.next);
    }
    return stats;
}

}  // namespace

std::vector<TileRect> makeTiles(int width, int height, int tileSize) {
    std::vector<TileRect> tiles;
    if (width <= 0 || height <= 0 || tileSize <= 0) return tiles;
    for (int y = 0; y < height; y += tileSize)
        for (int x = 0; x < width; x += tileSize)
            tiles.push_back({x, y, std::min(width, x + tileSize), std::min(height, y + tileSize)});
    return tiles;
}

namespace {

// Renders every tile of a frame with `renderOne(rect)` on settings.threads threads, tiles handed
// out on demand; a tile that throws stops the frame, and the first TileError is rethrown once
// every thread has stopped. Returns the rays traced.
template <class RenderOne>
TileStats renderTilesInParallel(const RenderSettings& settings, RenderOne&& renderOne) {
    const std::vector<TileRect> tiles = makeTiles(settings.width, settings.height, settings.tileSize);
    int threads = settings.threads > 0 ? settings.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    threads = std::max(1, std::min<int>(threads, int(tiles.size())));

    std::atomic<size_t> nextTile{0};
    std::atomic<uint64_t> rays{0}, shadowRays{0};
    std::mutex failureMutex;
    std::exception_ptr failure;  // the first tile that threw
    auto worker = [&] {
        TileStats local;
        for (size_t t; (t = nextTile.fetch_add(1, std::memory_order_relaxed)) < tiles.size();) {
            try {
                const TileStats ts = renderOne(tiles[t]);
                local.rays += ts.rays;
                local.shadowRays += ts.shadowRays;
            } catch (...) {
                // No thread dies silently: stop handing out tiles and report this one (a
                // TileError: renderTile makes every exception one).
                nextTile = tiles.size();
                std::lock_guard lock(failureMutex);
                if (!failure) failure = std::current_exception();
            }
        }
        rays += local.rays;
        shadowRays += local.shadowRays;
    };
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
    return {rays.load(), shadowRays.load()};
}

}  // namespace

Image renderFrame(const Scene& scene, const Camera& camera, const RenderSettings& settings, uint32_t frame,
                  TileStats* stats, const TraceOptions& trace) {
    Image img;
    img.width = settings.width;
    img.height = settings.height;
    img.rgb.assign(size_t(img.width) * img.height * 3, 0);
    const TileStats st = renderTilesInParallel(settings, [&](const TileRect& r) {
        return renderTile(scene, camera, r, frame, settings, {img.pixel(r.x0, r.y0), size_t(img.width) * 3}, trace);
    });
    if (stats) *stats = st;
    return img;
}

RenderedFrame renderFrameWithDepth(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                                   uint32_t frame, const TraceOptions& trace) {
    RenderedFrame out;
    out.image.width = settings.width;
    out.image.height = settings.height;
    out.image.rgb.assign(size_t(std::max(0, settings.width)) * size_t(std::max(0, settings.height)) * 3, 0);
    out.depth.assign(size_t(std::max(0, settings.width)) * size_t(std::max(0, settings.height)), kBackgroundDepth);
    const size_t w = size_t(std::max(0, settings.width));
    renderTilesInParallel(settings, [&](const TileRect& r) {
        return renderTile(scene, camera, r, frame, settings, {out.image.pixel(r.x0, r.y0), w * 3},
                          {out.depth.data() + size_t(r.y0) * w + size_t(r.x0), w}, trace);
    });
    return out;
}

FeatureFrame renderFrameFeatures(const Scene& scene, const Camera& camera, const RenderSettings& settings, uint32_t frame,
                                 TileStats* stats, const TraceOptions& trace) {
    const size_t w = size_t(std::max(0, settings.width)), n = w * size_t(std::max(0, settings.height));
    FeatureFrame out;
    out.linear.assign(n * 3, 0.0f);
    out.depth.assign(n, kBackgroundDepth);
    out.albedo.assign(n * 3, 0.0f);
    out.normal.assign(n * 3, 0.0f);
    out.id.assign(n, 0u);
    const TileStats st = renderTilesInParallel(settings, [&](const TileRect& r) {
        const size_t at = size_t(r.y0) * w + size_t(r.x0);
        return renderTileLinear(scene, camera, r, frame, settings, out.linear.data() + at * 3, w * 3,
                                {out.depth.data() + at, w},
                                {out.albedo.data() + at * 3, out.normal.data() + at * 3, out.id.data() + at, w}, trace);
    });
    if (stats) *stats = st;
    return out;
}

std::vector<float> renderFrameLinear(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                                     uint32_t frame, TileStats* stats, const TraceOptions& trace) {
    std::vector<float> out(size_t(std::max(0, settings.width)) * size_t(std::max(0, settings.height)) * 3, 0.0f);
    const size_t stride = size_t(std::max(0, settings.width)) * 3;
    const TileStats st = renderTilesInParallel(settings, [&](const TileRect& r) {
        return renderTileLinear(scene, camera, r, frame, settings, out.data() + size_t(r.y0) * stride + size_t(r.x0) * 3,
                                stride, trace);
    });
    if (stats) *stats = st;
    return out;
}

}  // namespace rtwall
