// rtwall bench display: options of the presenter and latency benchmark (tools/bench/display.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchDisplay(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::DisplayOptions>(bench, "display", "Presenter frames/s (upload methods, 1600x1200 and 4K) and camera-to-display latency");
    cmd->add_option("--frames", o.frames, "Frames per presenter measurement")->check(CLI::Range(5, 100000));
    cmd->add_option("--trials", o.trials, "Camera changes per latency measurement (median reported)")->check(CLI::Range(1, 1000));
    addSizeOptions(cmd, o.width, o.height, 16, 16384, "Image", " of the latency runs");
    cmd->add_option("--clients", o.clients, "Local clients of the latency runs")->check(CLI::Range(1, 64));
    addTrianglesOption(cmd, o.triangles, "Triangles of the built-in scene");
    callBenchmark(cmd, run, a, bench::display);
}

}  // namespace rtwall::cli
