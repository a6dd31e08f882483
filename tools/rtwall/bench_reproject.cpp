// rtwall bench reproject: options of the re-projection image quality benchmark
// (tools/bench/reproject.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchReproject(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::ReprojectOptions>(bench,
        "reproject", "Image quality of re-projected frames: PSNR and FLIP against true renders, head speed x render rate, "
                     "guard bands, failure cases");
    cmd->add_option("--scenes", o.scenes, "Scenes, comma-separated: demo (the demo scene file), plant (rtwall gen powerplant)")
        ->delimiter(',')
        ->check(CLI::IsMember({"demo", "plant"}));
    cmd->add_option("--demo", o.demo, "The demo scene file");
    cmd->add_option("--dir", o.dir, "Where the plant is generated");
    cmd->add_option("--images", o.images, "Where the failure cases' images are written (reprojection_CASE.png; default: --dir)");
    addSizeOptions(cmd, o.width, o.height, 16, 4096, "Screen");
    cmd->add_option("--display-hz", o.displayHz, "Display refresh rate")->check(CLI::Range(1.0, 1000.0));
    cmd->add_option("--seconds", o.seconds, "Displayed seconds per configuration")->check(CLI::Range(0.05, 600.0));
    cmd->add_option("--speeds", o.speeds, "Head speeds in m/s, comma-separated")->delimiter(',')->check(CLI::Range(0.0, 10.0));
    cmd->add_option("--render-fps", o.renderFps, "Render rates in frames/s, comma-separated")
        ->delimiter(',')
        ->check(CLI::Range(0.5, 1000.0));
    cmd->add_option("--guard-bands", o.guardBands, "Guard bands: share of the width and height rendered beyond the screen, "
                                                   "comma-separated (none: --guard-bands 0)")
        ->delimiter(',')
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--plant-triangles", o.plantTriangles, "Triangles of the generated plant")
        ->check(CLI::Range(int64_t(1000), int64_t(100'000'000)));
    cmd->add_option("--seed", o.seed, "Seed of the render clocks' phases against the display's");
    cmd->add_flag("!--no-failure-cases", o.failureCases, "Skip the failure cases and their images");
    callBenchmark(cmd, run, a, bench::reprojection);
}

}  // namespace rtwall::cli
