// rtwall bench shading: options of the shading-demo benchmark (tools/bench/shading.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchShading(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::ShadingOptions>(bench, "shading", "Shading demos: frame time and PSNR vs pruning, GI samples, volume step");
    cmd->add_flag("--json", a->json, "Print JSON");
    addSizeOptions(cmd, o.width, o.height, 16, 8192);
    cmd->add_option("--rounds", o.rounds, "Frames timed per point (median)")->check(CLI::Range(1, 100));
    cmd->add_option("--reference-frames", o.referenceFrames, "Frames averaged for the GI reference")->check(CLI::Range(1, 100000));
    addThreadsOption(cmd, o.threads, "Render threads (0 = all)");
    cmd->add_option("--dir", o.dir, "Where the demo scenes are written");
    cmd->add_option("--scenes", o.scenes, "Scenes to run (office, headlight, sunflowers)")
        ->check(CLI::IsMember({"office", "headlight", "sunflowers"}))
        ->delimiter(',');
    cmd->add_option("--sunflower-plants", o.sunflowerPlants, "Plants in the generated sunflower field")
        ->check(CLI::Range(int64_t(1), int64_t(10'000'000)));
    cmd->add_option("--sunflower-trees", o.sunflowerTrees, "Large trees in the generated sunflower field")
        ->check(CLI::Range(0, 64));
    cmd->add_option("--thresholds", o.thresholds, "Pruning thresholds to measure")
        ->check(CLI::Range(0.0f, 1.0f))
        ->delimiter(',');
    cmd->add_option("--gi-samples", o.giSamples, "GI samples per pixel to measure (office, sunflowers)")
        ->check(CLI::Range(1, 4096))
        ->delimiter(',');
    cmd->add_option("--volume-steps", o.volumeSteps, "Volume steps in voxels to measure (office)")
        ->check(CLI::Range(0.01f, 64.0f))
        ->delimiter(',');
    callBenchmark(cmd, run, a, bench::shading, {}, false);  // --json is added above, first in --help
}

}  // namespace rtwall::cli
