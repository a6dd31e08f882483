#include "commands.h"
#include "progress.h"

#include <rtwall/cluster.h>
#include <rtwall/wall.h>
#include <rtwall/engine.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

namespace rtwall::cli {

namespace {

struct RenderOptions {
    std::string scene, out, camera, kernel, region, codec = "lz4", view;
    int width = 0, height = 0, threads = -1, tile = 0, clients = 0, prefetch = 4;
    int samples = 0, maxDepth = 0, frames = 1, packetWidth = 0;
    double prune = -1;
    bool gi = false;
};

bool isSceneFile(const std::filesystem::path& p) {
    std::string ext = p.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".toml";
}

TileRect parseRegion(const std::string& text, const RenderSettings& s) {
    TileRect r;
    if (std::sscanf(text.c_str(), "%d,%d,%d,%d", &r.x0, &r.y0, &r.x1, &r.y1) != 4 || r.x0 < 0 || r.y0 < 0 ||
        r.x1 > s.width || r.y1 > s.height || r.x0 >= r.x1 || r.y0 >= r.y1)
        throw InputError("--region '" + text + "': expected x0,y0,x1,y1 inside the " + std::to_string(s.width) + "x" +
                         std::to_string(s.height) + " image");
    return r;
}

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
    cs.wideAccumulation = o.frames > 1;
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
SceneDesc loadWithProgress(const std::filesystem::path& path) {
    ProgressBar bar("loading", 1, "");
    SceneLoadOptions lo;
    lo.progress = bar.fn();
    return loadSceneFile(path, lo);
}

}  // namespace

void addRender(CLI::App& app, Run& run) {
    auto o = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand("render", "Render one frame of a scene file (.toml) or a mesh file to PNG");
    cmd->add_option("scene", o->scene,
                    "Scene file (.toml), mesh file (.obj .off .ply .stl .om), or builtin:knots")->required();
    cmd->add_option("--out,-o", o->out, "Output PNG file")->required();
    cmd->add_option("--width", o->width, "Image width in pixels (overrides the scene)")->check(CLI::Range(1, 16384));
    cmd->add_option("--height", o->height, "Image height in pixels (overrides the scene)")->check(CLI::Range(1, 16384));
    cmd->add_option("--camera", o->camera, "Name of the scene camera to use (default: the first)");
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
    cmd->add_flag("--gi", o->gi, "Global illumination: path tracing with next-event estimation");
    cmd->add_option("--samples", o->samples, "Random samples per pixel sample and frame")->check(CLI::Range(1, 4096));
    cmd->add_option("--prune", o->prune, "Ray-tree pruning threshold (0 = off)")->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--max-depth", o->maxDepth, "Longest ray path")->check(CLI::Range(1, 64));
    cmd->add_option("--frames", o->frames,
                    "Average this many frames in linear light, each with its own seeds (progressive refinement)")
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--region", o->region, "Render only pixels x0,y0,x1,y1 (half-open; the rest stays black), to replay one tile");

    cmd->callback([&run, o] {
        run = [o] {
            const std::filesystem::path path(o->scene);
            installInterruptHandler();
            SceneDesc desc = o->scene.starts_with("builtin:") ? builtinScene(o->scene.substr(8), 3'000'000)
                             : isSceneFile(path)                 ? loadWithProgress(path)
                                                                 : sceneFromMeshFile(path);
            RenderSettings& s = desc.settings;
            if (o->width) s.width = o->width;
            if (o->height) s.height = o->height;
            if (o->threads >= 0) s.threads = o->threads;
            if (o->tile) s.tileSize = o->tile;
            if (!o->kernel.empty()) s.kernel = o->kernel == "single" ? KernelType::Single : KernelType::Packet;
            s.packetWidth = o->packetWidth;
            if (!o->view.empty()) s.view = viewModeFromName(o->view);
            if (o->gi) s.gi = true;
            if (o->samples) s.samples = o->samples;
            if (o->prune >= 0) s.pruneThreshold = float(o->prune);
            if (o->maxDepth) s.maxDepth = o->maxDepth;
            const CameraDesc* cam = o->camera.empty() ? &desc.cameras.front() : desc.findCamera(o->camera);
            if (!cam) {
                std::string names;
                for (const CameraDesc& c : desc.cameras) names += (names.empty() ? "" : ", ") + c.name;
                throw InputError(o->scene + ": no camera named '" + o->camera + "' (cameras: " + names + ")");
            }
            const char* kernel = s.kernel == KernelType::Packet ? "packet" : "single";
            const auto t0 = std::chrono::steady_clock::now();
            if (o->clients > 0) {
                if (!o->region.empty()) throw InputError("--region and --clients cannot be combined");
                FrameReport report;
                const Image img = renderWithClients(desc, *cam, *o, report);
                writePng(img, o->out);
                const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                std::printf("wrote %s (%dx%d, camera '%s', %s kernel, %d clients, codec %s): frame %.3f s, "
                            "%.3f s with start-up, %.2f MB of tiles\n",
                            o->out.c_str(), s.width, s.height, cam->name.c_str(), kernel, o->clients, o->codec.c_str(),
                            report.seconds, total, double(report.bytes) * 1e-6);
                return 0;
            }
            int64_t triangles = 0;
            for (const MeshDesc& m : desc.meshes) triangles += int64_t(m.mesh->triangleCount());
            std::optional<ProgressBar> bar(std::in_place, "bvh build", double(triangles) * 1e-6, "Mtri");
            Scene scene(desc, bar->fn());
            bar.reset();
            const auto t1 = std::chrono::steady_clock::now();
            const Camera camera(*cam, s.width, s.height);
            TileStats stats;
            Image img;
            if (o->region.empty()) {
                // The cluster numbers its frames from 1; so do we, so both give the same bytes.
                // Frames are averaged in linear light, before the 8-bit quantisation clips each
                // at 1.0 (a GI sample far above 1 would lose its excess in every frame), at the
                // half precision the cluster sends them in (Accumulator::addLinear). A
                // deterministic scene renders the same image every frame: its 8-bit mean is it.
                const bool linear = o->frames > 1 && rendersStochastically(desc);
                Accumulator acc;
                for (int f = 0; f < o->frames; ++f) {
                    TileStats fs;
                    if (linear) {
                        const std::vector<float> frame = renderFrameLinear(scene, camera, s, uint32_t(f + 1), &fs);
                        acc.addLinear(frame.data(), s.width, s.height);
                    } else {
                        img = renderFrame(scene, camera, s, uint32_t(f + 1), &fs);
                        if (o->frames > 1) acc.add(img);
                    }
                    stats.rays += fs.rays;
                    stats.shadowRays += fs.shadowRays;
                }
                if (o->frames > 1) img = acc.resolve();
            } else {
                const TileRect r = parseRegion(o->region, s);
                img.width = s.width;
                img.height = s.height;
                img.rgb.assign(size_t(s.width) * s.height * 3, 0);
                stats = renderTile(scene, camera, r, 0, s, {img.pixel(r.x0, r.y0), size_t(s.width) * 3});
            }
            const auto t2 = std::chrono::steady_clock::now();
            writePng(img, o->out);
            const double build = std::chrono::duration<double>(t1 - t0).count();
            const double render = std::chrono::duration<double>(t2 - t1).count();
            const double pixels = double(s.width) * s.height * std::max(1, o->frames);
            std::printf("wrote %s (%dx%d, camera '%s', %s kernel): BVH build %.3f s, render %.3f s, %.2f Mrays/s "
                        "(%.1f rays + %.1f shadow rays per pixel and frame)\n",
                        o->out.c_str(), s.width, s.height, cam->name.c_str(), kernel, build, render,
                        double(stats.rays + stats.shadowRays) / render * 1e-6, double(stats.rays) / pixels,
                        double(stats.shadowRays) / pixels);
            return 0;
        };
    });
}

}  // namespace rtwall::cli
