// WallSession: the display master's frame loop (what `rtwall run` runs).
#include "live_scene.h"
#include "scene_watcher.h"
#include "tuning.h"
#include "wall_input.h"

#include <rtwall/frame.h>
#include <rtwall/wall.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <fstream>
#include <span>
#include <sstream>
#include <thread>

namespace rtwall {

using wall::LiveScene;
using wall::SceneWatcher;
using wall::WallTuning;
using wall::WallInput;

namespace {

// What the run config and the wall decide over the scene file (also for a reloaded one).
void fitToRun(SceneDesc& d, const RunConfig& c, const WallConfig& wall) {
    if (c.width) d.settings.width = c.width;
    if (c.height) d.settings.height = c.height;
    if (c.hasWall()) {
        d.settings.width = wall.width;
        d.settings.height = wall.height;
    }
    if (!c.parts.empty()) applyPartView(d, c.parts);
    if (!c.camera.empty()) {
        const CameraDesc* cam = d.findCamera(c.camera);
        if (!cam) throw InputError(c.scene + ": no camera named '" + c.camera + "'");
        d.cameras = {*cam};
    }
}

bool samePose(const HeadPose& a, const HeadPose& b) {
    auto same = [](const Float3& p, const Float3& q) { return p.x == q.x && p.y == q.y && p.z == q.z; };
    return same(a.position, b.position) && same(a.right, b.right) && same(a.up, b.up);
}

std::string format(const char* fmt, auto... args) {
    char buf[512];
    std::snprintf(buf, sizeof buf, fmt, args...);
    return buf;
}

}  // namespace

struct WallSession::Impl {
    RunConfig config;
    const std::atomic<bool>* stop = nullptr;
    std::function<void(const std::string&)> log;
    WallConfig wallConfig;
    bool stereo = false;
    bool views = false;  // off-axis views (stereo, tracked, or screens given by corners)
    std::unique_ptr<TrackerReceiver> tracker;
    TrackerState trackerState;
    HeadPose head;
    bool trackerStale = false;
    CameraDesc start;
    std::vector<CameraKey> path;
    RenderSettings baseSettings;  // the wall's resolution and the scene's settings before any operating point
    CodecSettings baseCodec;

    // The scene as loadScene was given it, for replay commands; none for a scene given in code.
    std::optional<std::string> replaySource;

    std::unique_ptr<Master> master;
    std::unique_ptr<LocalClients> processes;
    // A wall on display nodes (issue 19): the screens are on the nodes, the master shows no
    // pixels (a console window at most); local node processes when the config asks for them.
    bool onNodes = false;
    std::unique_ptr<LocalDisplayNodes> nodeProcesses;
    std::vector<std::thread> nodeThreads;  // with clientThreads (tests): runWallNode, headless
    std::atomic<bool> stopNodes{false};
    std::vector<std::string> nodesPresent;  // at the last step, for the log
    uint64_t nodesLeftOut = 0;              // FrameReport::nodesLeftOut at the last step
    bool ranToTheEnd = false;               // every frame asked for was stepped
    std::vector<std::thread> clientThreads;
    std::unique_ptr<LiveScene> live;
    std::unique_ptr<WallInput> input;
    std::unique_ptr<SceneWatcher> watcher;
    std::unique_ptr<WallTuning> tuning;  // the operating point (--target-fps)

    // Per frame.
    int frame = 0;  // frames stepped
    std::vector<double> frameTimes;
    std::chrono::steady_clock::time_point last;
    uint64_t bytes = 0;
    Compositor compositor;      // the running means of stochastic frames go on from step to step
    std::vector<float> linear;  // the frame in linear RGB when it came as linear tiles
    WallFrame shown;
    FrameReport report;
    // Multi-view frames (views): what each setViews asked for, by tag, until its frame is back
    // (async returns the frame begun a step earlier); each view's eye and screens.
    struct ViewSpec {
        uint64_t tag = 0;
        uint64_t trackerPackets = 0;  // the tracker datagrams counted when its head pose was taken
        HeadPose head;
        std::vector<FrameView> views;
    };
    std::deque<ViewSpec> viewSpecs;
    uint64_t nextViewTag = 1;
    std::vector<int> viewEye;                  // -1 (mono), 0 left, 1 right
    std::vector<std::vector<size_t>> viewScreens;  // a view's screens (empty: it is the whole image)
    std::vector<std::vector<float>> viewLinear;
    uint64_t shownTrackerPackets = 0;  // of the head pose the last shown frame was made for
    HeadPose shownHead;
    CameraDesc lastNavigation;
    bool moved = false;                // this frame's view moved (navigation, scripted camera, head): the controller favours speed

