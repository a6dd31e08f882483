// rtwall bench kernel: options of the primary-ray benchmark (tools/bench/kernel.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchKernel(CLI::App& bench, Run& run) {
    auto a = std::make_shared<BenchArgs<bench::KernelOptions>>();
    bench::KernelOptions& o = a->options;
    CLI::App* cmd = bench.add_subcommand("kernel", "Primary-ray Mrays/s: packet kernel, single kernel, bare Embree loop");
    cmd->add_option("--width", o.width, "Image width")->check(CLI::Range(16, 16384));
    cmd->add_option("--height", o.height, "Image height")->check(CLI::Range(16, 16384));
    cmd->add_option("--triangles", o.triangles, "Unique triangles in the benchmark scene")->check(CLI::Range(int64_t(1000), int64_t(200'000'000)));
    cmd->add_option("--threads", o.threads, "Threads (0 = one per hardware thread)")->check(CLI::Range(0, 1024));
    cmd->add_option("--rounds", o.rounds, "Interleaved rounds; medians are reported")->check(CLI::Range(1, 1000));
    cmd->add_option("--tile", o.tile, "Tile size")->check(CLI::Range(2, 1024));
    cmd->add_option("--packet-width", o.packetWidth, "Rays per packet, kernel and bare loop (0 = this CPU's widest)")
        ->check(CLI::IsMember({0, 4, 8, 16}));
    cmd->add_option("--sections", o.sections, "Section planes that keep the whole scene (their clipping's cost)")
        ->check(CLI::Range(0, 6));  // kMaxSections
    cmd->add_flag("--cut", o.cut, "With --sections: the first plane cuts the scene in half (with a cap)");
    callBenchmark(cmd, run, a, bench::kernel);
}

}  // namespace rtwall::cli
