// rtwall bench updates: what a camera move costs the master with many instances (issue 17), and
// with --transforms K, K instance transforms per frame as well (a dragged object: each client
// applies them to its Scene before the frame, so a per-update cost that grows with the instance
// count shows in the frame time).
// A scene of N instances of one box, a tiny image (one 32x32 tile, eyelight) so that the cost of
// the update, not rendering, decides the frame time, and local render clients. Per frame: the
// application thread's time in Master::setCamera, the time of the whole Master::renderFrame
// (synchronous: begin, the clients' catch-up, the tile, the frame's end), and the network
// thread's time from the frame's begin to its last tile (FrameReport::seconds). Medians.
// With --moving K: part moves on one Scene instead (moves() below), the issue 29 figures.
#include "bench.h"
#include "bench_util.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>
#include <rtwall/engine_embree.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace rtwall::bench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// A p90 alongside the median (bench_util.h's median is rtwall/tune.h's).
double quantile(std::vector<double> v, double q) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
}

// N boxes on a square grid in the xz-plane, all of one mesh and one material.
SceneDesc manyInstances(int count) {
    SceneDesc d;
    d.meshes.push_back({"box", "shape:box", std::make_shared<const TriangleMesh>(makeBox())});
    Material m;
    m.name = "grey";
    d.materials.push_back(m);
    const int side = std::max(1, int(std::ceil(std::sqrt(double(count)))));
    d.instances.reserve(size_t(count));
    for (int i = 0; i < count; ++i) {
        const double x = 3.0 * (i % side - side / 2), z = 3.0 * (i / side - side / 2);
        d.instances.push_back({0, 0, Transform::translate(x, 0, z) * Transform::scale(0.5, 0.5, 0.5)});
    }
    d.lights.push_back(Light{});
    CameraDesc c;
    c.position = {0, float(3 * side), float(3 * side)};
    d.cameras.push_back(c);
    d.settings.width = 32;
    d.settings.height = 32;
    d.settings.tileSize = 32;
    d.settings.shading = ShadingMode::EyeLight;
    return d;
}

// The bare-Embree reference for a part move: a top level of `count` instances of one box (as
// manyInstances) that one transform change makes Embree rebuild whole, as the engine's single
// top level did before moved instances got a level of their own. Per commit, seconds.
std::vector<double> bareEmbreeRebuilds(int count, int changes) {
    RTCDevice device = rtcNewDevice(nullptr);
    const TriangleMesh box = makeBox();
    RTCScene mesh = rtcNewScene(device);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, box.vertexCount()));
    std::copy_n(box.positions(), 3 * box.vertexCount(), v);
    auto* tri = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, box.triangleCount()));
    std::copy_n(box.indices(), 3 * box.triangleCount(), tri);
    rtcCommitGeometry(g);
    rtcAttachGeometry(mesh, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(mesh);
    const SceneDesc d = manyInstances(count);
    RTCScene top = rtcNewScene(device);
    std::vector<RTCGeometry> instances;
    for (const InstanceDesc& in : d.instances) {
        RTCGeometry i = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(i, mesh);
        float m[12];
        for (int k = 0; k < 12; ++k) m[k] = float(in.transform.m[k]);
        rtcSetGeometryTransform(i, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m);
        rtcCommitGeometry(i);
        rtcAttachGeometry(top, i);
        instances.push_back(i);
    }
    rtcCommitScene(top);
    std::vector<double> out;
    for (int c = 0; c < changes; ++c) {
        RTCGeometry i = instances[size_t(c * 7919) % instances.size()];
        float m[12];
        const Transform t = Transform::translate(0, 0.001 * (c + 1), 0) * d.instances[size_t(c * 7919) % instances.size()].transform;
        for (int k = 0; k < 12; ++k) m[k] = float(t.m[k]);
        rtcSetGeometryTransform(i, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m);
        rtcCommitGeometry(i);
        out.push_back(secondsOf([&] { rtcCommitScene(top); }));
    }
    for (RTCGeometry i : instances) rtcReleaseGeometry(i);
    rtcReleaseScene(top);
    rtcReleaseScene(mesh);
    rtcReleaseDevice(device);
    return out;
}

toml::table timing(const std::vector<double>& seconds) {
    return toml::table{{"median", 1e3 * median(seconds)}, {"p95", 1e3 * quantile(seconds, 0.95)}};
}

