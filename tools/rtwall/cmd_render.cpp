// rtwall render: one frame (or the mean of frames 1..N) of a scene to PNG, on this PC or through
// a master and local client processes (the wall's session, rtwall/wall.h). Option values are
// read in render_args.cpp.
#include "commands.h"
#include "render_args.h"

#include <rtwall/denoise.h>

#include <progress.h>
#include <tile_failure.h>

#include <rtwall/cluster.h>
#include <rtwall/engine.h>
#include <rtwall/frame.h>
#include <rtwall/wall.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

namespace rtwall::cli {

void applyDenoiseIsa(const std::string& isa) {
    if (!isa.empty()) setDenoiseIsa(denoiseIsaFromName(isa));
}


namespace {

using bench::withReplay;

// The cluster path: the wall's session (rtwall/wall.h) with local client processes, headless,
// frames 1..N of a still view, averaged as one machine averages them (the same bytes).
Image renderWithClients(SceneDesc desc, const CameraDesc& camera, const RenderOptions& o, FrameReport& report) {
    desc.cameras = {camera};
    RunConfig c;
    c.scene = o.scene;
    ClusterSettings& cs = c.cluster;
    cs.localClients = o.clients;
    cs.threadsPerClient = desc.settings.threads > 0 ? std::max(1, desc.settings.threads / o.clients) : 1;
    cs.prefetch = o.prefetch;
    cs.async = false;
    cs.codec.codec = tileCodecFromName(o.codec);
    // Frames that are averaged travel as linear half-float tiles, to be averaged in linear light
    // as the single-machine path below does; one frame comes as 8-bit tiles, the bytes
    // renderFrame gives (a linear tile would be rounded to half precision first).
    cs.wideAccumulation = o.frames > 1 || (desc.denoise.mode != DenoiseSettings::Mode::Off && rendersStochastically(desc));
    c.loaded = std::move(desc);
    c.frames = o.frames;
    c.framesGiven = true;
    c.orbit = 0.0;
    c.writeEvery = 0;
    c.headless = true;
    c.log = [](const std::string& line) {
        if (line.starts_with("only ")) std::printf("%s\n", line.c_str());  // a client that did not join
    };
    WallSession session(c);
    while (session.step()) {
    }
    report = session.lastReport();
    if (const MasterCounters m = session.summary().counters; m.dropped() + m.failedSends + m.lostHandOuts + m.clientsDropped > 0)
        std::printf("master: %s\n", describeCounters(m).c_str());
    // A stochastic scene's frames are averaged while the view stays (the progressive mean); a
    // deterministic scene's are every one the same image.
    return session.lastFrame().left;
}

// Scene files may name gigabytes of meshes: a progress bar on a terminal, and Ctrl-C stops.
SceneDesc loadWithProgress(const std::string& scene, const RenderOptions& o) {
    std::optional<bench::ProgressBar> bar;
    SceneLoadOptions lo;
    lo.builtinTriangles = o.triangles;
    lo.linearDeflection = o.deflection;
    lo.angularDeflection = o.angularDeflection;
    if (o.cache) lo.cache = true;
    if (sceneSourceKind(scene) == SceneSourceKind::SceneFile) lo.progress = bar.emplace("loading", 1, "").fn();
    else if (isAssemblyFile(scene)) lo.progress = bar.emplace("importing", 1, "").fn();
    return loadScene(scene, lo);
}

// Frames firstFrame.. on this PC: one, the mean of o.frames, or the pixels of --region alone.
Image renderHere(const Scene& scene, const Camera& camera, const SceneDesc& desc, const CameraDesc& cam,
                 const RenderOptions& o, const TraceOptions& trace, TileStats& stats) {
    const RenderSettings& s = desc.settings;
    // The cluster numbers its frames from 1; so do we, so both give the same bytes.
    const uint32_t firstFrame = o.frame >= 0 ? uint32_t(o.frame) : 1;
    Image img;
    try {
        if (!o.region.empty() && o.frames > 1) throw InputError("--region renders one frame: give it --frame, not --frames");
        if (o.region.empty()) {
            // The frames' mean is the wall's (the one Compositor): in linear light, before the
            // 8-bit quantisation clips each at 1.0 (a GI sample far above 1 would lose its
            // excess in every frame), at the half precision the cluster sends them in. A
            // deterministic scene renders the same image every frame: its 8-bit mean is it.
            // Denoised ([denoise] or --denoise, a stochastic scene): each frame with its depth
            // and features, as a cluster delivers them (quantiseAsSent), so that the filter sees
            // the wall's values.
            const bool denoise = desc.denoise.mode != DenoiseSettings::Mode::Off && rendersStochastically(desc);
            const uint8_t bits = featureBitsFor(desc.denoise.mode);
            ComposeFrame mean;
            mean.stochastic = o.frames > 1 || denoise;
            mean.linear = mean.stochastic && rendersStochastically(desc);
            if (denoise) {
                mean.denoise = desc.denoise;
                mean.camera = cam;
                mean.keepForWarp = false;
            }
            std::vector<std::vector<float>> depth(1);
            std::vector<FeatureImages> features(1);
            Compositor compositor;
            for (int f = 0; f < o.frames; ++f) {
                TileStats fs;
                const uint32_t frame = firstFrame + uint32_t(f);
                std::vector<Image> image(1);
                std::vector<float> rgb;
                if (denoise) {
                    FeatureFrame ff = renderFrameFeatures(scene, camera, s, frame, &fs, trace);
                    quantiseAsSent(ff, bits);
                    rgb = std::move(ff.linear);
                    depth[0] = std::move(ff.depth);
                    features[0] = {std::move(ff.albedo), std::move(ff.normal), std::move(ff.id)};
                    mean.depth = depth;
                    mean.features = features;
                    image[0].width = s.width;
                    image[0].height = s.height;
                    image[0].rgb.resize(size_t(s.width) * size_t(s.height) * 3);
                } else if (mean.linear) {
                    rgb = renderFrameLinear(scene, camera, s, frame, &fs, trace);
                    image[0].width = s.width;
                    image[0].height = s.height;
                } else {
                    image[0] = renderFrame(scene, camera, s, frame, &fs, trace);
                }
                img = compositor.compose(mean, std::move(image), {&rgb, 1}).left;
                stats.rays += fs.rays;
                stats.shadowRays += fs.shadowRays;
            }
        } else {
            const TileRect r = parseRegion(o.region, s);
            img.width = s.width;
            img.height = s.height;
            img.rgb.assign(size_t(s.width) * s.height * 3, 0);
            stats = renderTile(scene, camera, r, firstFrame, s, {img.pixel(r.x0, r.y0), size_t(s.width) * 3}, trace);
        }
    } catch (const TileError& e) {
        throw withReplay(e, {o.scene, o.triangles, desc.origin, cam, s, trace, 0, {}});
    }
    return img;
}

int runRender(const RenderOptions& o) {
    bench::installInterruptHandler();
    SceneDesc desc = loadWithProgress(o.scene, o);
    applyPartView(desc, o.parts);  // on top of the scene file's [parts]
    RenderSettings& s = desc.settings;
    applyOverrides(s, o);
    if (!o.denoise.empty()) desc.denoise.mode = denoiseModeFromName(o.denoise);
    applyDenoiseIsa(o.denoiseIsa);
    const TraceOptions trace = traceOptionsOf(o);
    const CameraDesc cam = chooseCamera(desc, o);
    const char* kernel = s.kernel == KernelType::Packet ? "packet" : "single";
    const auto t0 = std::chrono::steady_clock::now();
    if (o.clients > 0) {
        if (!o.region.empty()) throw InputError("--region and --clients cannot be combined");
        if (o.frame >= 0) throw InputError("--frame and --clients cannot be combined (the cluster numbers its frames)");
        FrameReport report;
        const Image img = renderWithClients(desc, cam, o, report);
        writePng(img, o.out);
        const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("wrote %s (%dx%d, camera '%s', %s kernel, %d clients, codec %s): frame %.3f s, "
                    "%.3f s with start-up, %.2f MB of tiles\n",
                    o.out.c_str(), s.width, s.height, cam.name.c_str(), kernel, o.clients, o.codec.c_str(),
                    report.seconds, total, double(report.bytes) * 1e-6);
        return 0;
    }
    int64_t triangles = 0;
    for (const MeshDesc& m : desc.meshes) triangles += int64_t(m.mesh->triangleCount());
    std::optional<bench::ProgressBar> bar(std::in_place, "bvh build", double(triangles) * 1e-6, "Mtri");
    Scene scene(desc, bar->fn());
    bar.reset();
    const auto t1 = std::chrono::steady_clock::now();
    const Camera camera(cam, s.width, s.height);
    TileStats stats;
    const Image img = renderHere(scene, camera, desc, cam, o, trace, stats);
    const auto t2 = std::chrono::steady_clock::now();
    writePng(img, o.out);
    const double build = std::chrono::duration<double>(t1 - t0).count();
    const double render = std::chrono::duration<double>(t2 - t1).count();
    const double pixels = double(s.width) * s.height * std::max(1, o.frames);
    std::printf("wrote %s (%dx%d, camera '%s', %s kernel): BVH build %.3f s, render %.3f s, %.2f Mrays/s "
                "(%.1f rays + %.1f shadow rays per pixel and frame)\n",
                o.out.c_str(), s.width, s.height, cam.name.c_str(), kernel, build, render,
                double(stats.rays + stats.shadowRays) / render * 1e-6, double(stats.rays) / pixels,
                double(stats.shadowRays) / pixels);
    return 0;
}

}  // namespace

void addRender(CLI::App& app, Run& run) {
    auto o = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand("render", "Render one frame of a scene file (.toml) or a mesh file to PNG");
    cmd->add_option("scene", o->scene,
                    "Scene file (.toml), mesh file (.obj .off .ply .stl .om .vtk .vtp .vtu .wrl), assembly (.gltf .glb .step .stp .iges .igs), or builtin:knots")->required();
    cmd->add_option("--out,-o", o->out, "Output PNG file")->required();
    cmd->add_option("--triangles", o->triangles, "Triangles of a builtin scene")
        ->check(CLI::Range(int64_t(1000), int64_t(200'000'000)));
    cmd->add_option("--deflection", o->deflection, "STEP/IGES: tessellation tolerance, the largest surface-to-triangle distance in file units (0.1)")
        ->check(CLI::Range(1e-6, 1e6));
    cmd->add_option("--angular-deflection", o->angularDeflection, "STEP/IGES: largest angle between neighbouring triangles, radians (0.5)")
        ->check(CLI::Range(1e-3, 3.14));
    cmd->add_flag("--cache", o->cache, "STEP/IGES: use FILE.rtwasm when it matches the file and deflections, else write it");
    cmd->add_option("--hide", o->parts.hide, "Hide the parts (or meshes) this pattern names: a name, or a path a/b/c when it has a '/'; '*' is any text (repeatable)");
    cmd->add_option("--isolate", o->parts.isolate, "Show only the parts (or meshes) these patterns name (repeatable)");
    cmd->add_option("--highlight", o->parts.highlight, "Highlight the parts (or meshes) this pattern names: tinted and glowing (repeatable)");
    cmd->add_option("--width", o->width, "Image width in pixels (overrides the scene)")->check(CLI::Range(1, 16384));
    cmd->add_option("--height", o->height, "Image height in pixels (overrides the scene)")->check(CLI::Range(1, 16384));
    cmd->add_option("--camera", o->camera, "Name of the scene camera to use (default: the first)");
    cmd->add_option("--camera-position", o->cameraPosition, "Camera position x,y,z in the scene's world coordinates (overrides the camera's)");
    cmd->add_option("--camera-look-at", o->cameraLookAt, "Point x,y,z the camera looks at (overrides the camera's)");
    cmd->add_option("--camera-up", o->cameraUp, "Camera up direction x,y,z (overrides the camera's)");
    cmd->add_option("--fov", o->fov, "Vertical field of view in degrees (overrides the camera's)")->check(CLI::Range(0.01, 179.0));
    cmd->add_option("--camera-window", o->cameraWindow,
                    "Off-axis projection: the image rectangle's lower-left corner (world coordinates), its right edge "
                    "and its up edge, 9 numbers x,y,z,x,y,z,x,y,z");
    cmd->add_option("--threads", o->threads, "Render threads (0 = one per hardware thread)")->check(CLI::Range(0, 1024));
    cmd->add_option("--tile", o->tile, "Tile size in pixels (overrides the scene)")->check(CLI::Range(1, 1024));
    cmd->add_option("--kernel", o->kernel, "Ray kernel (overrides the scene)")->check(CLI::IsMember({"packet", "single"}));
    cmd->add_option("--packet-width", o->packetWidth, "Rays per Embree packet on this machine (0 = this CPU's widest; 4, 8, 16 force one)")
        ->check(CLI::IsMember({0, 4, 8, 16}));
    cmd->add_option("--clients", o->clients,
                    "Render through a master and this many local client processes (the cluster path)")
        ->check(CLI::Range(0, 256));
    cmd->add_option("--prefetch", o->prefetch, "Tiles each client keeps in flight (with --clients)")->check(CLI::Range(1, 64));
    cmd->add_option("--codec", o->codec, "Tile codec (with --clients); jpeg is lossy")
        ->check(CLI::IsMember({"raw", "lz4", "zstd", "jpeg"}));
    cmd->add_option("--view", o->view, "False-colour view (overrides the scene)")
        ->check(CLI::IsMember({"shaded", "depth", "rays", "tile_time", "client"}));
    cmd->add_option("--client-id", o->clientId, "The render client id the client view shows (default 0)")
        ->check(CLI::Range(int64_t(0), int64_t(UINT32_MAX)));
    cmd->add_option("--shading", o->shading, "full, or eyelight: primary rays only (overrides the scene)")
        ->check(CLI::IsMember({"full", "eyelight"}));
    cmd->add_option("--shadows", o->shadows, "Hard shadows from every light (overrides the scene)")->check(CLI::IsMember({"on", "off"}));
    cmd->add_option("--background", o->background, "Radiance r,g,b of rays that hit nothing (overrides the scene)");
    cmd->add_option("--ambient", o->ambient, "Constant ambient light r,g,b (overrides the scene)");
    CLI::Option* gi = cmd->add_flag("--gi", o->gi, "Global illumination: path tracing with next-event estimation");
    cmd->add_flag("--no-gi", o->noGi, "No global illumination (overrides the scene)")->excludes(gi);
    cmd->add_option("--samples", o->samples, "Random samples per pixel sample and frame")->check(CLI::Range(1, 4096));
    cmd->add_option("--denoise", o->denoise, "Denoise the frames of a stochastic scene (over the scene's [denoise] mode)")
        ->check(CLI::IsMember({"off", "temporal", "svgf"}));
    addDenoiseIsaOption(cmd, o->denoiseIsa);
    cmd->add_option("--supersample", o->supersample, "n x n sub-pixel samples per pixel (overrides the scene)")->check(CLI::Range(1, 16));
    cmd->add_option("--prune", o->prune, "Ray-tree pruning threshold (0 = off)")->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--max-depth", o->maxDepth, "Longest ray path")->check(CLI::Range(1, 64));
    CLI::Option* frames = cmd->add_option("--frames", o->frames,
                    "Average frames 1..N in linear light, each with its own seeds (progressive refinement)")
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--frame", o->frame, "Render frame N alone, with its own seeds (default: frame 1)")
        ->check(CLI::Range(int64_t(0), int64_t(UINT32_MAX)))->excludes(frames);
    cmd->add_option("--region", o->region, "Render only pixels x0,y0,x1,y1 (half-open; the rest stays black), to replay one tile");
    // Tests only, not in --help: the tile of frame F holding pixel (X, Y) throws, to test how a
    // failed tile is reported and replayed.
    cmd->add_option("--inject-tile-fault", o->fault, "F,X,Y")->group("");

    cmd->callback([&run, o] { run = [o] { return runRender(*o); }; });
}

}  // namespace rtwall::cli
