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
#include "commands.h"
#include "bench_util.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <toml++/toml.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

namespace rtwall::cli {

namespace {

struct Point {
    std::string vary;
    int clients, prefetch;
    TileCodec codec;
    bool affinity;
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

}  // namespace

void addBenchCluster(CLI::App& bench, Run& run) {
    struct Options {
        int width = 1600, height = 1200, tile = 32, frames = 10, maxClients = 4;
        int64_t triangles = 200'000;
        bool json = false, render = false, insecure = false;
        std::string bind = "tcp://127.0.0.1:0", netns, link = "loopback", codec = "lz4";
        std::vector<int> clientCounts;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = bench.add_subcommand("cluster", "Frames/s, bytes, stealing and busy time of master and local clients");
    cmd->add_option("--width", o->width, "Image width")->check(CLI::Range(16, 16384));
    cmd->add_option("--height", o->height, "Image height")->check(CLI::Range(16, 16384));
    cmd->add_option("--tile", o->tile, "Tile size")->check(CLI::Range(4, 1024));
    cmd->add_option("--frames", o->frames, "Measured frames per setting (medians are reported)")->check(CLI::Range(1, 10000));
    cmd->add_option("--max-clients", o->maxClients, "Largest client count in the sweep (1, 2, 4, ... up to it)")->check(CLI::Range(1, 256));
    cmd->add_option("--triangles", o->triangles, "Triangles of the built-in scene")->check(CLI::Range(int64_t(1000), int64_t(100'000'000)));
    cmd->add_flag("--render", o->render, "Clients really render every tile (default: replay pre-encoded tiles)");
    cmd->add_option("--bind", o->bind, "Master endpoint (tools/netem.sh binds inside its namespaces)");
    cmd->add_option("--client-netns", o->netns, "Start client i in network namespace <prefix><i> (tools/netem.sh)");
    cmd->add_option("--link", o->link, "Description of the link, copied into the output");
    cmd->add_flag("--insecure", o->insecure, "Allow a non-loopback --bind without CURVE keys (tools/netem.sh namespaces)");
    cmd->add_option("--client-counts", o->clientCounts,
                    "Only these client counts (prefetch 4, LZ4, affinity on), e.g. 1,2,3,4: the simulation's validation")
        ->delimiter(',')
        ->check(CLI::Range(1, 256));
    cmd->add_option("--codec", o->codec, "Codec of the --client-counts runs")->check(CLI::IsMember({"raw", "lz4", "zstd", "jpeg"}));
    cmd->add_flag("--json", o->json, "Print JSON");
    cmd->callback([&run, o] {
        run = [o] {
            SceneDesc desc = builtinScene("knots", o->triangles);
            desc.settings.width = o->width;
            desc.settings.height = o->height;
            desc.settings.tileSize = o->tile;
            desc.settings.shading = ShadingMode::EyeLight;  // cheap first renders; replay does the rest

            std::vector<Point> points;
            for (int c = 1; c <= o->maxClients; c *= 2) points.push_back({"clients", c, 4, TileCodec::Lz4, true});
            for (int p : {1, 2, 8}) points.push_back({"prefetch", 2, p, TileCodec::Lz4, true});
            for (TileCodec c : {TileCodec::Raw, TileCodec::Zstd, TileCodec::Jpeg}) points.push_back({"codec", 2, 4, c, true});
            points.push_back({"affinity", 2, 4, TileCodec::Lz4, false});
            // The targets: raw pixels against the link's limit, and a codec at >= 40 dB.
            for (TileCodec c : {TileCodec::Raw, TileCodec::Lz4, TileCodec::Jpeg})
                points.push_back({"target", o->maxClients, 8, c, true});
            if (!o->clientCounts.empty()) {
                points.clear();
                for (int c : o->clientCounts) points.push_back({"clients", c, 4, tileCodecFromName(o->codec), true});
            }

            // Reference for the error of each setting: the single-machine image.
            const Image reference = [&] {
                const Scene scene(desc);
                return renderFrame(scene, Camera(desc.cameras.front(), o->width, o->height), desc.settings);
            }();
            auto psnr = [&](const Image& img) {
                double se = 0;
                for (size_t i = 0; i < img.rgb.size() && i < reference.rgb.size(); ++i) {
                    const double d = double(img.rgb[i]) - double(reference.rgb[i]);
                    se += d * d;
                }
                return se == 0 ? 999.0 : 10.0 * std::log10(255.0 * 255.0 * double(img.rgb.size()) / se);
            };

            toml::array results;
            for (const Point& p : points) {
                ClusterSettings cs;
                cs.prefetch = p.prefetch;
                cs.affinity = p.affinity;
                cs.codec.codec = p.codec;
                cs.async = true;
                cs.bind = o->bind;
                cs.insecure = o->insecure;
                Master master(desc, cs);
                LocalClients clients(p.clients, master.endpoint(), 1, !o->render, o->netns);
                if (!master.waitForClients(p.clients, 120'000)) throw InputError("local clients did not join");
                master.renderFrame();  // warm-up: first renders (and replay caches)
                master.renderFrame();
                std::vector<double> times, bytes, latency, busy;
                uint64_t stolen = 0, hits = 0;
                double quality = 0;
                Image first;
                auto snapshot = [&] {
                    std::vector<std::map<long, ThreadCpu>> s{threadCpu(getpid())};
                    for (pid_t pid : clients.pids()) s.push_back(threadCpu(pid));
                    return s;
                };
                const std::vector<std::map<long, ThreadCpu>> cpuBefore = snapshot();
                const auto start = std::chrono::steady_clock::now();
                auto last = start;
                for (int f = 0; f < o->frames; ++f) {
                    FrameReport r;
                    Image img = master.renderFrame(&r);
                    if (f == 0) first = std::move(img);  // judged after the measured frames: its CPU is not the master's
                    const auto now = std::chrono::steady_clock::now();
                    times.push_back(std::chrono::duration<double>(now - last).count());
                    last = now;
                    bytes.push_back(double(r.bytes));
                    latency.push_back(r.meanTileLatency);
                    stolen += r.tilesStolen;
                    hits += r.affinityHits;
                    for (const ClientReport& c : r.clients) busy.push_back(c.busyFraction);
                }
                const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                const std::vector<std::map<long, ThreadCpu>> cpuAfter = snapshot();
                quality = psnr(first);
                const auto masterCpu = cpuByRole({cpuBefore[0]}, {cpuAfter[0]}, true);
                const auto clientCpu = cpuByRole({cpuBefore.begin() + 1, cpuBefore.end()}, {cpuAfter.begin() + 1, cpuAfter.end()}, false);
                const double tiles = double(makeTiles(o->width, o->height, o->tile).size()) * o->frames;
                toml::table cpu;  // CPU seconds per frame by role (mean over the measured frames)
                double clientOther = 0, masterTotal = 0;
                for (const auto& [role, sec] : clientCpu) {
                    cpu.insert("client_" + role + "_s", sec / o->frames);
                    if (role != "render") clientOther += sec;
                }
                for (const auto& [role, sec] : masterCpu) {
                    cpu.insert("master_" + role + "_s", sec / o->frames);
                    masterTotal += sec;
                }
                cpu.insert("client_non_render_s", clientOther / o->frames);
                cpu.insert("master_total_s", masterTotal / o->frames);
                cpu.insert("wall_s", wall / o->frames);
                cpu.insert("tiles", double(makeTiles(o->width, o->height, o->tile).size()));
                toml::table row{{"vary", p.vary},
                                {"clients", p.clients},
                                {"prefetch", p.prefetch},
                                {"codec", tileCodecName(p.codec)},
                                {"affinity", p.affinity},
                                {"fps", 1.0 / median(times)},
                                {"bytes_per_frame", median(bytes)},
                                {"mean_tile_latency_ms", median(latency) * 1e3},
                                {"client_busy_fraction", median(busy)},
                                {"tiles_stolen_per_frame", double(stolen) / o->frames},
                                {"affinity_hit_fraction", double(hits) / tiles},
                                {"psnr_db", quality},
                                {"mean_fps", o->frames / wall},
                                {"cpu_per_frame", std::move(cpu)}};
                if (!o->json) {
                    std::printf("%-9s clients %d prefetch %d %-4s affinity %-3s: %6.1f fps, %6.2f MB/frame, PSNR %5.1f dB, "
                                "tile latency %6.2f ms, busy %.2f, %.1f stolen/frame, %.0f%% kept their client\n",
                                p.vary.c_str(), p.clients, p.prefetch, tileCodecName(p.codec), p.affinity ? "on" : "off",
                                1.0 / median(times), median(bytes) * 1e-6, quality, median(latency) * 1e3, median(busy),
                                double(stolen) / o->frames, 100.0 * double(hits) / tiles);
                    std::fflush(stdout);
                }
                results.push_back(std::move(row));
            }
            if (o->json) {
                toml::table out{{"benchmark", "cluster"}, {"width", o->width}, {"height", o->height}, {"tile", o->tile},
                                {"frames", o->frames}, {"replay", !o->render}, {"link", o->link}, {"results", results}};
                std::cout << toml::json_formatter{out} << "\n";
            }
            return 0;
        };
    });
}

}  // namespace rtwall::cli