    ~Impl() {
        // The master goes first: its goodbye ends the client threads, which are joined after it.
        watcher.reset();
        input.reset();
        live.reset();
        // The nodes show the last frame before the master says goodbye (bounded: a node that
        // stalls is left out of it after the barrier's stall time anyway). Not after a stop,
        // when the wait would throw Cancelled here.
        if (onNodes && ranToTheEnd && master && !stopped() && !master->displayNodesPresent().empty() &&
            !master->waitForSwap(report.frame, 3000))
            log(format("display nodes: frame %u was not swapped within 3 s of its last tile", report.frame));
        master.reset();
        for (std::thread& t : clientThreads) t.join();
        stopNodes = true;  // the master's goodbye ends them; this, one that never joined
        for (std::thread& t : nodeThreads) t.join();
        processes.reset();
        nodeProcesses.reset();
    }

    bool stopped() const { return stop && stop->load(); }

    void startClients() {
        const ClusterSettings& cs = config.cluster;
        const int count = cs.localClients, threads = std::max(1, cs.threadsPerClient);
        if (count == 0) return;
        if (!config.clientThreads) {
            processes = std::make_unique<LocalClients>(count, master->endpoint(), threads, false, std::string{},
                                                       master->localClientArgs(), config.clientExecutable);
            return;
        }
        ClientSettings c;
        c.connect = master->endpoint();
        c.threads = threads;
        c.exitAfterIdleMs = 5000;
        c.faults = config.clientFaults;
        const std::vector<std::string> args = master->localClientArgs();  // --key K --server-key P, with keys
        for (size_t i = 0; i + 1 < args.size(); i += 2) {
            if (args[i] == "--key") c.keyFile = args[i + 1];
            if (args[i] == "--server-key") c.serverKeyFile = args[i + 1];
        }
        for (int i = 0; i < count; ++i) clientThreads.emplace_back([c] { runClient(c); });
    }

    void waitForClients() {
        const ClusterSettings& cs = config.cluster;
        // Remote clients may take a while to be started; local ones are here in seconds, and one
        // that died or froze on the way must not keep the wall dark: go on with the others.
        const int needed = std::max(1, cs.localClients);
        const int waitMs = cs.localClients > 0 ? 60'000 : 600'000;
        if (cs.localClients == 0) log("waiting for clients: rtwall client --connect " + master->endpoint());
        const int joined = master->awaitClients(needed, waitMs, cs.localClients > 0 ? std::max(3000, 2 * cs.timeoutMs) : waitMs);
        if (joined == 0)
            throw InputError("no render client joined " + master->endpoint() + " in time" +
                             (cs.keyFile.empty() ? "" : " (" + describeCounters(master->counters()) +
                                                            "; each client needs --key with its public key in client_keys)"));
        if (joined < needed)
            log(format("only %d of %d %srender clients joined; rendering with them (the others join when they can)", joined,
                       needed, cs.localClients > 0 ? "local " : ""));
    }

    // The wall's screens name display nodes: the master routes every tile to the nodes that show
    // it, each view by its eye.
    void routeToNodes() {
        onNodes = true;
        std::stringstream text;
        if (config.loadedWall) {
            text << writeWallConfig(*config.loadedWall);  // what the nodes parse: loads back equal
        } else {
            std::ifstream in(config.wall, std::ios::binary);
            text << in.rdbuf();
            if (!in) throw InputError(config.wall.string() + ": cannot read it");
        }
        std::vector<int> eyes;
        if (views)
            for (int eye : stereo ? std::vector<int>{0, 1} : std::vector<int>{-1})
                for (size_t i = 0; i < wallViews(wallConfig, staticHead(wallConfig.stereo), eye).size(); ++i) eyes.push_back(eye);
        config.cluster.displayNodes = displayNodeSettings(wallConfig, text.str(), eyes);
    }

