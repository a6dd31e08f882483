// The benchmarks behind `rtwall bench ...`: one options struct and one function per benchmark.
// Each function runs the benchmark, writes its human-readable lines to `text` as it goes (none
// when `text` is null; `--json` makes it null) and returns its figures: the JSON that `--json`
// prints. Adding a benchmark: its options and function here, its work in a file of its own
// (tools/bench/NAME.cpp, listed in tools/CMakeLists.txt), and its command-line options in
// tools/rtwall/bench_NAME.cpp. Timing targets live here, never in tests.
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace rtwall::bench {

// What every benchmark's options have.
struct Common {
    std::FILE* text = stdout;  // human-readable lines as the benchmark goes; nullptr: none
};

// Primary-ray throughput: packet and single-ray kernels against a bare rtcIntersectK loop.
struct KernelOptions : Common {
    int width = 1600, height = 1200, threads = 0, rounds = 7, tile = 32, packetWidth = 0;
    int64_t triangles = 3'000'000;
    // Section planes (issue 20): this many, each keeping the whole scene (their clipping's own
    // cost), or with `cut` the first through the scene's centre (half of it cut away, capped).
    int sections = 0;
    bool cut = false;
};
toml::table kernel(const KernelOptions& o);

// The master and local clients over loopback, each setting varied around a base.
struct ClusterOptions : Common {
    int width = 1600, height = 1200, tile = 32, frames = 10, maxClients = 4;
    int64_t triangles = 200'000;
    bool render = false, insecure = false;
    // --depth (issue 27): each setting measured twice in one run, without and with depth with
    // every tile (ClusterSettings::depth), for what depth costs in bytes and frames per second.
    bool depth = false;
    // --features MODE,... (issue 28): the scene with GI (linear half-float tiles, as a stochastic
    // scene travels), each setting measured plain, then with depth and the features each denoise
    // mode reads (featureBitsFor), in one run: what the denoiser's features cost on the link.
    std::vector<std::string> features;
    std::string bind = "tcp://127.0.0.1:0", netns, link = "loopback", codec = "lz4";
    std::vector<int> clientCounts;
    // --display-nodes: walls split over these numbers of display-node processes instead
    // (cluster_nodes.cpp), each with every codec of nodeCodecs, maxClients clients.
    std::vector<int> displayNodes;
    std::vector<std::string> nodeCodecs = {"raw", "lz4"};
    std::vector<std::string> nodeAddresses;  // node i binds its tile socket here (default 127.0.0.1)
    std::string nodeNetns;                   // node i runs in network namespace <nodeNetns><i> (tools/netem.sh)
    double nodeLinkMbit = 0;                 // each node's link, for the link-bound frame rate (0: not known)
    int nodePrefetch = 8;
};
toml::table cluster(const ClusterOptions& o);
// The wall config of `bench cluster --display-nodes`: a grid of screens whose columns go to the
// nodes n1..nK in equal runs. InputError for a count the wall cannot be split into.
std::string nodeBenchWall(int width, int height, int nodes);

// The cost of a killed or frozen client, and of CURVE encryption.
struct FaultsOptions : Common {
    int clients = 3, frames = 5, timeoutMs = 400;
    std::string bind = "tcp://127.0.0.1:0", netns, link = "loopback";
};
toml::table faults(const FaultsOptions& o);

// The master under attack, with and without CURVE.
struct AttackOptions : Common {
    int clients = 2, rate = 5000;
    double seconds = 10;
    uint64_t seed = 1;
};
toml::table attack(const AttackOptions& o);

// Rendering while client processes are frozen, killed, restarted and cut off at random. The
// run went well when every frame completed bit-identical: see chaosPassed().
struct ChaosOptions : Common {
    int clients = 4, intervalMs = 300, maxMs = 1500, timeoutMs = 400, framesAfter = 10;
    double seconds = 30;
    uint64_t seed = 1;
    bool linkCuts = false;
};
toml::table chaos(const ChaosOptions& o);
bool chaosPassed(const toml::table& result);

// GL presenter frames/s and camera-to-display latency (needs a display).
struct DisplayOptions : Common {
    int frames = 60, trials = 8, width = 800, height = 600, clients = 2;
    int64_t triangles = 200'000;
};
toml::table display(const DisplayOptions& o);

// Import, cache, BVH build, memory and frame time of a scene file.
struct SceneOptions : Common {
    std::string scene, camera;
    int width = 1600, height = 1200, threads = 0, frames = 3;
    bool sweep = false, skipParse = false, otherPrimitives = true;
    std::string robust = "scene";  // "scene", "on" or "off"
};
toml::table scene(const SceneOptions& o);

// Shading demos: frame time and error as pruning, GI samples and the volume step vary.
struct ShadingOptions : Common {
    int width = 1600, height = 1200, rounds = 3, referenceFrames = 64, threads = 0;
    std::string dir = "out/bench-shading";
    std::vector<std::string> scenes{"office", "headlight", "sunflowers"};
    int64_t sunflowerPlants = 2000;  // the field is generated at this size (rtwall gen sunflowers --instances)
    int sunflowerTrees = 1;
    std::vector<float> thresholds{0.0005f, 0.002f, 0.01f, 0.05f};
    std::vector<int> giSamples{1, 2, 4, 8, 16};
    std::vector<float> volumeSteps{0.25f, 0.5f, 1.0f, 2.0f, 4.0f};
};
toml::table shading(const ShadingOptions& o);

// The master's cost of a camera update per frame, with N instances of one box.
struct UpdatesOptions : Common {
    int instances = 100'000, frames = 200, clients = 1;
    int transforms = 0;  // instances moved per frame as well (Master::setInstanceTransform)
    bool async = false;
    int moving = 0;  // > 0: part moves on one Scene (moving instances per change) instead
    bool movable = false;  // with moving: the movers are marked movable in the scene (InstanceDesc::movable)
};
toml::table updates(const UpdatesOptions& o);

// STEP tessellation: triangles, memory, import time and image error against a much finer
// tessellation, for every pair of linear and angular deflection (`rtwall gen step-curved`).
struct TessellationOptions : Common {
    std::string dir = "out/bench-tessellation";  // where the STEP assembly is written
    int64_t instances = 11;                      // part instances (one module: the parts fill the view)
    int width = 800, height = 600, supersample = 2, threads = 0, runs = 3;
    std::vector<double> linear{3.0, 1.0, 0.3, 0.1, 0.03, 0.01};  // file units (mm)
    std::vector<double> angular{1.0, 0.5, 0.25, 0.1};       // radians
    double referenceLinear = 0.002, referenceAngular = 0.05;
};
toml::table tessellation(const TessellationOptions& o);

// What tracing each calibrated projector pixel's ray gains over resampling a flat render
// through the warp (issue 30): one projector lights a cylindrical section of a fixed chord
// (3.2 x 2.4 m, the eye 2.5 m before it), its span the warp's strength; direct (rays through
// the warp; direct_ss2 with 2 x 2 samples a pixel), post and post_2x (a flat render of the
// projector's pixels, or of twice as many each way, resampled through the warp) against a
// supersampled direct render, by PSNR and FLIP, with each one's time.
struct WarpOptions : Common {
    std::string scene = "configs/demo.toml";
    int width = 400, height = 300, referenceSupersample = 4, threads = 0, runs = 3;
    std::vector<double> spans{0, 30, 60, 90, 120};  // degrees of arc; 0: the flat chord itself
};
toml::table warp(const WarpOptions& o);

// Motion-to-photon latency of a tracked wall (issue 18): DTrack datagram to the first presented
// frame made with it, and the head error at presentation, mono/stereo x async off/on x
// prediction off/on, at each image width (height = 3/4 of it), loopback client threads.
struct LatencyOptions : Common {
    std::string scene = "builtin:knots";
    std::vector<int> widths{320, 640, 960};
    int clients = 2, frames = 120, warmupFrames = 10;
    double rate = 120;            // tracker datagrams a second
    double targetSlackMs = 10;    // latency target: one frame time plus this (async off)
    double targetErrorMm = 5;     // prediction target at 0.5 m/s
    bool reproject = false;       // each configuration with re-projection off and on (issue 27)
    double refreshHz = 60;        // the display's refresh re-projecting (headless: paced by the wall)
    double reprojectSlackMs = 5;  // re-projecting target: one refresh plus this
    bool nodes = false;           // with reproject: also each configuration on two display nodes (threads), re-projecting
};
toml::table latency(const LatencyOptions& o);

// Image quality of re-projected frames (issue 27): a head stepping in front of a tracked wall
// (off-axis eye cameras) at each speed, a cluster rendering at each rate, a display at displayHz
// showing the newest complete frame warped to the head's pose at that moment (the frame before
// it fills holes) or as it is, scored (PSNR, FLIP) against a true render of that pose; guard
// bands; and the failure cases (thin geometry, mirror and glass, a large disocclusion) with an
// image each (reproject.cpp, reproject_quality.h).
struct ReprojectOptions : Common {
    std::vector<std::string> scenes{"demo", "plant"};  // "demo": the demo scene file; "plant": rtwall gen powerplant
    std::string demo = "configs/demo.toml";
    std::string dir = "out/bench-reproject";  // the plant is generated here
    std::string images;                       // the failure cases' images are written here (empty: dir)
    int width = 320, height = 240;            // the screen's pixels (a scale model of a wall's)
    double displayHz = 60, seconds = 1;       // displayed frames: seconds * displayHz per configuration
    std::vector<double> speeds{0.1, 0.25, 0.5, 1.0};  // head speed, m/s
    std::vector<double> renderFps{5, 14, 27};
    std::vector<double> guardBands{0.02, 0.05, 0.1};  // share of the width and height rendered beyond the screen
    int64_t plantTriangles = 200'000;
    uint64_t seed = 1;  // the render clocks' phases
    bool failureCases = true;
};
toml::table reprojection(const ReprojectOptions& o);

// What the denoiser buys (issue 28, denoise.cpp): PSNR, FLIP, frame rate and flicker of each
// setting on an orbiting and a still camera against converged references.
struct DenoiseOptions : Common {
    std::vector<std::string> scenes{"office"};  // office (rtwall gen office), demo (--demo, with GI), sunflowers (rtwall gen sunflowers)
    std::string dir = "out/bench-denoise";     // generated scenes go here
    std::string demo = "configs/demo.toml";
    std::string images;                        // the last scored frame of each setting as PNG here (empty: none)
    std::vector<std::string> sizes{"200x150", "640x480"};
    std::vector<std::string> modes{"off", "temporal", "svgf"};
    std::vector<int> giSpp{1, 4};
    int frames = 24;                 // frames of the orbit
    int scoreEvery = 4;              // every this many-th frame is scored
    double degreesPerFrame = 0.5;    // the orbit's speed
    int referenceSpp = 512;          // GI samples of a reference render of the moving path
    int stillReferenceSpp = 2048;    // of the still view's references (40 dB needs a reference far better)
    std::string camera;              // the scene's camera the orbit starts from (empty: its first)
    std::string tag;                 // the images' names: denoise_[TAG_]SCENE_WIDTH_MODE_SPPspp.png
    double stillSeconds = 4;         // the still camera refines at most this long
    int flickerFrames = 8;
    int threads = 0;                 // render and denoise threads (0: one per hardware thread)
    // The filter's controls over the scene's [denoise] (0: the scene's).
    int levels = 0, history = 0;
    double sigmaLuminance = 0, sigmaDepth = 0, sigmaNormal = 0;
};
toml::table denoise(const DenoiseOptions& o);

}  // namespace rtwall::bench
