// rtwall bench cluster: the master and its clients on this PC over loopback. Each setting is
// varied on its own around a base (2 clients, prefetch 4, LZ4, affinity on): client count,
// prefetch depth, codec, affinity. With --replay (the default) clients render each tile once
// and then resend its bytes, so the figures measure the master and the link, not the CPUs.
// Every result also reports where the CPU time went during the measured frames, per thread from
// /proc/PID/task/TID/stat (user + system time, so the kernel's loopback TCP is counted in the
// thread that sends or receives): the clients' render threads (named rtw-render; rendering and
// encoding) against everything else in the clients, and the master's network thread (rtw-net),
// decode threads (rtw-decode), ZeroMQ I/O threads (ZMQbg/...) and the rest (the caller's frame
// assembly). The simulation's host costs (rtwall simulate --client-us-per-tile ...) come from these.
#include "bench.h"
#include "bench_util.h"

#include <rtwall/cluster.h>
#include <rtwall/denoise.h>
#include <rtwall/engine.h>

#include <toml++/toml.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <cmath>
#include <sstream>

namespace rtwall::bench {

namespace {

struct Point {
    std::string vary;
    int clients, prefetch;
    TileCodec codec;
    bool affinity;
    bool depth = false;  // depth with every tile (--depth)
    std::string features = "off";  // the denoise mode whose features travel (--features)
};

// CPU seconds (user + system) of every thread of a process, by thread id, with its name.
struct ThreadCpu {
    std::string name;
    double seconds = 0;
};
std::map<long, ThreadCpu> threadCpu(pid_t pid) {
    std::map<long, ThreadCpu> out;
    static const double tick = double(sysconf(_SC_CLK_TCK));
    std::error_code ec;
    for (const auto& task : std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
        std::ifstream in(task.path() / "stat");
        std::string line;
        if (!std::getline(in, line)) continue;  // the thread ended meanwhile
        const size_t open = line.find('('), close = line.rfind(')');
        if (open == std::string::npos || close == std::string::npos || close < open) continue;
        std::istringstream rest(line.substr(close + 2));
        std::vector<std::string> f;
        for (std::string x; rest >> x;) f.push_back(x);
        if (f.size() < 13) continue;
        // After the name: state is field 3 of proc(5), utime 14, stime 15.
        ThreadCpu t{line.substr(open + 1, close - open - 1), (std::stod(f[11]) + std::stod(f[12])) / tick};
        out[std::stol(task.path().filename().string())] = t;
    }
    return out;
}

// CPU seconds per role between two snapshots of the same processes.
std::map<std::string, double> cpuByRole(const std::vector<std::map<long, ThreadCpu>>& before,
                                        const std::vector<std::map<long, ThreadCpu>>& after, bool master) {
    std::map<std::string, double> roles;
    for (size_t p = 0; p < after.size(); ++p)
        for (const auto& [tid, t] : after[p]) {
            const auto b = before[p].find(tid);
            const double d = t.seconds - (b == before[p].end() ? 0.0 : b->second.seconds);
            std::string role;
            if (t.name == "rtw-render") role = "render";
            else if (t.name == "rtw-net") role = "net";
            else if (t.name == "rtw-decode") role = "decode";
            else if (t.name.rfind("ZMQbg", 0) == 0) role = "zmq";
            else role = master ? "main" : "other";
            roles[role] += d;
        }
    return roles;
}

// The settings measured: each varied on its own around the base, or only --client-counts.
std::vector<Point> pointsOf(const ClusterOptions& o) {
    std::vector<Point> points;
    if (!o.clientCounts.empty()) {
        for (int c : o.clientCounts) points.push_back({"clients", c, 4, tileCodecFromName(o.codec), true});
        return points;
    }
    for (int c = 1; c <= o.maxClients; c *= 2) points.push_back({"clients", c, 4, TileCodec::Lz4, true});
    for (int p : {1, 2, 8}) points.push_back({"prefetch", 2, p, TileCodec::Lz4, true});
    for (TileCodec c : {TileCodec::Raw, TileCodec::Zstd, TileCodec::Jpeg}) points.push_back({"codec", 2, 4, c, true});
    points.push_back({"affinity", 2, 4, TileCodec::Lz4, false});
    // The targets: raw pixels against the link's limit, and a codec at >= 40 dB.
    for (TileCodec c : {TileCodec::Raw, TileCodec::Lz4, TileCodec::Jpeg})
        points.push_back({"target", o.maxClients, 8, c, true});
    return points;
}

using CpuSnapshot = std::vector<std::map<long, ThreadCpu>>;  // this process, then each client

// CPU seconds per frame by role (mean over the measured frames).
toml::table cpuTable(const CpuSnapshot& before, const CpuSnapshot& after, const ClusterOptions& o, double wall) {
    const auto masterCpu = cpuByRole({before[0]}, {after[0]}, true);
    const auto clientCpu = cpuByRole({before.begin() + 1, before.end()}, {after.begin() + 1, after.end()}, false);
    toml::table cpu;
    double clientOther = 0, masterTotal = 0;
    for (const auto& [role, sec] : clientCpu) {
        cpu.insert("client_" + role + "_s", sec / o.frames);
        if (role != "render") clientOther += sec;
    }
    for (const auto& [role, sec] : masterCpu) {
        cpu.insert("master_" + role + "_s", sec / o.frames);
        masterTotal += sec;
    }
    cpu.insert("client_non_render_s", clientOther / o.frames);
    cpu.insert("master_total_s", masterTotal / o.frames);
    cpu.insert("wall_s", wall / o.frames);
    cpu.insert("tiles", double(makeTiles(o.width, o.height, o.tile).size()));
    return cpu;
}

// One setting: a master and its clients, warmed up, then o.frames measured frames.
toml::table measure(const SceneDesc& desc, const Image& reference, const Point& p, const ClusterOptions& o) {
    ClusterSettings cs;
    cs.prefetch = p.prefetch;
    cs.affinity = p.affinity;
    cs.codec.codec = p.codec;
    cs.depth = p.depth;
    cs.features = p.features == "off" ? uint8_t(0) : featureBitsFor(denoiseModeFromName(p.features));
    cs.async = true;
    cs.bind = o.bind;
    cs.insecure = o.insecure;
    Master master(desc, cs);
    LocalClients clients(p.clients, master.endpoint(), 1, !o.render, o.netns);
    if (!master.waitForClients(p.clients, 120'000)) throw InputError("local clients did not join");
    master.renderFrame();  // warm-up: first renders (and replay caches)
    master.renderFrame();
    std::vector<double> times, bytes, latency, busy;
    uint64_t stolen = 0, hits = 0;
    Image first;
    auto snapshot = [&] {
        CpuSnapshot s{threadCpu(getpid())};
        for (pid_t pid : clients.pids()) s.push_back(threadCpu(pid));
        return s;
    };
    const CpuSnapshot cpuBefore = snapshot();
    const Stopwatch total;
    Stopwatch frame;
    for (int f = 0; f < o.frames; ++f) {
        FrameReport r;
        Image img = master.renderFrame(&r);
        if (f == 0) first = std::move(img);  // judged after the measured frames: its CPU is not the master's
        times.push_back(frame.seconds());
        frame.restart();
        bytes.push_back(double(r.bytes));
        latency.push_back(r.meanTileLatency);
        stolen += r.tilesStolen;
        hits += r.affinityHits;
        for (const ClientReport& c : r.clients) busy.push_back(c.busyFraction);
    }
    const double wall = total.seconds();
    const CpuSnapshot cpuAfter = snapshot();
    const double db = psnrDb(first, reference), quality = std::isinf(db) ? 999.0 : db;
    const double tiles = double(makeTiles(o.width, o.height, o.tile).size()) * o.frames;
    if (o.text) {
        std::fprintf(o.text, "%-9s clients %d prefetch %d %-4s affinity %-3s depth %-3s features %-8s: %6.1f fps, %6.2f MB/frame, "
                     "PSNR %5.1f dB, tile latency %6.2f ms, busy %.2f, %.1f stolen/frame, %.0f%% kept their client\n",
                     p.vary.c_str(), p.clients, p.prefetch, tileCodecName(p.codec), p.affinity ? "on" : "off",
                     p.depth ? "on" : "off", p.features.c_str(),
                     1.0 / median(times), median(bytes) * 1e-6, quality, median(latency) * 1e3, median(busy),
                     double(stolen) / o.frames, 100.0 * double(hits) / tiles);
        std::fflush(o.text);
    }
    return toml::table{{"vary", p.vary},
                       {"clients", p.clients},
                       {"prefetch", p.prefetch},
                       {"codec", tileCodecName(p.codec)},
                       {"affinity", p.affinity},
                       {"depth", p.depth},
                       {"features", p.features},
                       {"linear_tiles", !o.features.empty()},
                       {"fps", 1.0 / median(times)},
                       {"bytes_per_frame", median(bytes)},
                       {"mean_tile_latency_ms", median(latency) * 1e3},
                       {"client_busy_fraction", median(busy)},
                       {"tiles_stolen_per_frame", double(stolen) / o.frames},
                       {"affinity_hit_fraction", double(hits) / tiles},
                       {"psnr_db", quality},
                       {"mean_fps", o.frames / wall},
                       {"cpu_per_frame", cpuTable(cpuBefore, cpuAfter, o, wall)}};
}

}  // namespace

toml::table clusterNodes(const SceneDesc& desc, const Image& reference, const ClusterOptions& o);  // cluster_nodes.cpp

toml::table cluster(const ClusterOptions& o) {
    // Display-node walls: every count checked before anything runs.
    for (int k : o.displayNodes) {
        nodeBenchWall(o.width, o.height, k);
        if (!o.nodeAddresses.empty() && o.nodeAddresses.size() < size_t(k))
            throw InputError("--node-addresses: " + std::to_string(o.nodeAddresses.size()) + " given for " + std::to_string(k) +
                             " display nodes");
    }
    for (const std::string& c : o.nodeCodecs) tileCodecFromName(c);
    SceneDesc desc = builtinScene("knots", o.triangles);
    desc.settings.width = o.width;
    desc.settings.height = o.height;
    desc.settings.tileSize = o.tile;
    desc.settings.shading = ShadingMode::EyeLight;  // cheap first renders; replay does the rest
    if (!o.features.empty()) {
        // A stochastic scene: its frames travel as linear half-float tiles, which carry features.
        desc.settings.shading = ShadingMode::Full;
        desc.settings.gi = true;
    }
    // Reference for the error of each setting: the single-machine image.
    const Image reference = [&] {
        const Scene scene(desc);
        return renderFrame(scene, Camera(desc.cameras.front(), o.width, o.height), desc.settings);
    }();
    if (!o.displayNodes.empty()) return clusterNodes(desc, reference, o);
    toml::array results;
    for (Point p : pointsOf(o)) {
        results.push_back(measure(desc, reference, p, o));
        // With --depth (--features) the same setting again with depth (and each mode's
        // features), right after: the set shares the load.
        if (o.depth) {
            p.depth = true;
            results.push_back(measure(desc, reference, p, o));
        }
        for (const std::string& mode : o.features) {
            p.depth = true;
            p.features = mode;
            results.push_back(measure(desc, reference, p, o));
        }
    }
    return toml::table{{"benchmark", "cluster"}, {"width", o.width}, {"height", o.height}, {"tile", o.tile}, {"gi", desc.settings.gi},
                       {"frames", o.frames}, {"replay", !o.render}, {"link", o.link}, {"results", results}};
}

}  // namespace rtwall::bench
