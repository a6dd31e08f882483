// Speed against accuracy (issue #8): the options of the commands that measure both sides
// (rtwall compare, reference, bench tiles, bench codecs, simulate); tools/bench/speed.h does the work.
#include "bench_cli.h"

#include <speed.h>

#include <rtwall/wall.h>

#include <algorithm>
#include <initializer_list>
#include <string>

namespace rtwall::cli {

namespace {

// The controls named in `only` (rtwall/wall.h's table) as options of a command: a value given
// overrides the scene's.
void addControlOptions(CLI::App* cmd, bench::ControlValues& values, std::initializer_list<std::string> only) {
    for (const Control& c : controls())
        if (*c.option && std::find(only.begin(), only.end(), c.name) != only.end())
            cmd->add_option(c.option, values.given[c.name], std::string(c.help) + " (overrides the scene)")->check(CLI::Range(c.min, c.max));
}

}  // namespace

void addCompare(CLI::App& app, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::CompareOptions>(app, "compare", "Error of an image against a reference: RMSE, PSNR, SSIM, largest error");
    cmd->add_option("image", o.test, "The image to judge (PNG)")->required();
    cmd->add_option("reference", o.reference, "The reference (PNG, same size)")->required();
    cmd->add_option("--diff", o.diff, "Write a false-colour difference image (PNG)");
    cmd->add_option("--diff-scale", o.scale, "Error in levels shown as full red (default: the largest error)")
        ->check(CLI::Range(1, 255));
    callBenchmark(cmd, run, a, bench::compare);
}

void addReference(CLI::App& app, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::ReferenceOptions>(app, 
        "reference", "Render a converged reference image: many samples per pixel, on this PC (lossless, no cluster)");
    cmd->add_option("scene", o.scene, "Scene file (.toml), mesh file or builtin:NAME")->required();
    cmd->add_option("--out,-o", o.out, "Output PNG")->required();
    addSizeOptions(cmd, o.width, o.height, 1, 16384, "Image", " (overrides the scene)");
    cmd->add_option("--camera", o.camera, "Scene camera (default: the first)");
    addControlOptions(cmd, o.controls, {"supersample", "prune", "gi_spp", "volume_step"});  // supersample: 8 x 8 unless given
    addTrianglesOption(cmd, o.triangles, "Triangles of a builtin scene");
    cmd->add_option("--frames", o.frames,
                    "Average this many frames in linear light (path tracing jitters samples per frame; an even count "
                    "also reports the error between its two halves, an estimate of the reference's own error)")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--first-frame", o.firstFrame, "Frame number of the first frame (seeds its random numbers)");
    cmd->add_option("--progress-out", o.progressOut,
                    "Also write the mean of the first 1, 2, 4, 8, ... frames to PREFIX-N.png (progressive refinement)");
    callBenchmark(cmd, run, a, bench::reference);
}

void addBenchTiles(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::TilesOptions>(bench, 
        "tiles", "Per-tile render, encode and decode times (a tile profile for 'rtwall simulate') and each codec's error");
    cmd->add_option("scene", o.scene, "Scene file (.toml), mesh file or builtin:NAME")->required();
    addSizeOptions(cmd, o.width, o.height, 16, 16384, "Wall image", " (overrides the scene)");
    addControlOptions(cmd, o.controls, {"scale", "tile", "supersample", "prune", "gi_spp", "volume_step", "denoise"});  // scale: upscaled for the error
    cmd->add_option("--denoise-frames", o.denoiseFrames,
                    "With --denoise: frames of the orbit that arrives at the scored view (the filter's history)")
        ->check(CLI::Range(1, 10000));
    cmd->add_option("--denoise-orbit", o.denoiseDegrees, "With --denoise: its degrees per frame")->check(CLI::Range(-90.0, 90.0));
    cmd->add_option("--shading", o.shading, "full or eyelight (overrides the scene)")->check(CLI::IsMember({"full", "eyelight"}));
    cmd->add_option("--camera", o.camera, "Scene camera (default: the first)");
    cmd->add_option("--frames", o.frames, "Frames to time, the camera orbiting --orbit degrees per frame")->check(CLI::Range(1, 1000));
    cmd->add_option("--orbit", o.orbitDegrees, "Degrees per frame around the camera's look-at point")->check(CLI::Range(-360.0, 360.0));
    cmd->add_option("--codecs", o.codecs, "Comma-separated codecs: raw, lz4, zstd[:LEVEL], jpeg[:QUALITY]");
    cmd->add_option("--reference", o.reference, "Reference PNG at the wall's resolution (rtwall reference): errors are reported");
    cmd->add_option("--profile-out", o.profileOut, "Write the tile profile (TOML) for 'rtwall simulate'");
    cmd->add_option("--save-image", o.saveImage, "Write frame 0 as rendered (lossless, at the render resolution)");
    addTrianglesOption(cmd, o.triangles, "Triangles of a builtin scene");
    callBenchmark(cmd, run, a, bench::tiles);
}

void addBenchCodecs(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::CodecsOptions>(bench, "codecs", "Size and error of any image (PNG) through each tile codec");
    cmd->add_option("image", o.image, "The image (PNG)")->required();
    cmd->add_option("--codecs", o.codecs, "Comma-separated codecs: raw, lz4, zstd[:LEVEL], jpeg[:QUALITY]");
    cmd->add_option("--tile", o.tile, "Tile size")->check(CLI::Range(4, 1024));
    cmd->add_option("--diff-dir", o.diffDir, "Write each codec's decoded image and false-colour difference here");
    callBenchmark(cmd, run, a, bench::codecs);
}

void addSimulate(CLI::App& app, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::SimulateOptions>(app, "simulate", "Frames/s, utilisation and link load of N clients: the real tile scheduler "
                                                   "against simulated clients and links, fed with a tile profile");
    cmd->add_option("--profile", o.profile, "Tile profile (rtwall bench tiles --profile-out)")->required();
    cmd->add_option("--codec", o.codec, "Which of the profile's codecs, e.g. lz4 or jpeg:75 (default: the first)");
    cmd->add_option("--clients", o.clients, "Comma-separated client counts");
    cmd->add_option("--threads", o.threads, "Render threads per client")->check(CLI::Range(1, 1024));
    cmd->add_option("--client-speed", o.clientSpeed, "Client speed relative to the PC that recorded the profile")->check(CLI::Range(0.001, 1000.0));
    cmd->add_option("--prefetch", o.prefetch, "Tiles each client keeps in flight")->check(CLI::Range(1, 64));
    cmd->add_flag("--no-affinity", o.noAffinity, "Tiles start in the shared queue every frame");
    cmd->add_option("--straggler-factor", o.straggler, "Re-issue tiles outstanding this many median latencies")->check(CLI::Range(1.0, 1000.0));
    cmd->add_option("--client-link", o.clientLink, "Each client's link: 100mbit, 1gbit, 10gbit, unlimited");
    cmd->add_option("--master-link", o.masterLink, "The master's uplink, shared by all results");
    cmd->add_option("--latency-ms", o.latencyMs, "One-way latency of every link")->check(CLI::Range(0.0, 10000.0));
    cmd->add_option("--spike-probability", o.spikeProb, "Chance that a message is delayed by --spike-ms")->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--spike-ms", o.spikeMs, "Extra delay of a spiking message")->check(CLI::Range(0.0, 100000.0));
    cmd->add_option("--master-us-per-message", o.masterUs, "Master network thread's cost per message (µs)")->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--decode-threads", o.decodeThreads, "Master decode threads")->check(CLI::Range(1, 1024));
    cmd->add_option("--decode-speed", o.decodeSpeed, "Master decode speed relative to the recording PC")->check(CLI::Range(0.001, 1000.0));
    cmd->add_option("--overhead-bytes", o.overhead, "Protocol bytes per result message")->check(CLI::Range(0, 100000));
    cmd->add_option("--host-cores", o.hostCores,
                    "Clients and master share this many cores (local clients on one PC); 0: each has its own")
        ->check(CLI::Range(0.0, 100000.0));
    cmd->add_option("--host-load", o.hostLoad, "With --host-cores: other jobs' runnable threads on those cores")
        ->check(CLI::Range(0.0, 100000.0));
    // Host costs besides rendering, from `rtwall bench cluster --json` (cpu_per_frame); see
    // docs/speed-accuracy.md, Validation, for how they are measured and calibrated.
    cmd->add_option("--client-us-per-result", o.clientUsPerResult,
                    "A client's CPU per result outside its render threads (network, ZeroMQ, kernel TCP), µs")
        ->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--client-ns-per-byte", o.clientNsPerByte, "... and per result byte, ns")->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--master-us-per-result", o.masterUsPerResult,
                    "The master's CPU per result before its network thread (ZeroMQ I/O thread, kernel TCP), µs")
        ->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--master-ns-per-byte", o.masterNsPerByte, "... and per result byte, ns")->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--master-ms-per-frame", o.masterMsPerFrame, "The master's CPU per frame after the last decode, ms")
        ->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--frames", o.frames, "Simulated frames per client count (after one warm-up frame)")->check(CLI::Range(1, 100000));
    cmd->add_option("--seed", o.seed, "Seed for latency spikes and steal victims");
    cmd->add_option("--display-nodes", o.displayNodes,
                    "A wall on this many display nodes, each driving an equal run of columns (0: the master takes the pixels)")
        ->check(CLI::Range(0, 64));
    cmd->add_option("--node-link", o.nodeLink, "With --display-nodes: each node's link");
    cmd->add_option("--node-decode-threads", o.nodeDecodeThreads, "With --display-nodes: decode threads per node")
        ->check(CLI::Range(1, 1024));
    callBenchmark(cmd, run, a, bench::simulate);
}

}  // namespace rtwall::cli