    std::string joined(const std::vector<std::string>& names) const {
        std::string out;
        for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
        return out;
    }

    // Starts the local nodes (or says how to start them on their PCs) and waits for all of
    // them, bounded: a node that dies or does not come is said, and the wall runs without it.
    void startNodes() {
        const std::vector<std::string>& names = config.cluster.displayNodes.names;
        if (config.localDisplayNodes && config.clientThreads) {
            for (const std::string& n : names) {
                DisplayNodeOptions o;
                o.connect = master->endpoint();
                o.name = n;
                o.headless = true;  // windows belong to the main thread
                o.out = config.out / n;
                o.exitAfterIdleMs = 5000;
                nodeThreads.emplace_back([this, o] {
                    try {
                        runWallNode(o, &stopNodes);
                    } catch (const std::exception& e) {
                        std::fprintf(stderr, "display node '%s': %s\n", o.name.c_str(), e.what());
                    }
                });
            }
            log("display nodes: " + joined(names) + " as threads of this process, writing to " + (config.out / "NAME").string());
        } else if (config.localDisplayNodes) {
            LocalDisplayNodes::Options o;
            o.headless = config.headless;
            o.outDir = config.out;
            o.extraArgs = master->localClientArgs();
            o.executable = config.clientExecutable;
            nodeProcesses = std::make_unique<LocalDisplayNodes>(names, master->endpoint(), o);
            log("display nodes: started " + joined(names) + " on this PC" +
                (config.headless ? " (headless: each writes its screens to " + (config.out / "NAME").string() + ")" : ""));
        } else {
            for (const std::string& n : names) log("waiting for display node '" + n + "': rtwall display --connect " + master->endpoint() + " --node " + n);
        }
        const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(nodeProcesses ? 30 : 120);
        while (!master->waitForDisplayNodes(200)) {
            reportNodeProcesses();
            if ((nodeProcesses && nodeProcesses->running() == 0) || std::chrono::steady_clock::now() >= end) break;
        }
        nodesPresent = master->displayNodesPresent();
        if (nodesPresent.size() < names.size()) {
            std::vector<std::string> missing;
            for (const std::string& n : names)
                if (std::find(nodesPresent.begin(), nodesPresent.end(), n) == nodesPresent.end()) missing.push_back(n);
            log(format("display nodes: %zu of %zu joined (not there: %s); the wall runs without their screens, they join when they can",
                       nodesPresent.size(), names.size(), joined(missing).c_str()));
        } else {
            log("display nodes: all " + std::to_string(names.size()) + " joined (" + joined(names) + "); the master shows no pixels");
        }
    }

    void reportNodeProcesses() {
        if (nodeProcesses)
            for (const std::string& line : nodeProcesses->takeEnded()) log(line);
    }

    // The nodes' state after a frame: said at once when it changes, and on the console.
    std::string nodeStatus() {
        reportNodeProcesses();
        const std::vector<std::string>& names = config.cluster.displayNodes.names;
        const std::vector<std::string> present = master->displayNodesPresent();
        if (present != nodesPresent) {
            log("display nodes there: " + (present.empty() ? std::string("none") : joined(present)) + format(" (%zu of %zu)", present.size(), names.size()));
            nodesPresent = present;
        }
        if (report.nodesLeftOut > nodesLeftOut)
            log(format("display nodes: %llu more left out of a frame for stalling (%llu in all)",
                       (unsigned long long)(report.nodesLeftOut - nodesLeftOut), (unsigned long long)report.nodesLeftOut));
        nodesLeftOut = report.nodesLeftOut;
        std::string line = format("display nodes %zu/%zu, %llu swaps released, %llu left out, swap skew %.2f ms (max %.2f ms)",
                                  present.size(), names.size(), (unsigned long long)report.swapsReleased,
                                  (unsigned long long)report.nodesLeftOut, report.lastSwapSkew * 1e3, report.maxSwapSkew * 1e3);
        if (present.size() < names.size()) {
            std::vector<std::string> missing;
            for (const std::string& n : names)
                if (std::find(present.begin(), present.end(), n) == present.end()) missing.push_back(n);
            line += " | not there: " + joined(missing);
        }
        return line;
    }

