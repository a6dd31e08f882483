// rtwall bench latency: options of the motion-to-photon benchmark (tools/bench/latency.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchLatency(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::LatencyOptions>(bench, 
        "latency", "Tracker datagram to presented frame, and the predicted head's error at 0.5 m/s (mono/stereo, async, prediction)");
    cmd->add_option("--scene", o.scene, "Scene to render");
    cmd->add_option("--widths", o.widths, "Wall image widths, comma-separated (height = 3/4): one frame rate each")
        ->delimiter(',')
        ->check(CLI::Range(32, 8192));
    cmd->add_option("--clients", o.clients, "Local client threads (one render thread each)")->check(CLI::Range(1, 64));
    cmd->add_option("--frames", o.frames, "Measured frames per configuration")->check(CLI::Range(5, 100000));
    cmd->add_option("--warmup", o.warmupFrames, "Frames before measuring")->check(CLI::Range(0, 10000));
    cmd->add_option("--rate", o.rate, "Tracker datagrams per second")->check(CLI::Range(1.0, 2000.0));
    cmd->add_flag("--reproject", o.reproject,
                  "Each configuration with re-projection off and on (the display at --refresh-hz, never waiting for the cluster)");
    cmd->add_flag("--nodes", o.nodes,
                  "With --reproject: also each configuration on two display nodes (threads here) warping their own screens")
        ->needs("--reproject");
    cmd->add_option("--refresh-hz", o.refreshHz, "The display's refresh rate re-projecting")->check(CLI::Range(1.0, 1000.0));
    callBenchmark(cmd, run, a, bench::latency);
}

}  // namespace rtwall::cli
