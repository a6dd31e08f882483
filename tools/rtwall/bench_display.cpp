// rtwall bench display: options of the presenter and latency benchmark (tools/bench/display.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchDisplay(CLI::App& bench, Run& run) {
    auto a = std::make_shared<BenchArgs<bench::DisplayOptions>>();
    bench::DisplayOptions& o = a->options;
    CLI::App* cmd = bench.add_subcommand("display", "Presenter frames/s (upload methods, 1600x1200 and 4K) and camera-to-display latency");
    cmd->add_option("--frames", o.frames, "Frames per presenter measurement")->check(CLI::Range(5, 100000));
    cmd->add_option("--trials", o.trials, "Camera changes per latency measurement (median reported)")->check(CLI::Range(1, 1000));
    cmd->add_option("--width", o.width, "Image width of the latency runs")->check(CLI::Range(16, 16384));
    cmd->add_option("--height", o.height, "Image height of the latency runs")->check(CLI::Range(16, 16384));
    cmd->add_option("--clients", o.clients, "Local clients of the latency runs")->check(CLI::Range(1, 64));
    cmd->add_option("--triangles", o.triangles, "Triangles of the built-in scene")->check(CLI::Range(int64_t(1000), int64_t(100'000'000)));
    callBenchmark(cmd, run, a, bench::display);
}

}  // namespace rtwall::cli
