// rtwall bench scene SCENE: options of the big-scene benchmark (tools/bench/scene.cpp).
#include "bench_cli.h"

#include <bench.h>
#include <progress.h>

namespace rtwall::cli {

void addBenchScene(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::SceneOptions>(bench, "scene", "Import, cache, BVH build, memory and frame time of a scene file");
    cmd->add_option("scene", o.scene, "Scene file (.toml)")->required();
    cmd->add_option("--camera", o.camera, "Camera (default: the first)");
    addSizeOptions(cmd, o.width, o.height, 16, 16384);
    addThreadsOption(cmd, o.threads, "Render threads (0 = one per hardware thread)");
    cmd->add_option("--frames", o.frames, "Frames per setting; the median is reported")->check(CLI::Range(1, 100));
    cmd->add_flag("--sweep", o.sweep, "Also build and render with every BVH quality, compact off and on");
    cmd->add_flag("--skip-parse", o.skipParse, "Do not time a load without caches");
    cmd->add_flag("!--no-other-primitives", o.otherPrimitives,
                  "Do not also build and render with the other [bvh] primitives (auto/triangles)");
    cmd->add_option("--robust", o.robust, "Robust traversal: as the scene file says, or on/off for every row")
        ->check(CLI::IsMember({"scene", "on", "off"}));
    callBenchmark(cmd, run, a, [](const bench::SceneOptions& options) {
        bench::installInterruptHandler();  // Ctrl-C stops the import or the BVH build at its next progress report
        return bench::scene(options);
    });
}

}  // namespace rtwall::cli
