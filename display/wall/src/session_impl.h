// WallSession's state (session.cpp): shared by the files that make up the master's loop
// (session.cpp, the frame and its presentation; session_reproject.cpp, the refresh loop that
// re-projects while the cluster renders).
#pragma once

#include "live_scene.h"
#include "refresher.h"
#include "scene_watcher.h"
#include "tuning.h"
#include "wall_input.h"

#include <rtwall/frame.h>
#include <rtwall/mpcdi.h>
#include <rtwall/wall.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <fstream>
#include <mutex>
#include <span>
#include <sstream>
#include <thread>

namespace rtwall {

namespace wall {
template <class... Args>
std::string format(const char* fmt, Args... args) {
    char buf[512];
    std::snprintf(buf, sizeof buf, fmt, args...);
    return buf;
}
}  // namespace wall

using wall::format;
using wall::LiveScene;
using wall::Refresher;
using wall::SceneWatcher;
using wall::WallTuning;
using wall::WallInput;

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
    // Per screen of a calibrated wall: its warp grids' indexes (ClusterSettings::warpGrids) and
    // rectangles in wall pixels; empty without [warp].
    std::vector<std::vector<std::pair<uint32_t, ViewRegion>>> screenWarps;
    std::unique_ptr<ProjectorBlendStage> blend;  // its alpha and beta maps on the master's screens
    std::unique_ptr<PostWarpStage> postWarp;     // [warp] mode = "post": the screens' flat images resampled
    // The post-warp resamples from the eyes the shown image was made for: the head its frame
    // was rendered with (with async frames, a step older than the newest), or re-projecting,
    // the pose it was warped to. On display nodes the eyes go with each frame and pose.
    std::array<Float3, 2> postWarpEyes(const HeadPose& h) const {
        const double sep = wallConfig.stereo.eyeSeparation;
        if (stereo) return {eyePosition(h, sep, 0), eyePosition(h, sep, 1)};
        return {eyePosition(h, sep, -1), eyePosition(h, sep, -1)};
    }
    std::optional<std::array<Float3, 2>> nodeEyes(const HeadPose& h) const {
        if (!postWarp || !onNodes) return std::nullopt;
        return postWarpEyes(h);
    }
    void setPostWarpEyes() {
        if (!postWarp) return;
        const std::array<Float3, 2> e = postWarpEyes(shownHead);
        postWarp->setEyes(e[0], e[1]);
    }
    std::atomic<bool> stopNodes{false};
    std::atomic<size_t> nodeThreadsEnded{0};
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
        std::chrono::steady_clock::time_point posed = std::chrono::steady_clock::now();  // when the head pose was read
    };
    std::deque<ViewSpec> viewSpecs;
    uint64_t nextViewTag = 1;
    std::vector<int> viewEye;                  // -1 (mono), 0 left, 1 right
    std::vector<std::vector<size_t>> viewScreens;  // a view's screens (empty: it is the whole image)
    std::vector<std::vector<float>> viewLinear;
    uint64_t shownTrackerPackets = 0;  // of the head pose the last shown frame was made for
    HeadPose shownHead;
    std::chrono::steady_clock::time_point shownPosed;  // when that head pose was read
    CameraDesc lastNavigation;

    // Re-projection (issue 27; session_reproject.cpp): the cluster renders on the refresher's
    // worker while this thread shows the newest frame at every refresh, warped to the head pose
    // read just before each presentation (late latching). The clients send depth with every tile.
    bool reproject = false;
    bool warpDebug = false;
    std::unique_ptr<Refresher> refresher;
    std::vector<std::vector<float>> viewDepth;  // the rendered frame's, per view
    std::vector<CameraDesc> targets;            // per view: its camera for the latched pose
    std::deque<Presentation> presentations;     // since takePresentations()
    std::deque<NodeRefreshDelay> nodeRefreshes;  // on display nodes: the refreshes they answered
    void collectNodeRefreshes();
    // Denoising (issue 28): frames of a stochastic scene come with their features and depth and
    // the compositor filters them (rtwall/denoise.h); `denoise` is the scene's [denoise] (or
    // --denoise) as the cluster was started for it.
    DenoiseSettings denoise;
    bool denoising() const { return denoise.mode != DenoiseSettings::Mode::Off; }
    // The mode whose features the clients send (the scene's, or the most demanding one an
    // operating point of --front names): a mode that reads no more switches at once.
    DenoiseSettings::Mode sentFeatures = DenoiseSettings::Mode::Off;
    // Switches the filter (an edit, an operating point): true if applied, else one line naming
    // `who` and why (the clients do not send its features: a restart would).
    bool setDenoiseMode(DenoiseSettings::Mode mode, const std::string& who) {
        if (mode == denoise.mode) return true;
        const uint8_t need = featureBitsFor(mode);
        if (need && !config.cluster.wideAccumulation) {
            log(format("%s mode %s: not applied: it needs linear tiles (the cluster's wide accumulation)", who.c_str(),
                       denoiseModeName(mode)));
            return false;
        }
        if ((need & ~config.cluster.features) != 0 || (need && !config.cluster.depth)) {
            log(format("%s mode %s needs a restart (the clients send the features of %s)", who.c_str(), denoiseModeName(mode),
                       denoiseModeName(sentFeatures)));
            return false;
        }
        denoise.mode = mode;
        log(format("denoise: %s", denoiseModeName(denoise.mode)));
        return true;
    }
    // The ring of pixels each screen's window is filtered with (ComposeFrame::denoiseRing), fixed
    // at the start; and the windows of the frame size and views last composed.
    int denoiseRing = 0;
    std::vector<std::vector<TileRect>> windowRects;
    int windowsWidth = -1, windowsHeight = -1;
    std::vector<FrameView> windowsViews;  // their regions
    std::vector<FeatureImages> viewFeatures;       // the rendered frame's, per view
    std::vector<std::vector<float>> monoLinear;    // a frame without views, as renderViews gives it
    // Before the master starts: the features the clients send, for the scene's mode or the most
    // demanding one the operating points name (`frontMost`).
    void decideDenoising(const SceneDesc& desc, DenoiseSettings::Mode frontMost);
    bool reprojects() const;     // what decideReprojection will decide, before it is said
    void decideReprojection();   // before the master starts: whether, and depth from the clients
    void latchTargets();         // targets := the views' cameras for the head pose read now
    void startRefresher();       // once the wall's windows are open
    std::vector<Image> renderWhileRefreshing();
    void latchAndWarp();         // shown := the newest frame warped for the pose read now
    void warpOnGpu();            // ... by the GL presenter
    void presentRefresh();
    void recordPresentation(bool warped);
    // The operator (issue 31; operator.cpp): commands posted from other threads, run at the next
    // step after the input; observers called after each step; bookmarks; a camera flight.
    std::mutex commandsMutex;
    std::vector<std::function<void(WallSession&)>> commands;
    std::vector<std::function<void(const WallSession&)>> observers;
    std::vector<Bookmark> bookmarks;
    struct Flight {
        CameraDesc from, to;
        std::chrono::steady_clock::time_point start;
        double seconds = 0;
    };
    std::optional<Flight> flight;
    std::vector<Transform> loadedTransforms;  // the instances' as the scene was loaded
    void runOperator(WallSession& self);
    void notifyObservers(const WallSession& self);
    bool moved = false;                // this frame's view moved (navigation, scripted camera, head): the controller favours speed

    ~Impl() {
        refresher.reset();  // its worker renders nothing between steps
        // The master goes first: its goodbye ends the client threads, which are joined after it.
        watcher.reset();
        input.reset();
        live.reset();
        // The nodes show the last frame before the master says goodbye (bounded: a node that
        // stalls is left out of it after the barrier's stall time anyway). Not after a stop,
        // when the wait would throw Cancelled here.
        const bool nodesFinish = onNodes && ranToTheEnd && master && !stopped() && !master->displayNodesPresent().empty();
        if (nodesFinish && !master->waitForSwap(report.frame, 3000))
            log(format("display nodes: frame %u was not swapped within 3 s of its last tile", report.frame));
        master.reset();
        for (std::thread& t : clientThreads) t.join();
        // The swap's release is not its showing: a node reads the swap, shows the frame (denoised
        // and written, seconds on a loaded PC), then the goodbye, and ends. Stopped before that, it
        // would never show the last frame. So the nodes get time to end on their own (bounded).
        if (nodesFinish) {
            const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
            if (nodeProcesses && !nodeProcesses->awaitEnd(20'000)) log("display nodes: not ended 20 s after the goodbye; stopped");
            while (nodeThreadsEnded < nodeThreads.size() && std::chrono::steady_clock::now() < until)
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
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
        const double stallSeconds = config.cluster.displayNodes.stallSeconds;  // the caller's, if set
        config.cluster.displayNodes = displayNodeSettings(wallConfig, text.str(), eyes, reprojects(), denoiseRing);
        config.cluster.displayNodes.stallSeconds = stallSeconds;
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
                    ++nodeThreadsEnded;
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
        if (reproject) {
            // The last 100 refreshes the nodes answered: latched pose to each node's answer.
            collectNodeRefreshes();
            std::vector<double> ms;
            for (size_t i = nodeRefreshes.size() > 100 ? nodeRefreshes.size() - 100 : 0; i < nodeRefreshes.size(); ++i)
                ms.push_back(nodeRefreshes[i].milliseconds);
            line += ms.empty() ? std::string(", no refresh answered yet")
                               : format(", pose to node shown %.1f ms (median of %zu)", median(ms), ms.size());
        }
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
        if (e.denoise) setDenoiseMode(e.denoise->mode, file + ": [denoise]");
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
        forEachView(head, [&](int eye, const std::vector<WallView>& vs, size_t i) {
            viewScreens.push_back(vs.size() > 1 ? vs[i].screens : std::vector<size_t>{});
            viewEye.push_back(eye);
            out.push_back(frameView(vs, i));
        });
        return out;
    }

    // f(eye, the eye's views, i) for every view of the wall for `pose`, eye by eye: the order of
    // a frame's views.
    template <class F> void forEachView(const HeadPose& pose, F&& f) {
        static constexpr int kStereo[2] = {0, 1}, kMono[1] = {-1};
        for (int eye : stereo ? std::span<const int>(kStereo) : std::span<const int>(kMono)) {
            const std::vector<WallView> vs = wallViews(wallConfig, pose, eye);
            for (size_t i = 0; i < vs.size(); ++i) f(eye, vs, i);
        }
    }

    // The camera that shows wall pixel (x, y) (WallInput::setPickCamera): the view whose part of
    // the wall holds it (the left eye's of a stereo wall), off-axis, through its calibration's
    // warps, as the frame renders it; none on a pixel no view shows.
    std::optional<Camera> pickCamera(double x, double y) {
        std::optional<Camera> out;
        forEachView(head, [&](int eye, const std::vector<WallView>& vs, size_t i) {
            if (out || eye == 1) return;
            const FrameView f = frameView(vs, i);
            bool inside = f.regions.empty();
            for (const ViewRegion& r : f.regions) inside = inside || (x >= r.x && x < r.x + r.width && y >= r.y && y < r.y + r.height);
            if (inside) out.emplace(f.camera, wallConfig.width, wallConfig.height, frameWarps(f, config.cluster.warpGrids, wallConfig.width, wallConfig.height));
        });
        return out;
    }

    // View i of an eye's views with its off-axis camera; one plane of several shows (and has
    // rendered) only its screens' pixels.
    // A calibrated screen's projector pixels look where its warps say (issue 30), the room
    // placed in the world as the view's window is.
    FrameView frameView(const std::vector<WallView>& vs, size_t i) {
        FrameView f;
        f.camera = input->viewCamera(vs[i].window);
        if (!screenWarps.empty()) {
            const RoomToWorld room = input->roomToWorld();
            for (size_t screen : vs[i].screens)
                for (const auto& [grid, rect] : screenWarps[screen]) f.warps.push_back({grid, rect, room});
            if (!f.warps.empty()) {
                f.refWidth = wallConfig.width;
                f.refHeight = wallConfig.height;
            }
        }
        if (vs.size() == 1) return f;
        for (size_t screen : vs[i].screens) {
            const PixelRect& r = wallConfig.screens[screen].viewport;
            f.regions.push_back({r.x, r.y, r.width, r.height});
        }
        f.refWidth = wallConfig.width;
        f.refHeight = wallConfig.height;
        return f;
    }

    // Reads the wall's calibration ([warp], already checked): its grids go to the clients once
    // (ClusterSettings::warpGrids), and each frame's views name them (screenWarps).
    void loadWarps(ClusterSettings& cluster) {
        const MpcdiFile file = readMpcdi(wallConfig.warp->mpcdi);
        blend = std::make_unique<ProjectorBlendStage>(wallConfig, file);
        if (wallConfig.warp->mode == WarpMode::Post) {
            // The comparison mode: flat renders, resampled through the warp on the screens: the
            // master's here, a display node's there (each frame tells the nodes its eyes).
            postWarp = std::make_unique<PostWarpStage>(wallConfig, file);
            log(format("warp: %s, post-warp: flat renders resampled through the calibration on the screens (%s profile)",
                       wallConfig.warp->mpcdi.filename().string().c_str(), mpcdiProfileName(file.profile)));
            return;
        }
        screenWarps.assign(wallConfig.screens.size(), {});
        size_t regions = 0;
        for (WallWarp& w : wallWarps(wallConfig, file))
            for (ScreenWarp& r : w.regions) {
                screenWarps[w.screen].emplace_back(uint32_t(cluster.warpGrids.size()),
                                                   ViewRegion{r.rect.x0, r.rect.y0, r.rect.width(), r.rect.height()});
                cluster.warpGrids.push_back(std::move(r.warp));
                ++regions;
            }
        log(format("warp: %s, %zu projector regions on %zu screens, rays through each projector pixel (%s profile)",
                   wallConfig.warp->mpcdi.filename().string().c_str(), regions, wallConfig.warp->buffers.size(),
                   mpcdiProfileName(file.profile)));
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
        if (reproject || denoising()) f.depth = viewDepth;
        f.keepForWarp = reproject;  // the frame becomes the warp's newest source
        if (denoising()) {
            f.denoise = live->desc().denoise;
            f.denoise.mode = denoise.mode;  // the cluster sends the features of the mode it began with
            f.features = viewFeatures;
            f.camera = report.camera;
            f.sceneSeq = report.sceneSeq;  // a camera move re-projects the history, an edit discards it
            // The wall's screens, each with its ring, as the display nodes filter theirs.
            const int w = images.empty() ? 0 : images.front().width, h = images.empty() ? 0 : images.front().height;
            bool same = windowsWidth == w && windowsHeight == h && windowsViews.size() == rendered.size();
            for (size_t v = 0; same && v < rendered.size(); ++v)
                same = windowsViews[v].regions == rendered[v].regions && windowsViews[v].refWidth == rendered[v].refWidth &&
                       windowsViews[v].refHeight == rendered[v].refHeight;
            if (!same) {
                windowRects.clear();
                if (w > 0 && h > 0 && w <= wallConfig.width && h <= wallConfig.height)
                    windowRects = denoiseWindowRects(denoiseWindows(TileRouting(wallConfig, w, h), w, h, rendered, viewEye));
                windowsWidth = w, windowsHeight = h;
                windowsViews = rendered;
            }
            f.denoiseWindows = windowRects;
            f.denoiseRing = denoiseRing;
        }
        EyeImages eyes = compositor.compose(f, std::move(images), linearViews);
        shown.left = std::move(eyes.left);
        shown.right = std::move(eyes.right);
    }

    // Renders the frame (both eyes on a stereo wall) into `shown` and `report`.
    void render() {
        if (!reproject) shown = WallFrame{};
        if (onNodes && denoising()) {  // the nodes filter as compose() would
            DenoiseSettings d = live->desc().denoise;
            d.mode = denoise.mode;
            master->setDenoise(d, denoiseRing);
            // Each frame's history is the frame before: the master begins a frame only once the
            // one two before it was swapped (Master::renderViews), so none is overtaken unseen.
        }  // re-projecting, the refreshes show it while the next frame renders
        if (views) {
            // Every view's tiles in one scheduler pass. The views go with a tag: with async the
            // frame that comes back was begun with the views of the step before.
            ViewSpec spec{nextViewTag++, trackerState.packets, head, frameViews()};
            master->setViews(spec.views, spec.tag, nodeEyes(spec.head));
            viewSpecs.push_back(std::move(spec));
            std::vector<Image> images = reproject ? renderWhileRefreshing()
                                                  : master->renderViews(&report, &viewLinear, denoising() ? &viewDepth : nullptr,
                                                                        denoising() ? &viewFeatures : nullptr);
            while (viewSpecs.size() > 1 && viewSpecs.front().tag != report.viewsTag) viewSpecs.pop_front();
            const ViewSpec& rendered = viewSpecs.front();
            shownTrackerPackets = rendered.trackerPackets;
            shownHead = rendered.head;
            shownPosed = rendered.posed;
            if (images.size() != rendered.views.size())
                throw std::runtime_error("internal error: a multi-view frame came back with " + std::to_string(images.size()) +
                                         " images for " + std::to_string(rendered.views.size()) + " views");
            if (!onNodes) compose(rendered.views, std::move(images), viewLinear);  // on nodes the pixels are on the nodes
            if (reproject) latchAndWarp();  // the new frame too is shown for the newest pose
        } else {
            std::vector<Image> image(1);
            if (denoising()) {  // the frame's depth and features too
                image = master->renderViews(&report, &monoLinear, &viewDepth, &viewFeatures);
                if (onNodes) shown.left = std::move(image[0]);  // the nodes filter their screens
                else compose({}, std::move(image), monoLinear);
            } else {
                image[0] = master->renderFrame(&report, &linear);
                if (onNodes) shown.left = std::move(image[0]);
                else compose({}, std::move(image), {&linear, 1});
            }
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

}  // namespace rtwall
