// rtwall bench updates: options of the camera-update cost benchmark (tools/bench/updates.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchUpdates(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::UpdatesOptions>(bench, "updates", "Cost of a camera update per frame with many instances");
    cmd->add_option("--instances", o.instances, "Instances of one box in the scene")->check(CLI::Range(1, 10'000'000));
    cmd->add_option("--frames", o.frames, "Measured frames, each after one camera update")->check(CLI::Range(1, 100000));
    cmd->add_option("--clients", o.clients, "Local client processes (one render thread each)")->check(CLI::Range(1, 16));
    cmd->add_option("--transforms", o.transforms,
                    "Instance transforms moved per frame besides the camera (as a dragged object or a "
                    "flystick's pick does)")
        ->check(CLI::Range(0, 100000));
    cmd->add_option("--moving", o.moving,
                    "Part moves instead: this many instances dragged per change on one Scene; JSON commit_ms "
                    "{median, p95} per change, the background rebuild and bare Embree's whole top-level rebuild")
        ->check(CLI::Range(0, 100000));
    cmd->add_flag("--movable", o.movable,
                  "With --moving: the movers are marked movable in the scene (`movable = true`): in the moving top level "
                  "from the start, no static rebuild (static_rebuild_ms 0)");
    cmd->add_flag("--async", o.async, "Asynchronous frames (as rtwall run): the frame time overlaps the next one's begin");
    callBenchmark(cmd, run, a, bench::updates);
}

}  // namespace rtwall::cli