    SceneEdit applyEdit(const SceneDesc& edited) {
        const SceneEdit e = live->applyEdit(edited, tuning->controller() != nullptr, !path.empty() || config.orbit != 0.0);
        if (e.camera) input->setCamera(*e.camera);
        const std::string file = config.scene;
        for (const std::string& r : e.refused) log(file + ": " + r + " (not applied)");
        log(format("%s changed: %zu materials, %zu lights, %zu instance transforms, render settings %s, camera %s, %zu "
                   "section planes, %zu instance visibilities",
                   file.c_str(), e.materials.size(), e.lights.size(), e.transforms.size(), e.settings ? "changed" : "same",
                   e.camera ? "moved" : "same", e.sections.size(), e.visibility.size()));
        return e;
    }

    // One line per tile a client failed: which, why, and the command that renders just that tile
    // again with the frame's camera and settings and the client's packet width. (Changes made to
    // the scene after it was loaded, other than the camera and settings, are not in it.)
    void reportTileFailures() {
        for (const TileFailure& f : master->takeTileFailures()) {
            std::string line = format("client %u failed frame %u, tile %d,%d,%d,%d: ", f.client, f.frame, f.rect.x0, f.rect.y0,
                                      f.rect.x1, f.rect.y1) + f.reason;
            if (replaySource) {
                TileReplay t;
                t.scene = *replaySource;
                t.builtinTriangles = SceneLoadOptions{}.builtinTriangles;  // how the session loads it
                t.origin = live->desc().origin;
                t.camera = f.camera;
                t.settings = f.settings;
                t.trace.packetWidth = f.packetWidth;
                t.trace.clientId = f.client;
                t.frame = f.frame;
                t.rect = f.rect;
                line += " (replay: " + replayCommand(t) + ")";
            } else {
                line += " (no replay command: the scene was given in code)";
            }
            log(line);
        }
    }

    // The head this frame's frusta are made for: the tracked one (predicted to display time, or
    // held after the timeout), else the config's viewer.
    void updateHead() {
        head = staticHead(wallConfig.stereo);
        if (!tracker) return;
        for (const std::string& line : tracker->takeMessages()) log(line);  // said here, on the session's thread
        trackerState = tracker->state();
        if (trackerState.seen) head = trackerState.head;
        if (trackerState.seen && trackerState.stale != trackerStale)
            log(trackerState.stale ? describeTracker(trackerState) : "tracker: the head is back");
        trackerStale = trackerState.seen && trackerState.stale;
        input->setTrackerLine(describeTracker(trackerState));
    }

    // Each view of the wall (both eyes, each plane of a CAVE's screens) with its off-axis
    // camera: its eye, its screens, and its part of the wall image.
    std::vector<FrameView> frameViews() {
        std::vector<FrameView> out;
        viewEye.clear();
        viewScreens.clear();
        const std::vector<int> eyes = stereo ? std::vector<int>{0, 1} : std::vector<int>{-1};
        for (int eye : eyes) {
            const std::vector<WallView> vs = wallViews(wallConfig, head, eye);
            for (size_t i = 0; i < vs.size(); ++i) {
                viewScreens.push_back(vs.size() > 1 ? vs[i].screens : std::vector<size_t>{});
                viewEye.push_back(eye);
                out.push_back(frameView(vs, i));
            }
        }
        return out;
    }

    // View i of an eye's views with its off-axis camera; one plane of several shows (and has
    // rendered) only its screens' pixels.
    FrameView frameView(const std::vector<WallView>& vs, size_t i) {
        FrameView f;
        f.camera = input->viewCamera(vs[i].window);
        if (vs.size() == 1) return f;
        for (size_t screen : vs[i].screens) {
            const PixelRect& r = wallConfig.screens[screen].viewport;
            f.regions.push_back({r.x, r.y, r.width, r.height});
        }
        f.refWidth = wallConfig.width;
        f.refHeight = wallConfig.height;
        return f;
    }

