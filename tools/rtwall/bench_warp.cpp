// rtwall bench warp: options of the calibrated-projector benchmark (tools/bench/warp.cpp, issue 30).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchWarp(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::WarpOptions>(
        bench, "warp", "Curved screen: per-pixel rays through the warp against resampling a flat render (PSNR, FLIP, time)");
    cmd->add_flag("--json", a->json, "Print JSON");
    cmd->add_option("--scene", o.scene, "Scene file or mesh");
    addSizeOptions(cmd, o.width, o.height, 16, 8192);
    cmd->add_option("--reference-supersample", o.referenceSupersample, "The reference's n x n samples per pixel")->check(CLI::Range(2, 16));
    cmd->add_option("--spans", o.spans, "Arcs of the cylindrical screen, degrees (0: flat)")->check(CLI::Range(0.0, 170.0))->delimiter(',');
    addThreadsOption(cmd, o.threads, "Render threads (0 = all)");
    cmd->add_option("--runs", o.runs, "Timed runs per method (median)")->check(CLI::Range(1, 100));
    callBenchmark(cmd, run, a, bench::warp, {}, false);  // --json is added above, first in --help
}

}  // namespace rtwall::cli
