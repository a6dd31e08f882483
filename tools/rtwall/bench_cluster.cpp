// rtwall bench cluster: the master and its clients on this PC over loopback. Each setting is
// varied on its own around a base (2 clients, prefetch 4, LZ4, affinity on): client count,
// prefetch depth, codec, affinity. With --replay (the default) clients render each tile once
// and then resend its bytes, so the figures measure the master and the link, not the CPUs.
#include "commands.h"
#include "local_clients.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
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

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

void addBenchCluster(CLI::App& bench, Run& run) {
    struct Options {
        int width = 1600, height = 1200, tile = 32, frames = 10, maxClients = 4;
        int64_t triangles = 200'000;
        bool json = false, render = false, insecure = false;
        std::string bind = "tcp://127.0.0.1:0", netns, link = "loopback";
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
                for (int c : o->clientCounts) points.push_back({"clients", c, 4, TileCodec::Lz4, true});
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
                auto last = std::chrono::steady_clock::now();
                for (int f = 0; f < o->frames; ++f) {
                    FrameReport r;
                    const Image img = master.renderFrame(&r);
                    if (f == 0) quality = psnr(img);
                    const auto now = std::chrono::steady_clock::now();
                    times.push_back(std::chrono::duration<double>(now - last).count());
                    last = now;
                    bytes.push_back(double(r.bytes));
                    latency.push_back(r.meanTileLatency);
                    stolen += r.tilesStolen;
                    hits += r.affinityHits;
                    for (const ClientReport& c : r.clients) busy.push_back(c.busyFraction);
                }
                const double tiles = double(makeTiles(o->width, o->height, o->tile).size()) * o->frames;
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
                                {"psnr_db", quality}};
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
