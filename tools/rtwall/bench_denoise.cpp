// rtwall bench denoise: options of the denoiser's benchmark (tools/bench/denoise.cpp, issue 28).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchDenoise(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::DenoiseOptions>(bench,
        "denoise", "Denoising of GI frames: PSNR, FLIP, frame rate and flicker of each setting on an orbiting and a still "
                   "camera against converged references");
    cmd->add_option("--scenes", o.scenes, "Scenes, comma-separated: office, demo (the demo scene file, with GI), sunflowers")
        ->delimiter(',')
        ->check(CLI::IsMember({"office", "demo", "sunflowers"}));
    cmd->add_option("--dir", o.dir, "Where the scenes are generated");
    cmd->add_option("--demo", o.demo, "The demo scene file");
    cmd->add_option("--images", o.images, "Write each setting's last scored frame and its reference here (PNG)");
    cmd->add_option("--sizes", o.sizes, "Image sizes WIDTHxHEIGHT, comma-separated")->delimiter(',');
    cmd->add_option("--modes", o.modes, "Denoise settings, comma-separated")->delimiter(',')->check(CLI::IsMember({"off", "temporal", "svgf"}));
    cmd->add_option("--gi-spp", o.giSpp, "GI samples per pixel and frame, comma-separated")->delimiter(',')->check(CLI::Range(1, 4096));
    cmd->add_option("--frames", o.frames, "Frames of the orbit")->check(CLI::Range(1, 100000));
    cmd->add_option("--score-every", o.scoreEvery, "Score every this many-th frame")->check(CLI::Range(1, 100000));
    cmd->add_option("--degrees-per-frame", o.degreesPerFrame, "Orbit speed")->check(CLI::Range(0.0, 90.0));
    cmd->add_option("--reference-spp", o.referenceSpp, "GI samples per pixel of the moving path's references")->check(CLI::Range(1, 65536));
    cmd->add_option("--still-reference-spp", o.stillReferenceSpp, "GI samples per pixel of the still view's two references")
        ->check(CLI::Range(1, 65536));
    cmd->add_option("--tag", o.tag, "A word in the images' names (denoise_TAG_SCENE_...)");
    cmd->add_option("--camera", o.camera, "The scene camera the orbit starts from (default: the first)");
    cmd->add_option("--still-seconds", o.stillSeconds, "Longest refinement of the still camera")->check(CLI::Range(0.0, 3600.0));
    cmd->add_option("--flicker-frames", o.flickerFrames, "Still frames the flicker is measured over")->check(CLI::Range(1, 10000));
    cmd->add_option("--levels", o.levels, "A-trous levels (over the scene's [denoise])")->check(CLI::Range(1, 10));
    cmd->add_option("--history", o.history, "Longest history of a moving view, frames")->check(CLI::Range(1, 65536));
    cmd->add_option("--sigma-luminance", o.sigmaLuminance, "Luminance edge stop")->check(CLI::Range(1e-6, 1e6));
    cmd->add_option("--sigma-depth", o.sigmaDepth, "Depth edge stop")->check(CLI::Range(1e-6, 1e6));
    cmd->add_option("--sigma-normal", o.sigmaNormal, "Normal edge stop (exponent)")->check(CLI::Range(0.0, 1e6));
    addThreadsOption(cmd, o.threads, "Render and denoise threads (0: one per hardware thread)");
    callBenchmark(cmd, run, a, bench::denoise);
}

}  // namespace rtwall::cli
