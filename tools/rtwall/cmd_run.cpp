// rtwall run: the display master with local render clients, frame after frame, shown on the
// wall (GLFW windows, or the headless presenter where there is no display); every Nth frame
// also goes to a PNG file and the frame rate to stdout.
#include "commands.h"
#include "local_clients.h"
#include "wall_view.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>
#include <rtwall/toml_reader.h>
#include <rtwall/tune.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <future>
#include <memory>
#include <numbers>
#include <optional>
#include <tuple>

namespace rtwall::cli {

namespace {

// The run configuration (format: configs/README.md, "Run configs").
struct RunConfig {
    std::string scene = "builtin:knots";  // scene file, mesh file or builtin:NAME
    std::string camera;
    ClusterSettings cluster;
    int frames = 60;         // 0 = until Ctrl-C
    int writeEvery = 30;     // 0 = never
    std::string out = "out/frames";
    double orbit = 1.0;      // degrees per frame around the camera's look-at point
    std::string cameraPath;  // a camera path file (replaces orbit)
    int width = 0, height = 0;  // override the scene's image size
    std::string wall;        // a wall config (configs/wall/); none: one window of the image's size
};

// A camera path: keyframes at frame numbers, linearly interpolated, held after the last.
struct CameraKey {
    int frame;
    CameraDesc camera;
};

// Positions are world coordinates (double), made relative to the scene's rebased `origin` here,
// so a path survives a change of origin (a recorded path is written the same way).
std::vector<CameraKey> readCameraPath(const std::filesystem::path& file, const std::array<double, 3>& origin) {
    using namespace toml_reader;
    const toml::table root = parseFile(file);
    Reader top(file, root, "");
    std::vector<CameraKey> keys;
    forEachTable(top, file, "key", [&](Reader& r, const toml::table&) {
        CameraKey k;
        k.frame = r.integer("frame", 0, 0, 100'000'000);
        if (!keys.empty() && k.frame <= keys.back().frame)
            r.fail(r.find("frame"), "key 'frame': keyframes must have increasing frame numbers");
        auto rel = [&](const std::array<double, 3>& p) {
            return Float3{float(p[0] - origin[0]), float(p[1] - origin[1]), float(p[2] - origin[2])};
        };
        k.camera.position = rel(r.vec3d("position", {}, true));
        k.camera.lookAt = rel(r.vec3d("look_at", {}, true));
        k.camera.up = r.vec3("up", k.camera.up);
        k.camera.fovY = float(r.number("fov", k.camera.fovY, 0.01, 179.0));
        keys.push_back(k);
    });
    top.finish();
    if (keys.empty()) throw InputError(file.string() + ": a camera path needs at least one [[key]]");
    return keys;
}

CameraDesc cameraAt(const std::vector<CameraKey>& keys, int frame) {
    if (frame <= keys.front().frame) return keys.front().camera;
    for (size_t i = 1; i < keys.size(); ++i)
        if (frame <= keys[i].frame) {
            const CameraKey &a = keys[i - 1], &b = keys[i];
            const float t = float(frame - a.frame) / float(b.frame - a.frame);
            auto mix = [t](Float3 p, Float3 q) {
                return Float3{p.x + (q.x - p.x) * t, p.y + (q.y - p.y) * t, p.z + (q.z - p.z) * t};
            };
            CameraDesc c = a.camera;
            c.position = mix(a.camera.position, b.camera.position);
            c.lookAt = mix(a.camera.lookAt, b.camera.lookAt);
            c.up = mix(a.camera.up, b.camera.up);
            c.fovY = a.camera.fovY + (b.camera.fovY - a.camera.fovY) * t;
            return c;
        }
    return keys.back().camera;
}

// Used when `rtwall run` is given no config: the built-in knot field, two local clients.
constexpr const char* kEmbeddedDefault = R"(scene = "builtin:knots"
[image]
width = 800
height = 600
[cluster]
clients = 2
[run]
frames = 60
write_every = 30
orbit = 1.0
)";

RunConfig readRunConfig(const std::filesystem::path& file, const toml::table& root) {
    using namespace toml_reader;
    RunConfig c;
    Reader top(file, root, "");
    std::string scene = top.string("scene", c.scene);
    if (!scene.starts_with("builtin:") && !file.empty()) scene = (file.parent_path() / scene).string();
    c.scene = scene;
    c.camera = top.string("camera", "");
    if (const std::string wall = top.string("wall", ""); !wall.empty()) c.wall = (file.parent_path() / wall).string();
    if (const toml::table* t = subTable(top, "image")) {
        Reader r(file, *t, "[image]: ");
        c.width = r.integer("width", 0, 1, 16384);
        c.height = r.integer("height", 0, 1, 16384);
        r.finish();
    }
    if (const toml::table* t = subTable(top, "cluster")) {
        Reader r(file, *t, "[cluster]: ");
        ClusterSettings& cs = c.cluster;
        cs.bind = r.string("bind", cs.bind);
        cs.localClients = r.integer("clients", cs.localClients, 0, 256);
        cs.threadsPerClient = r.integer("threads", cs.threadsPerClient, 0, 1024);
        cs.prefetch = r.integer("prefetch", cs.prefetch, 1, 64);
        cs.affinity = r.boolean("affinity", cs.affinity);
        cs.async = r.boolean("async", cs.async);
        cs.codec.codec = tileCodecFromName(r.choice("codec", "lz4", {"raw", "lz4", "zstd", "jpeg"}));
        cs.codec.jpegQuality = r.integer("jpeg_quality", cs.codec.jpegQuality, 1, 100);
        cs.codec.jpegSubsample = r.boolean("jpeg_subsample", cs.codec.jpegSubsample);
        cs.codec.zstdLevel = r.integer("zstd_level", cs.codec.zstdLevel, 1, 19);
        cs.heartbeatMs = r.integer("heartbeat_ms", cs.heartbeatMs, 10, 60000);
        cs.timeoutMs = r.integer("timeout_ms", cs.timeoutMs, 50, 600000);
        cs.stragglerFactor = r.number("straggler_factor", cs.stragglerFactor, 1.0, 1000.0);
        cs.wideAccumulation = r.boolean("wide_accumulation", cs.wideAccumulation);
        if (cs.timeoutMs <= cs.heartbeatMs) r.fail(r.find("timeout_ms"), "timeout_ms must exceed heartbeat_ms");
        const std::string key = r.string("key", "");
        if (!key.empty()) cs.keyFile = file.parent_path() / key;
        if (const toml::node* n = r.find("client_keys")) {
            const toml::array* a = n->as_array();
            if (!a) r.fail(n, "key 'client_keys': expected an array of public key files");
            for (const toml::node& e : *a) {
                if (!e.is_string()) r.fail(n, "key 'client_keys': expected strings");
                cs.clientKeys.push_back(file.parent_path() / std::string(*e.value<std::string>()));
            }
        }
        cs.insecure = r.boolean("insecure", cs.insecure);
        r.finish();
    }
    if (const toml::table* t = subTable(top, "run")) {
        Reader r(file, *t, "[run]: ");
        c.frames = r.integer("frames", c.frames, 0, 100'000'000);
        c.writeEvery = r.integer("write_every", c.writeEvery, 0, 100'000'000);
        c.out = r.string("out", c.out);
        c.orbit = r.number("orbit", c.orbit, -360.0, 360.0);
        if (r.has("camera_path")) {
            if (r.has("orbit")) r.fail(r.find("camera_path"), "give either 'orbit' or 'camera_path'");
            c.cameraPath = (file.parent_path() / r.string("camera_path", "")).string();
            c.orbit = 0.0;
        }
        r.finish();
    }
    top.finish();
    return c;
}

std::atomic<bool> gStop{false};

// `rtwall run --watch`: the scene file is reloaded on a background thread whenever it changes on
// disk, so that the wall keeps running while a large scene loads again.
class SceneWatcher {
public:
    SceneWatcher(std::filesystem::path file, std::function<SceneDesc()> load)
        : file_(std::move(file)), load_(std::move(load)), lastWrite_(writeTime()) {}

