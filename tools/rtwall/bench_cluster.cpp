// rtwall bench cluster: options of the loopback cluster benchmark (tools/bench/cluster.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchCluster(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::ClusterOptions>(bench, "cluster", "Frames/s, bytes, stealing and busy time of master and local clients");
    addSizeOptions(cmd, o.width, o.height, 16, 16384);
    cmd->add_option("--tile", o.tile, "Tile size")->check(CLI::Range(4, 1024));
    cmd->add_option("--frames", o.frames, "Measured frames per setting (medians are reported)")->check(CLI::Range(1, 10000));
    cmd->add_option("--max-clients", o.maxClients, "Largest client count in the sweep (1, 2, 4, ... up to it)")->check(CLI::Range(1, 256));
    addTrianglesOption(cmd, o.triangles, "Triangles of the built-in scene");
    cmd->add_flag("--render", o.render, "Clients really render every tile (default: replay pre-encoded tiles)");
    cmd->add_flag("--depth", o.depth, "Each setting without and with depth with every tile, in one run (issue 27)");
    cmd->add_option("--features", o.features,
                    "The scene with GI; each setting plain, then with depth and the features of each of these denoise modes "
                    "(temporal, svgf), in one run (issue 28)")
        ->delimiter(',')
        ->check(CLI::IsMember({"temporal", "svgf"}));
    addNetemOptions(cmd, o.bind, o.netns, o.link, "Master endpoint (tools/netem.sh binds inside its namespaces)",
                    "Start client i in network namespace <prefix><i> (tools/netem.sh)");
    cmd->add_flag("--insecure", o.insecure, "Allow a non-loopback --bind without CURVE keys (tools/netem.sh namespaces)");
    cmd->add_option("--client-counts", o.clientCounts,
                    "Only these client counts (prefetch 4, LZ4, affinity on), e.g. 1,2,3,4: the simulation's validation")
        ->delimiter(',')
        ->check(CLI::Range(1, 256));
    cmd->add_option("--codec", o.codec, "Codec of the --client-counts runs")->check(CLI::IsMember({"raw", "lz4", "zstd", "jpeg"}));
    cmd->add_option("--display-nodes", o.displayNodes,
                    "Walls split over these numbers of display-node processes, e.g. 1,2,4 (issue 19; frames paced by the swap)")
        ->delimiter(',')
        ->check(CLI::Range(1, 64));
    cmd->add_option("--node-codecs", o.nodeCodecs, "Codecs of the --display-nodes runs (default raw,lz4)")
        ->delimiter(',')
        ->check(CLI::IsMember({"raw", "lz4", "zstd", "jpeg"}));
    cmd->add_option("--node-addresses", o.nodeAddresses, "Address node i binds its tile socket to (default 127.0.0.1 for all)")
        ->delimiter(',');
    cmd->add_option("--node-netns", o.nodeNetns, "Start display node i in network namespace <prefix><i> (tools/netem.sh)");
    cmd->add_option("--node-link-mbit", o.nodeLinkMbit, "Each node's link in Mbit/s: reports the link-bound frame rate")
        ->check(CLI::Range(0.0, 1e7));
    cmd->add_option("--node-prefetch", o.nodePrefetch, "Prefetch of the --display-nodes runs")->check(CLI::Range(1, 64));
    callBenchmark(cmd, run, a, bench::cluster);
}

}  // namespace rtwall::cli
