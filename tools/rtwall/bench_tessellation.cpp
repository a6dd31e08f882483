// rtwall bench tessellation: options of the STEP tessellation benchmark (tools/bench/tessellation.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchTessellation(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::TessellationOptions>(bench, 
        "tessellation", "STEP tessellation: triangles, memory, import time and image error against a finer tessellation");
    cmd->add_flag("--json", a->json, "Print JSON");
    cmd->add_option("--dir", o.dir, "Where the STEP assembly (rtwall gen step-curved) is written");
    cmd->add_option("--instances", o.instances, "Part instances of the assembly")->check(CLI::Range(int64_t(1), int64_t(1'000'000)));
    cmd->add_option("--linear", o.linear, "Linear deflections to measure (file units)")->check(CLI::Range(1e-5, 1e3))->delimiter(',');
    cmd->add_option("--angular", o.angular, "Angular deflections to measure (radians)")->check(CLI::Range(1e-3, 3.0))->delimiter(',');
    cmd->add_option("--reference-linear", o.referenceLinear, "The reference's linear deflection")->check(CLI::Range(1e-5, 1e3));
    cmd->add_option("--reference-angular", o.referenceAngular, "The reference's angular deflection")->check(CLI::Range(1e-3, 3.0));
    addSizeOptions(cmd, o.width, o.height, 16, 8192);
    cmd->add_option("--supersample", o.supersample, "n x n samples per pixel")->check(CLI::Range(1, 16));
    addThreadsOption(cmd, o.threads, "Render threads (0 = all)");
    cmd->add_option("--runs", o.runs, "Cold imports per setting (median)")->check(CLI::Range(1, 100));
    callBenchmark(cmd, run, a, bench::tessellation, {}, false);  // --json is added above, first in --help
}

}  // namespace rtwall::cli