    // What the wall shows of a frame: its views (none: one image) accumulated and composed into
    // the eyes by the one compositor the display nodes use too.
    void compose(const std::vector<FrameView>& rendered, std::vector<Image> images,
                 std::span<const std::vector<float>> linearViews) {
        ComposeFrame f;
        f.views = rendered;
        if (!rendered.empty()) f.eyes = viewEye;
        f.stochastic = report.stochastic;
        f.stateSeq = report.stateSeq;
        f.linear = report.linear;
        EyeImages eyes = compositor.compose(f, std::move(images), linearViews);
        shown.left = std::move(eyes.left);
        shown.right = std::move(eyes.right);
    }

    // Renders the frame (both eyes on a stereo wall) into `shown` and `report`.
    void render() {
        shown = WallFrame{};
        if (views) {
            // Every view's tiles in one scheduler pass. The views go with a tag: with async the
            // frame that comes back was begun with the views of the step before.
            ViewSpec spec{nextViewTag++, trackerState.packets, head, frameViews()};
            master->setViews(spec.views, spec.tag);
            viewSpecs.push_back(std::move(spec));
            std::vector<Image> images = master->renderViews(&report, &viewLinear);
            while (viewSpecs.size() > 1 && viewSpecs.front().tag != report.viewsTag) viewSpecs.pop_front();
            const ViewSpec& rendered = viewSpecs.front();
            shownTrackerPackets = rendered.trackerPackets;
            shownHead = rendered.head;
            if (images.size() != rendered.views.size())
                throw std::runtime_error("internal error: a multi-view frame came back with " + std::to_string(images.size()) +
                                         " images for " + std::to_string(rendered.views.size()) + " views");
            if (!onNodes) compose(rendered.views, std::move(images), viewLinear);  // on nodes the pixels are on the nodes
        } else {
            std::vector<Image> image(1);
            image[0] = master->renderFrame(&report, &linear);
            if (onNodes) shown.left = std::move(image[0]);
            else compose({}, std::move(image), {&linear, 1});
        }
        shown.number = report.frame;
        // The tile grid of the frame as rendered (the `tile` control and [render] edits change it);
        // a multi-view frame shows the owners of its first view's tiles where that is the whole image.
        shown.tileOwners = report.tileOwners;
        if (report.views > 0) {
            const RenderSettings& rs = live->desc().settings;
            shown.tileOwners.resize(std::min(shown.tileOwners.size(), makeTiles(rs.width, rs.height, rs.tileSize).size()));
            if (!viewScreens.empty() && !viewScreens.front().empty()) shown.tileOwners.clear();
        }
        shown.tileSize = live->desc().settings.tileSize;
    }

    std::string nodeLine;  // this frame's nodeStatus()

