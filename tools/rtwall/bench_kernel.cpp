// rtwall bench kernel: options of the primary-ray benchmark (tools/bench/kernel.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchKernel(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::KernelOptions>(bench, "kernel", "Primary-ray Mrays/s: packet kernel, single kernel, bare Embree loop");
    addSizeOptions(cmd, o.width, o.height, 16, 16384);
    addTrianglesOption(cmd, o.triangles, "Unique triangles in the benchmark scene", 200'000'000);
    addThreadsOption(cmd, o.threads, "Threads (0 = one per hardware thread)");
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