    // The reloaded scene once the file changed and its load finished. A file that does not load
    // (an edit half-written, a typo) is reported in one line and the running scene stays.
    std::optional<SceneDesc> poll() {
        const auto now = std::chrono::steady_clock::now();
        if (!loading_.valid() && now - lastCheck_ > std::chrono::milliseconds(200)) {
            lastCheck_ = now;
            const auto t = writeTime();
            if (t && t != lastWrite_) {
                lastWrite_ = t;
                loading_ = std::async(std::launch::async, load_);
            }
        }
        if (!loading_.valid() || loading_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return std::nullopt;
        try {
            return loading_.get();
        } catch (const std::exception& e) {
            std::printf("rtwall run: --watch: %s (the running scene stays)\n", e.what());
            std::fflush(stdout);
            return std::nullopt;
        }
    }

private:
    std::optional<std::filesystem::file_time_type> writeTime() const {
        std::error_code ec;
        const auto t = std::filesystem::last_write_time(file_, ec);
        return ec ? std::nullopt : std::optional(t);
    }
    std::filesystem::path file_;
    std::function<SceneDesc()> load_;
    std::optional<std::filesystem::file_time_type> lastWrite_;
    std::chrono::steady_clock::time_point lastCheck_{};
    std::future<SceneDesc> loading_;
};

// ---- Operating point (--target-fps) ----------------------------------------------------------
// The controls `rtwall run` can change between frames, by the names a front uses. Adding one
// (pruning threshold, GI samples per pixel, volume step) is one entry here plus its column in
// the sweep (tools/speed_accuracy.py).
struct Knobs {
    RenderSettings settings;  // tile size, resolution, ...
    CodecSettings codec;
    float volumeStep = 0;     // > 0: every volume material's ray-march step, in voxels
};

void applyControl(Knobs& k, const RenderSettings& base, const std::string& name, double v, const std::string& point) {
    if (name == "tile") k.settings.tileSize = int(v);
    else if (name == "codec") k.codec.codec = TileCodec(int(v));  // 0 raw, 1 lz4, 2 zstd, 3 jpeg (TileCodec)
    else if (name == "jpeg_quality") k.codec.jpegQuality = int(v);
    else if (name == "scale") {
        k.settings.width = std::max(16, int(std::lround(base.width * v)));
        k.settings.height = std::max(16, int(std::lround(base.height * v)));
    } else if (name == "supersample") k.settings.supersample = int(v);
    else if (name == "prune") k.settings.pruneThreshold = float(v);
    else if (name == "gi_spp") {  // 0: no GI; n: path tracing with n samples per pixel sample
        k.settings.gi = v > 0;
        k.settings.samples = std::max(1, int(v));
    } else if (name == "volume_step") k.volumeStep = float(v);
    else
        throw InputError("operating point '" + point + "': this build cannot set control '" + name +
                         "' (it can: tile, codec, jpeg_quality, scale, supersample, prune, gi_spp, volume_step)");
}

Knobs knobsOf(const OperatingPoint& p, const RenderSettings& base, const CodecSettings& baseCodec) {
    Knobs k{base, baseCodec};
    for (const auto& [name, v] : p.controls) applyControl(k, base, name, v, p.name);
    return k;
}

// A front written by tools/speed_accuracy.py: [[point]] name, frame_s, error, [point.controls].
std::vector<OperatingPoint> readFront(const std::filesystem::path& file) {
    using namespace toml_reader;
    const toml::table root = parseFile(file);
    Reader top(file, root, "");
    std::vector<OperatingPoint> points;
    top.string("scene", "");
    top.number("target_fps_hint", 0, 0, 1e6);
    forEachTable(top, file, "point", [&](Reader& r, const toml::table& t) {
        OperatingPoint p;
        p.name = r.string("name", "", true);
        p.frameSeconds = r.number("frame_s", 0, 1e-9, 1e6);
        p.error = r.number("error", 0, 0, 1e9);
        r.number("psnr_db", 0, -1e9, 1e9);
        if (const toml::table* c = t["controls"].as_table()) {
            for (const auto& [key, value] : *c) {
                const std::optional<double> v = value.value<double>();
                if (!v) r.fail(&value, "point '" + p.name + "': control '" + std::string(key.str()) + "' must be a number");
                p.controls.emplace_back(std::string(key.str()), *v);
            }
            r.find("controls");
        }
        points.push_back(p);
    });
    top.finish();
    return points;
}

std::string codecPointName(const CodecSettings& c, int tile) {
    std::string n = tileCodecName(c.codec);
    if (c.codec == TileCodec::Jpeg) n += " q" + std::to_string(c.jpegQuality);
    return n + ", tile " + std::to_string(tile);
}

CameraDesc orbited(const CameraDesc& c, double degrees) {
    const double a = degrees * std::numbers::pi / 180.0, ca = std::cos(a), sa = std::sin(a);
    const double x = c.position.x - c.lookAt.x, z = c.position.z - c.lookAt.z;
    CameraDesc o = c;
    o.position.x = float(c.lookAt.x + ca * x + sa * z);
    o.position.z = float(c.lookAt.z - sa * x + ca * z);
    return o;
}

}  // namespace

void addRun(CLI::App& app, Run& run) {
    struct Options {
        std::string config;
        int frames = -1, clients = -1, writeEvery = -1;
        std::string out, bind, cameraPath, wall, front, trace;
        bool insecure = false, headless = false, watch = false;
        double targetFps = 0;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("run", "Run the display master with local render clients (default: a built-in demo)");
    cmd->add_option("config", o->config, "Run config (.toml, see configs/README.md); none: the embedded default");
    cmd->add_option("--frames", o->frames, "Frames to render (0 = until Ctrl-C)")->check(CLI::Range(0, 100'000'000));
    cmd->add_option("--clients", o->clients, "Local client processes to start")->check(CLI::Range(0, 256));
    cmd->add_option("--write-every", o->writeEvery, "Write every Nth frame as PNG (0 = never)")->check(CLI::Range(0, 100'000'000));
    cmd->add_option("--out", o->out, "Directory for the PNG frames");
    cmd->add_option("--camera-path", o->cameraPath, "Camera path file (.toml keyframes, see configs/README.md)");
    cmd->add_option("--wall", o->wall, "Wall config (configs/wall/*.toml; default: one window of the image's size)");
    cmd->add_flag("--headless", o->headless, "Never open windows, even where a display is available");
    cmd->add_flag("--watch", o->watch,
                  "Reload the scene file when it changes on disk and send what changed (materials, lights, instance "
                  "transforms, render settings, the camera) as differential updates");
    cmd->add_flag("--insecure", o->insecure, "Allow a non-loopback bind without CURVE keys (says so loudly)");
    cmd->add_option("--bind", o->bind, "Endpoint for clients, e.g. tcp://0.0.0.0:7700 (default: loopback, any port)");
    cmd->add_option("--target-fps", o->targetFps,
                    "Hold this frame rate: pick the most accurate settings on the front that do (codec, JPEG quality, tile size)")
        ->check(CLI::Range(0.1, 10000.0));
    cmd->add_option("--front", o->front,
                    "Measured front for --target-fps (.toml from tools/speed_accuracy.py); default: calibrate codecs and tile "
                    "sizes on the first frames");
    cmd->add_option("--trace", o->trace,
                    "With --target-fps: write one CSV line per frame (frame, seconds, clients, operating point)");
    cmd->callback([&run, o] {
        run = [o] {
            RunConfig c = o->config.empty() ? readRunConfig({}, toml::parse(kEmbeddedDefault))
                                            : readRunConfig(o->config, toml_reader::parseFile(o->config));
            if (o->frames >= 0) c.frames = o->frames;
            if (o->clients >= 0) c.cluster.localClients = o->clients;
            if (o->writeEvery >= 0) c.writeEvery = o->writeEvery;
            if (!o->out.empty()) c.out = o->out;
            if (!o->bind.empty()) c.cluster.bind = o->bind;
            if (!o->cameraPath.empty()) c.cameraPath = o->cameraPath;
            if (o->insecure) c.cluster.insecure = true;
            if (!o->wall.empty()) c.wall = o->wall;

            const std::filesystem::path scenePath(c.scene);
            SceneDesc desc = c.scene.starts_with("builtin:") ? builtinScene(c.scene.substr(8), 3'000'000)
                             : scenePath.extension() == ".toml" ? loadSceneFile(scenePath)
                                                                : sceneFromMeshFile(scenePath);
            if (o->watch && !(scenePath.extension() == ".toml" && !c.scene.starts_with("builtin:")))
                throw InputError("--watch needs a scene file (.toml); " + c.scene + " is not one");
            if (c.width) desc.settings.width = c.width;
            if (c.height) desc.settings.height = c.height;
            // The wall decides the image size; its config and shaders are checked before anything starts.
            WallConfig wall = singleScreenWall(desc.settings.width, desc.settings.height);
            if (!c.wall.empty()) {
                const std::vector<std::string> problems = checkWall(c.wall);
                if (!problems.empty()) throw InputError(problems.front());
                wall = loadWallConfig(c.wall);
            }
            // What the run config and the wall decide over the scene file (also for a reloaded one).
            auto fit = [&c, &wall](SceneDesc& d) {
                if (c.width) d.settings.width = c.width;
                if (c.height) d.settings.height = c.height;
                if (!c.wall.empty()) {
                    d.settings.width = wall.width;
                    d.settings.height = wall.height;
                }
                if (!c.camera.empty()) {
                    const CameraDesc* cam = d.findCamera(c.camera);
                    if (!cam) throw InputError(c.scene + ": no camera named '" + c.camera + "'");
                    d.cameras = {*cam};
                }
            };
            const bool stereo = wall.stereo.mode != StereoMode::None;
            if (stereo && c.cluster.async) {
                // Two renders per frame, one per eye: asynchronous mode would give each eye the other's camera.
                std::printf("stereo wall: asynchronous rendering off, each frame renders the left then the right eye\n");
                c.cluster.async = false;
            }
            fit(desc);
            const CameraDesc start = desc.cameras.front();
            const std::vector<CameraKey> path = c.cameraPath.empty() ? std::vector<CameraKey>{} : readCameraPath(c.cameraPath, desc.origin);

            // A given front is checked before anything starts: a mistake in it is one line, at once.
            const std::vector<OperatingPoint> givenFront = o->front.empty() ? std::vector<OperatingPoint>{} : readFront(o->front);
            if (!o->front.empty() && o->targetFps <= 0) throw InputError("--front needs --target-fps");
            for (const OperatingPoint& p : givenFront) knobsOf(p, desc.settings, c.cluster.codec);  // unknown controls fail now

            // Ctrl-C and SIGTERM stop the run between frames, and a frame that cannot finish
            // gives up (Cancelled: "interrupted", exit status 130).
            std::signal(SIGINT, [](int) { gStop = true; });
            std::signal(SIGTERM, [](int) { gStop = true; });
            Master master(desc, c.cluster);
            master.setStopFlag(&gStop);
            // What the master dropped, refused or lost, said when the run ends, however it ends.
            struct CountersAtExit {
                const Master& master;
                ~CountersAtExit() { std::printf("master: %s\n", describeCounters(master.counters()).c_str()); }
            } countersAtExit{master};
            std::printf("rtwall master at %s, %dx%d, %d local clients, codec %s%s\n", master.endpoint().c_str(),
                        desc.settings.width, desc.settings.height, c.cluster.localClients,
                        tileCodecName(c.cluster.codec.codec),
                        c.cluster.async ? ", asynchronous" : "");
            std::fflush(stdout);
            LocalClients clients(c.cluster.localClients, master.endpoint(), std::max(1, c.cluster.threadsPerClient), false,
                                 {}, master.localClientArgs());
            // Remote clients may take a while to be started; local ones are here in seconds, and
            // one that died or froze on the way must not keep the wall dark: go on with the others.
            const int needed = std::max(1, c.cluster.localClients);
            const int waitMs = c.cluster.localClients > 0 ? 60'000 : 600'000;
            if (c.cluster.localClients == 0)
                std::printf("waiting for clients: rtwall client --connect %s\n", master.endpoint().c_str());
            const int joined = master.awaitClients(needed, waitMs, c.cluster.localClients > 0 ? std::max(3000, 2 * c.cluster.timeoutMs) : waitMs);
            if (joined == 0)
                throw InputError("no render client joined " + master.endpoint() + " in time" +
                                 (c.cluster.keyFile.empty() ? "" : " (" + describeCounters(master.counters()) +
                                                                   "; each client needs --key with its public key in client_keys)"));
            if (joined < needed)
                std::printf("only %d of %d render clients joined; rendering with them (the others join when they can)\n", joined, needed);

            WallView::Options vo;
            vo.forceHeadless = o->headless;
            vo.perScreenImages = !c.wall.empty();
            vo.outDir = c.out;
            vo.interactive = path.empty();
            vo.codec = tileCodecName(c.cluster.codec.codec);
            WallView view(wall, desc, start, vo);
            // In a window the wall runs until it is closed, unless a frame count was asked for.
            if (view.windowed() && o->frames < 0) c.frames = 0;
            // Operating point: a front (given, or measured now on a still camera), a controller.
            std::unique_ptr<OperatingPointController> controller;
            const RenderSettings baseSettings = desc.settings;
            const CodecSettings baseCodec = c.cluster.codec;
            SceneDesc current = desc;  // the state the clients hold, as --watch edits it
            auto apply = [&](const OperatingPoint& p) {
                const Knobs k = knobsOf(p, baseSettings, baseCodec);
                master.setRenderSettings(k.settings);
                master.setCodec(k.codec);
                for (size_t m = 0; m < current.materials.size(); ++m)
                    if (current.materials[m].type == MaterialType::Volume) {
                        Material mat = current.materials[m];
                        if (k.volumeStep > 0) mat.volumeStep = k.volumeStep;
                        master.setMaterial(uint32_t(m), mat);
                    }
            };
            if (o->targetFps > 0) {
                std::vector<OperatingPoint> points;
                if (!givenFront.empty()) {
                    points = givenFront;
                } else {
                    // Calibration: each codec and tile size for three frames of the first view;
                    // error = 1 - SSIM against the lossless frame.
                    std::printf("calibrating the operating points (codec x tile size, and resolution, 3 frames each)\n");
                    std::fflush(stdout);
                    const Image lossless = master.renderFrame();
                    std::vector<std::tuple<int, int, double>> grid;  // JPEG quality (0: LZ4), tile, scale
                    for (int q : {0, 95, 90, 75, 50})
                        for (int tile : {32, 64, 128}) grid.emplace_back(q, tile, 1.0);
                    for (double scale : {0.75, 0.5}) grid.emplace_back(0, 64, scale);
                    for (const auto& [q, tile, scale] : grid) {
                            OperatingPoint p;
                            CodecSettings cs = baseCodec;
                            cs.codec = q == 0 ? TileCodec::Lz4 : TileCodec::Jpeg;
                            if (q) cs.jpegQuality = q;
                            p.name = codecPointName(cs, tile);
                            p.controls = {{"tile", tile}, {"codec", double(int(cs.codec))}, {"scale", scale}};
                            if (scale != 1.0) p.name += ", scale " + std::to_string(scale).substr(0, 4);
                            if (q) p.controls.emplace_back("jpeg_quality", q);
                            apply(p);
                            std::vector<double> times;
                            Image img;
                            for (int i = 0; i < 3 && !gStop; ++i) {
                                FrameReport r;
                                img = master.renderFrame(&r);
                                if (i > 0) times.push_back(r.seconds);
                            }
                            if (gStop) return 0;
                            std::sort(times.begin(), times.end());
                            p.frameSeconds = std::max(1e-6, times.front());
                            p.error = std::max(0.0, 1.0 - ssimLuminance(resizeBilinear(img, lossless.width, lossless.height), lossless));
                            std::printf("  %-20s %7.1f ms  1-SSIM %.5f\n", p.name.c_str(), p.frameSeconds * 1e3, p.error);
                            points.push_back(p);
                        }
                }
                ControllerOptions co;
                co.targetFps = o->targetFps;
                controller = std::make_unique<OperatingPointController>(points, co);
                apply(controller->current());
                std::printf("target %.1f fps: starting at '%s' (front of %zu points)\n", o->targetFps,
                            controller->current().name.c_str(), controller->front().size());
                std::fflush(stdout);
            }
            int framesOnTarget = 0;
            std::ofstream trace;
            if (!o->trace.empty()) {
                if (!controller) throw InputError("--trace needs --target-fps");
                trace.open(o->trace);
                if (!trace) throw InputError("--trace: cannot write " + o->trace);
                trace << "frame,seconds,clients,point_index,point\n";
            }

            std::unique_ptr<SceneWatcher> watcher;
            if (o->watch) {
                watcher = std::make_unique<SceneWatcher>(scenePath, [scenePath, fit] {
                    SceneDesc d = loadSceneFile(scenePath);
                    fit(d);
                    return d;
                });
                std::printf("watching %s: edits to materials, lights, instance transforms, render settings and the "
                            "camera are sent as they are saved\n", scenePath.c_str());
            }
            // A reloaded scene file: what changed goes to the clients as differential updates.
            auto applyEdit = [&](const SceneDesc& edited) {
                SceneEdit e = diffScenes(current, edited);
                if (e.settings && controller) {
                    e.refused.push_back("[render] changed, but --target-fps sets the render settings");
                    e.settings.reset();
                }
                if (e.camera && (!path.empty() || c.orbit != 0.0)) {
                    e.refused.push_back("the camera changed, but a camera path or orbit moves it");
                    e.camera.reset();
                }
                size_t materials = 0;
                for (const auto& [i, m] : e.materials) {
                    try {
                        master.setMaterial(i, m);
                        current.materials[i] = m;
                        ++materials;
                    } catch (const InputError& err) {
                        e.refused.push_back("material '" + m.name + "': " + err.what());
                    }
                }
                for (const auto& [i, l] : e.lights) {
                    master.setLight(i, l);
                    current.lights[i] = l;
                }
                for (const auto& [i, t] : e.transforms) {
                    master.setInstanceTransform(i, t);
                    current.instances[i].transform = t;
                }
                if (e.settings) {
                    master.setRenderSettings(*e.settings);
                    current.settings = *e.settings;
                }
                if (e.camera) {
                    master.setCamera(*e.camera);
                    view.setCamera(*e.camera);
                    current.cameras.front() = *e.camera;
                }
                for (const std::string& r : e.refused)
                    std::printf("rtwall run: %s: %s (not applied)\n", scenePath.c_str(), r.c_str());
                std::printf("rtwall run: %s changed: %zu materials, %zu lights, %zu instance transforms, render settings %s, "
                            "camera %s\n", scenePath.c_str(), materials, e.lights.size(), e.transforms.size(),
                            e.settings ? "changed" : "same", e.camera ? "moved" : "same");
                std::fflush(stdout);
            };

            std::vector<double> frameTimes;
            auto last = std::chrono::steady_clock::now();
            uint64_t bytes = 0;
            // A still view of a stochastic scene refines progressively (each frame has its own
            // sampling seeds); a moving camera restarts the accumulation every frame.
            uint32_t accumulatedSeq = UINT32_MAX;
            Accumulator progressive;
            std::vector<float> linear;  // the frame in linear RGB when it came as linear tiles
            int accumulatedFrames = 0, linearFrames = 0;
            for (int f = 1; (c.frames == 0 || f <= c.frames) && !gStop; ++f) {
                // Differential updates: only what changes goes to the clients (the camera; objects the
                // user moves on the wall).
                if (!view.handleInput(master, frameTimes.empty() ? 0.0 : frameTimes.back())) break;
                if (watcher)
                    if (std::optional<SceneDesc> edited = watcher->poll()) applyEdit(*edited);
                std::optional<CameraDesc> scripted;
                if (!path.empty()) scripted = cameraAt(path, f);
                else if (c.orbit != 0.0 && !view.windowed()) scripted = orbited(start, c.orbit * f);
                if (scripted) view.setCamera(*scripted);
                FrameReport report;
                WallFrame shown;
                if (stereo) {
                    master.setCamera(view.eyeCamera(0));
                    shown.left = master.renderFrame();
                    master.setCamera(view.eyeCamera(1));
                    shown.right = master.renderFrame(&report);
                } else {
                    if (scripted) master.setCamera(*scripted);
                    shown.left = master.renderFrame(&report, &linear);
                }
                shown.number = report.frame;
                const Image& img = shown.left;
                if (!stereo && report.stochastic) {
                    // A still view refines: each frame has its own sampling seeds; any change to
                    // the scene state (camera, objects, materials, codec) restarts the accumulation.
                    // Linear frames are summed without the 8-bit quantisation.
                    if (report.stateSeq != accumulatedSeq) progressive.reset();
                    accumulatedSeq = report.stateSeq;
                    if (report.linear) progressive.addLinear(linear.data(), shown.left.width, shown.left.height);
                    else progressive.add(shown.left);
                    ++accumulatedFrames;
                    linearFrames += report.linear;
                    shown.left = progressive.resolve();
                } else {
                    // Deterministic: every frame of a state is the same image; averaging would
                    // only cost time.
                    accumulatedSeq = UINT32_MAX;
                }
                const auto now = std::chrono::steady_clock::now();
                frameTimes.push_back(std::chrono::duration<double>(now - last).count());
                last = now;
                view.show(shown, report, frameTimes.back());
                bytes += report.bytes;
                if (controller) {
                    if (trace.is_open())
                        trace << f << ',' << report.seconds << ',' << master.connectedClients() << ','
                              << controller->currentIndex() << ",\"" << controller->current().name << "\"" << std::endl;
                    framesOnTarget += report.seconds <= 1.0 / o->targetFps;
                    if (controller->observe(report.seconds)) {
                        apply(controller->current());
                        std::printf("frame %d: %.1f ms (budget %.1f ms): operating point -> '%s'\n", f, report.seconds * 1e3,
                                    controller->budgetSeconds() * 1e3, controller->current().name.c_str());
                        std::fflush(stdout);
                    }
                }
                if (c.writeEvery > 0 && f % c.writeEvery == 0) {
                    char name[64];
                    std::snprintf(name, sizeof name, "frame_%06u.png", report.frame);
                    // A frame rendered at a lower resolution (operating point) is shown upscaled.
                    writePng(resizeBilinear(img, baseSettings.width, baseSettings.height), std::filesystem::path(c.out) / name);
                    std::printf("wrote %s\n", (std::filesystem::path(c.out) / name).c_str());
                }
                if (f % 10 == 0 || f == c.frames) {
                    std::vector<double> recent(frameTimes.end() - std::min<size_t>(10, frameTimes.size()), frameTimes.end());
                    std::sort(recent.begin(), recent.end());
                    std::printf("frame %d: %.1f fps (median of the last %zu), %.2f MB of tiles, %llu stolen, %llu of %zu tiles kept their client\n",
                                f, 1.0 / recent[recent.size() / 2], recent.size(), double(report.bytes) * 1e-6,
                                (unsigned long long)report.tilesStolen, (unsigned long long)report.affinityHits,
                                makeTiles(desc.settings.width, desc.settings.height, desc.settings.tileSize).size());
                    std::fflush(stdout);
                }
            }
            if (!frameTimes.empty()) {
                std::vector<double> sorted = frameTimes;
                std::sort(sorted.begin(), sorted.end());
                std::printf("%zu frames, median %.1f fps, %.2f MB of tiles per frame\n", frameTimes.size(),
                            1.0 / sorted[sorted.size() / 2], double(bytes) * 1e-6 / double(frameTimes.size()));
                if (accumulatedFrames > 0)
                    std::printf("progressive refinement: %d of %zu frames accumulated (stochastic scene), %d of them as linear tiles\n",
                                accumulatedFrames, frameTimes.size(), linearFrames);
                else
                    std::printf("no accumulation: the scene is deterministic (every frame of a view is the same image)\n");
                if (controller)
                    std::printf("target %.1f fps: %d of %zu frames within budget (master frame time), %llu operating-point "
                                "changes, ending at '%s'\n",
                                o->targetFps, framesOnTarget, frameTimes.size(), (unsigned long long)controller->changes(),
                                controller->current().name.c_str());
            }
            return 0;
        };
    });
}

}  // namespace rtwall::cli