    void writeFiles() {
        if (config.writeEvery > 0 && frame % config.writeEvery == 0 && !onNodes) {
            const std::filesystem::path file = config.out / format("frame_%06u.png", report.frame);
            // A frame rendered at a lower resolution (operating point) is written as the wall shows it.
            writePng(resizeBilinear(shown.left, baseSettings.width, baseSettings.height), file);
            log("wrote " + file.string());
        }
        if (frame % 10 == 0 || frame == config.frames) {
            const size_t n = std::min<size_t>(10, frameTimes.size());
            const double recent = median(std::vector<double>(frameTimes.end() - long(n), frameTimes.end()));
            const RenderSettings& s = live->desc().settings;
            log(format("frame %d: %.1f fps (median of the last %zu), %.2f MB of tiles, %llu stolen, %llu of %zu tiles kept their client",
                       frame, 1.0 / recent, n, double(report.bytes) * 1e-6, (unsigned long long)report.tilesStolen,
                       (unsigned long long)report.affinityHits,
                       // A multi-view frame's tiles are those of all its views.
                       report.views > 0 ? report.tileOwners.size() : makeTiles(s.width, s.height, s.tileSize).size()) +
                (onNodes ? "; " + nodeLine : std::string()));
        }
    }
};

WallSession::WallSession(RunConfig config, const std::atomic<bool>* stop) : impl_(std::make_unique<Impl>()) {
    Impl& s = *impl_;
    s.config = std::move(config);
    s.stop = stop;
    s.log = s.config.log ? s.config.log : [](const std::string& line) {
        std::printf("%s\n", line.c_str());
        std::fflush(stdout);
    };
    RunConfig& c = s.config;
    if (c.watch && (c.loaded || sceneSourceKind(c.scene) != SceneSourceKind::SceneFile))
        throw InputError("--watch needs a scene file (.toml); " + c.scene + " is not one");
    if (!c.loaded) s.replaySource = c.scene;
    SceneDesc desc = c.loaded ? std::move(*c.loaded) : loadScene(c.scene);
    c.loaded.reset();
    if (c.width) desc.settings.width = c.width;
    if (c.height) desc.settings.height = c.height;
    // The wall decides the image size; its config and shaders are checked before anything starts.
    s.wallConfig = singleScreenWall(desc.settings.width, desc.settings.height);
    if (c.hasWall()) {
        s.wallConfig = c.loadedWall ? *c.loadedWall : loadWallConfig(c.wall);
        const std::vector<std::string> problems = checkWall(s.wallConfig);
        if (!problems.empty()) throw InputError(problems.front());
    }
    s.stereo = s.wallConfig.stereo.mode != StereoMode::None;
    s.views = wallHasViews(s.wallConfig);
    if (!s.wallConfig.nodes().empty()) {
        if (c.targetFps > 0 && c.front.empty())
            throw InputError("--target-fps on a wall of display nodes needs --front: the master holds no pixels to calibrate with");
        s.routeToNodes();
    }
    fitToRun(desc, c, s.wallConfig);
    s.start = desc.cameras.front();
    s.baseSettings = desc.settings;
    s.baseCodec = c.cluster.codec;
    if (!c.cameraPath.empty()) s.path = readCameraPath(c.cameraPath, desc.origin);
    // A given front is checked before anything starts: a mistake in it is one line, at once.
    std::vector<OperatingPoint> givenFront;
    if (!c.front.empty()) {
        if (c.targetFps <= 0) throw InputError("--front needs --target-fps");
        givenFront = readFront(c.front);
        for (const OperatingPoint& p : givenFront) knobsOf(p, desc.settings, c.cluster.codec);  // unknown controls fail now
    }
    if (!c.trace.empty() && c.targetFps <= 0) throw InputError("--trace needs --target-fps");

    s.master = std::make_unique<Master>(desc, c.cluster);
    s.master->setStopFlag(stop);
    s.log(format("rtwall master at %s, %dx%d, %d local clients, codec %s%s", s.master->endpoint().c_str(), desc.settings.width,
                 desc.settings.height, c.cluster.localClients, tileCodecName(c.cluster.codec.codec),
                 c.cluster.async ? ", asynchronous" : ""));
    // Nodes first: a client learns where they are when it joins and connects to them while it
    // builds the scene (a tile sent to a node it is not yet connected to is dropped).
    if (s.onNodes) s.startNodes();
    s.startClients();
    s.waitForClients();
    s.live = std::make_unique<LiveScene>(std::move(desc), *s.master);
    if (s.wallConfig.tracking.enabled) {
        const TrackingConfig& t = s.wallConfig.tracking;
        s.tracker = std::make_unique<TrackerReceiver>(t);
        const std::string from = t.kind == TrackingSource::Vrpn ? "VRPN " + t.server + " (tcp " + t.address + ":" + std::to_string(t.port) + ")"
                                                                : format("ART DTrack on udp %s:%d", t.address.c_str(), s.tracker->port());
        s.log(format("tracker: listening for %s (head body %d%s%s)", from.c_str(), t.headBody,
                     t.flystick >= 0 ? format(", flystick %d", t.flystick).c_str() : "",
                     t.predictionMs > 0 ? format(", predicted %.0f ms ahead", t.predictionMs).c_str() : ""));
    }

    WallInput::Options io;
    io.forceHeadless = c.headless;
    io.perScreenImages = c.hasWall();
    io.outDir = c.out;
    io.interactive = s.path.empty();
    io.codec = tileCodecName(c.cluster.codec.codec);
    io.console = s.onNodes;
    s.input = std::make_unique<WallInput>(s.wallConfig, s.start, io, s.log);
    s.input->setPartView(*s.live, {});  // says what the scene file and the command line hid, if anything
    // In a window the wall runs until it is closed, unless a frame count was asked for.
    if (s.input->windowed() && !c.framesGiven) c.frames = 0;
    if (s.views) {
        // The views from the start: a calibration's frames then cost what the wall's frames do.
        s.head = staticHead(s.wallConfig.stereo);
        s.viewSpecs.push_back({0, 0, s.head, s.frameViews()});
        s.master->setViews(s.viewSpecs.back().views, 0);
    }
    s.tuning = std::make_unique<WallTuning>(*s.master, *s.live, s.baseSettings, s.baseCodec, s.log);
    s.tuning->start(c.targetFps, givenFront, c.trace);
    if (c.watch) {
        const std::filesystem::path file = c.scene;
        const RunConfig fitConfig = c;
        const WallConfig wall = s.wallConfig;
        s.watcher = std::make_unique<SceneWatcher>(
            file,
            [file, fitConfig, wall] {
                SceneDesc d = loadSceneFile(file);
                fitToRun(d, fitConfig, wall);
                return d;
            },
            s.log);
        s.log("watching " + file.string() +
              ": edits to materials, lights, instance transforms, render settings, the camera and section planes "
              "are sent as they are saved");
    }
    s.last = std::chrono::steady_clock::now();
}

WallSession::~WallSession() = default;

bool WallSession::step() {
    Impl& s = *impl_;
    if (s.stopped() || (s.config.frames > 0 && s.frame >= s.config.frames)) return false;
    const double dt = s.frameTimes.empty() ? 0.0 : s.frameTimes.back();
    if (!s.input->handle(*s.live, dt)) return false;
    ++s.frame;
    if (s.watcher)
        if (std::optional<SceneDesc> edited = s.watcher->poll()) s.applyEdit(*edited);
    // A scripted camera: a path, or the orbit (without a window, where nobody navigates).
    std::optional<CameraDesc> scripted;
    if (!s.path.empty()) scripted = cameraAt(s.path, s.frame);
    else if (s.config.orbit != 0.0 && !s.input->windowed()) scripted = orbitCamera(s.start, s.config.orbit * s.frame);
    if (scripted) {
        // A stereo wall sends each eye's camera before its render: this one merges away.
        s.input->setCamera(*scripted);
        s.live->setCamera(*scripted);
    }
    const CameraDesc navigation = s.input->camera();
    const HeadPose headBefore = s.head;
    if (s.views) s.updateHead();
    if (s.tracker) s.input->handleWand(*s.live, s.trackerState, dt);  // the flystick navigates, picks and drags
    // Motion, for the controller: the viewer's camera or the tracked head moved since the last frame.
    s.moved = s.frame > 1 && (!(navigation == s.lastNavigation) || !samePose(headBefore, s.head));
    s.lastNavigation = navigation;
    try {
        s.render();
    } catch (...) {
        s.reportTileFailures();  // the failure may be why the frame could not finish
        throw;
    }
    s.reportTileFailures();
    if (s.tracker) s.input->drawWand(s.shown, s.head);
    const auto now = std::chrono::steady_clock::now();
    s.frameTimes.push_back(std::chrono::duration<double>(now - s.last).count());
    s.last = now;
    if (s.onNodes) {
        s.nodeLine = s.nodeStatus();
        s.input->showConsole(s.nodeLine, s.report, s.frameTimes.back());
    } else {
        s.input->show(s.shown, s.report, s.frameTimes.back());
    }
    s.bytes += s.report.bytes;
    s.tuning->observe(s.frame, s.report, s.moved);
    s.writeFiles();
    s.ranToTheEnd = s.config.frames > 0 && s.frame >= s.config.frames;
    return true;
}

const SceneDesc& WallSession::scene() const { return impl_->live->desc(); }
CameraDesc WallSession::camera() const { return impl_->input->camera(); }
void WallSession::setCamera(const CameraDesc& camera) {
    impl_->input->setCamera(camera);
    impl_->live->setCamera(camera);
}
void WallSession::setInstanceTransform(uint32_t instance, const Transform& transform) {
    impl_->live->setInstanceTransform(instance, transform);
}
void WallSession::setMaterial(uint32_t material, const Material& value) { impl_->live->setMaterial(material, value); }
void WallSession::setLight(uint32_t light, const Light& value) { impl_->live->setLight(light, value); }
void WallSession::setRenderSettings(const RenderSettings& settings) { impl_->live->setRenderSettings(settings); }
void WallSession::setSection(uint32_t index, const SectionPlane& plane) { impl_->input->setSection(*impl_->live, index, plane); }
int WallSession::activeSection() const { return impl_->input->activeSection(); }
void WallSession::setCodec(const CodecSettings& codec) { impl_->master->setCodec(codec); }
SceneEdit WallSession::applyEdit(const SceneDesc& edited) { return impl_->applyEdit(edited); }
std::optional<PickResult> WallSession::pick(double wallX, double wallY) { return impl_->input->pick(*impl_->live, wallX, wallY); }
void WallSession::setMeasuring(bool on) { impl_->input->setMeasuring(on); }
bool WallSession::measuring() const { return impl_->input->measuring(); }
bool WallSession::measurePick(double wallX, double wallY) { return impl_->input->measurePick(*impl_->live, wallX, wallY); }
std::optional<Measurement> WallSession::measurement() const { return impl_->input->measurement(); }
void WallSession::showTileOwners(bool on) { impl_->input->showTileOwners(on); }
void WallSession::setPartView(const PartView& view) { impl_->input->setPartView(*impl_->live, view); }
const PartView& WallSession::partView() const { return impl_->live->partView(); }
void WallSession::showAllParts() { impl_->input->showAllParts(*impl_->live); }
void WallSession::inject(const InputState& input) { impl_->input->inject(input); }
double WallSession::navigationScale() const { return impl_->input->navigationScale(); }
const WallFrame& WallSession::lastFrame() const { return impl_->shown; }
std::optional<TrackerState> WallSession::tracker() const {
    if (!impl_->tracker) return std::nullopt;
    return impl_->tracker->state();
}
int WallSession::trackerPort() const { return impl_->tracker ? impl_->tracker->port() : 0; }
const HeadPose& WallSession::lastHead() const { return impl_->head; }
std::optional<WandPose> WallSession::wand() const { return impl_->input->wand(); }
uint64_t WallSession::shownTrackerPackets() const { return impl_->shownTrackerPackets; }
const HeadPose& WallSession::shownHead() const { return impl_->shownHead; }
size_t WallSession::viewRestarts() const { return impl_->compositor.viewRestarts(); }
const FrameReport& WallSession::lastReport() const { return impl_->report; }
std::string WallSession::endpoint() const { return impl_->master->endpoint(); }
bool WallSession::windowed() const { return impl_->input->windowed(); }

RunSummary WallSession::summary() const {
    const Impl& s = *impl_;
    RunSummary r;
    r.frames = s.frameTimes.size();
    r.medianFps = r.frames ? 1.0 / median(s.frameTimes) : 0.0;
    r.megabytesPerFrame = r.frames ? double(s.bytes) * 1e-6 / double(r.frames) : 0.0;
    r.accumulatedFrames = s.compositor.accumulatedFrames();
    r.linearFrames = s.compositor.linearFrames();
    if (const OperatingPointController* c = s.tuning ? s.tuning->controller() : nullptr) {
        r.framesOnTarget = s.tuning->framesOnTarget();
        r.operatingPointChanges = c->changes();
        r.operatingPoint = c->current().name;
    }
    r.counters = s.master->counters();
    return r;
}

std::string describeSummary(const RunSummary& r, double targetFps) {
    std::string out;
    if (r.frames > 0) {
        out += format("%zu frames, median %.1f fps, %.2f MB of tiles per frame\n", r.frames, r.medianFps, r.megabytesPerFrame);
        if (r.accumulatedFrames > 0)
            out += format("progressive refinement: %d of %zu frames accumulated (stochastic scene), %d of them as linear tiles\n",
                          r.accumulatedFrames, r.frames, r.linearFrames);
        else
            out += "no accumulation: the scene is deterministic (every frame of a view is the same image)\n";
        if (targetFps > 0)
            out += format("target %.1f fps: %zu of %zu frames within budget (master frame time), %llu operating-point "
                          "changes, ending at '%s'\n",
                          targetFps, r.framesOnTarget, r.frames, (unsigned long long)r.operatingPointChanges,
                          r.operatingPoint.c_str());
    }
    return out + "master: " + describeCounters(r.counters);
}

}  // namespace rtwall