// Part moves (issue 29): `moving` instances dragged together, frame after frame, on one Scene
// (what each render client does per change): the cost of the change (setInstanceTransform for
// each mover, then commit) while the static level is rebuilt in the background, a frame
// rendered between changes; the frame time with movers against none; and the bare-Embree
// rebuild that a change cost with one top level.
toml::table moves(const UpdatesOptions& o) {
    SceneDesc desc = manyInstances(o.instances);
    desc.settings.width = desc.settings.height = 128;
    desc.settings.threads = 0;
    std::vector<uint32_t> movers;
    for (int k = 0; k < o.moving; ++k) movers.push_back(uint32_t((size_t(k) * 7919) % desc.instances.size()));
    if (o.movable)
        for (uint32_t i : movers) desc.instances[i].movable = true;  // as the scene file's `movable = true`
    Scene scene(desc);
    const Camera camera(desc.cameras.front(), desc.settings.width, desc.settings.height);
    std::vector<double> still, commits, frames;
    for (int f = 0; f < 5; ++f) still.push_back(secondsOf([&] { renderFrame(scene, camera, desc.settings); }));
    double firstRebuild = 0;
    for (int f = 0; f < o.frames; ++f) {
        commits.push_back(secondsOf([&] {
            for (uint32_t i : movers)
                scene.setInstanceTransform(i, Transform::translate(0, 0.001 * (f + 1), 0) * desc.instances[i].transform);
            scene.commit();
        }));
        // The static level without the movers (none for marked ones: nothing goes stale).
        if (f == 0 && scene.topLevelState().rebuilding) firstRebuild = secondsOf([&] { scene.waitForRebuild(); });
        frames.push_back(secondsOf([&] { renderFrame(scene, camera, desc.settings); }));
    }
    const std::vector<double> bare = bareEmbreeRebuilds(o.instances, std::min(o.frames, 30));
    toml::table out{{"benchmark", "updates"},
                    {"mode", "moves"},
                    {"instances", o.instances},
                    {"moving", o.moving},
                    {"movable", o.movable},
                    {"changes", o.frames},
                    {"commit_ms", timing(commits)},
                    {"static_rebuild_ms", 1e3 * firstRebuild},
                    {"bare_embree_top_rebuild_ms", timing(bare)},
                    {"frame_ms_still", timing(still)},
                    {"frame_ms_moving", timing(frames)}};
    if (o.text)
        std::fprintf(o.text,
                     "%d instances, %d moving, %d changes: commit %.3f ms (p95 %.3f); static level rebuilt in the background in "
                     "%.1f ms; bare Embree top-level rebuild %.1f ms (p95 %.1f); frame %.2f ms moving, %.2f ms still (medians)\n",
                     o.instances, o.moving, o.frames, 1e3 * median(commits), 1e3 * quantile(commits, 0.95), 1e3 * firstRebuild,
                     1e3 * median(bare), 1e3 * quantile(bare, 0.95), 1e3 * median(frames), 1e3 * median(still));
    return out;
}

}  // namespace

toml::table updates(const UpdatesOptions& o) {
    if (o.moving > 0) return moves(o);
    const SceneDesc desc = manyInstances(o.instances);
    ClusterSettings cs;
    cs.async = o.async;
    const auto t0 = Clock::now();
    Master master(desc, cs);
    const double constructSeconds = seconds(Clock::now() - t0);
    LocalClients procs(o.clients, master.endpoint(), 1, false, {}, master.localClientArgs());
    const auto t1 = Clock::now();
    if (!master.waitForClients(o.clients, 300'000)) throw InputError("the local clients did not join");
    const double joinSeconds = seconds(Clock::now() - t1);
    for (int i = 0; i < 3; ++i) master.renderFrame();  // warm-up

    std::vector<double> update, frame, network, transforms;
    CameraDesc camera = desc.cameras.front();
    const float radius = camera.position.z;
    for (int f = 0; f < o.frames; ++f) {
        const float angle = 0.01f * float(f + 1);
        camera.position = {radius * std::sin(angle), camera.position.y, radius * std::cos(angle)};
        const auto a = Clock::now();
        master.setCamera(camera);
        const auto m = Clock::now();
        for (int k = 0; k < o.transforms; ++k) {
            const auto i = uint32_t((size_t(f) * size_t(o.transforms) + size_t(k)) % desc.instances.size());
            master.setInstanceTransform(i, Transform::translate(0, 0.001 * (f + 1), 0) * desc.instances[i].transform);
        }
        const auto b = Clock::now();
        transforms.push_back(seconds(b - m));
        FrameReport report;
        master.renderFrame(&report);
        const auto c = Clock::now();
        update.push_back(seconds(m - a));
        frame.push_back(seconds(c - b));
        network.push_back(report.seconds);
    }
    toml::table out{{"benchmark", "updates"},
                    {"instances", o.instances},
                    {"clients", o.clients},
                    {"frames", o.frames},
                    {"async", o.async},
                    {"transforms_per_frame", o.transforms},
                    {"set_transforms_us_median", 1e6 * median(transforms)},
                    {"master_construct_s", constructSeconds},
                    {"clients_join_s", joinSeconds},
                    {"set_camera_us_median", 1e6 * median(update)},
                    {"set_camera_us_p90", 1e6 * quantile(update, 0.9)},
                    {"render_frame_ms_median", 1e3 * median(frame)},
                    {"render_frame_ms_p90", 1e3 * quantile(frame, 0.9)},
                    {"frame_begin_to_end_ms_median", 1e3 * median(network)},
                    {"update_and_frame_ms_median", 1e3 * (median(update) + median(transforms) + median(frame))}};
    if (o.text)
        std::fprintf(o.text, "%d instances, %d client%s, %d frames (%s): setCamera %.1f us (p90 %.1f), %d transforms %.1f us, "
                    "renderFrame %.3f ms (p90 %.3f), begin to last tile %.3f ms (medians)\n",
                    o.instances, o.clients, o.clients == 1 ? "" : "s", o.frames, o.async ? "async" : "sync",
                    1e6 * median(update), 1e6 * quantile(update, 0.9), o.transforms, 1e6 * median(transforms), 1e3 * median(frame),
                    1e3 * quantile(frame, 0.9), 1e3 * median(network));
    return out;
}

}  // namespace rtwall::bench
