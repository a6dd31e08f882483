// WallSession: the display master's frame loop (what `rtwall run` runs).
#include "session_impl.h"

namespace rtwall {

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

}  // namespace

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
        if (s.wallConfig.warp) s.loadWarps(c.cluster);
    }
    s.stereo = s.wallConfig.stereo.mode != StereoMode::None;
    s.views = wallHasViews(s.wallConfig) || s.wallConfig.warp;  // warps travel with views; the post-warp's flat renders are the screens' frames
    if (!s.wallConfig.nodes().empty()) {
        if (c.targetFps > 0 && c.front.empty())
            throw InputError("--target-fps on a wall of display nodes needs --front: the master holds no pixels to calibrate with");
        s.onNodes = true;  // routed below, once re-projection and denoising are decided (their rings)
    }
    fitToRun(desc, c, s.wallConfig);
    s.start = desc.cameras.front();
    s.baseSettings = desc.settings;
    s.baseCodec = c.cluster.codec;
    if (!c.cameraPath.empty()) s.path = readCameraPath(c.cameraPath, desc.origin);
    // A given front is checked before anything starts: a mistake in it is one line, at once.
    std::vector<OperatingPoint> givenFront;
    DenoiseSettings::Mode frontDenoise = DenoiseSettings::Mode::Off;  // the most demanding mode a point names
    if (!c.front.empty()) {
        if (c.targetFps <= 0) throw InputError("--front needs --target-fps");
        givenFront = readFront(c.front);
        for (const OperatingPoint& p : givenFront)  // unknown controls fail now
            if (const Knobs k = knobsOf(p, desc.settings, c.cluster.codec); k.denoise) frontDenoise = std::max(frontDenoise, *k.denoise);
    }
    if (!c.trace.empty() && c.targetFps <= 0) throw InputError("--trace needs --target-fps");

    s.decideReprojection();
    if (c.denoise) desc.denoise.mode = *c.denoise;
    s.decideDenoising(desc, frontDenoise);
    if (s.onNodes) s.routeToNodes();
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
    if (s.postWarp) io.stages.push_back(s.postWarp.get());  // resampled first, then blended
    if (s.blend) io.stages.push_back(s.blend.get());
    s.input = std::make_unique<WallInput>(s.wallConfig, s.start, io, s.log);
    // Clicks pick (and measure) with the view that shows the pixel, as it was rendered.
    if (s.views) s.input->setPickCamera([&s](double x, double y) { return s.pickCamera(x, y); });
    s.input->setPartView(*s.live, {});  // says what the scene file and the command line hid, if anything
    for (const InstanceDesc& in : s.live->desc().instances) s.loadedTransforms.push_back(in.transform);
    if (!c.session.empty()) restoreSession(readSessionState(c.session, s.live->desc()));
    // In a window the wall runs until it is closed, unless a frame count was asked for.
    if (s.input->windowed() && !c.framesGiven) c.frames = 0;
    s.startRefresher();
    if (s.views) {
        // The views from the start: a calibration's frames then cost what the wall's frames do.
        s.head = staticHead(s.wallConfig.stereo);
        s.viewSpecs.push_back({0, 0, s.head, s.frameViews()});
        s.master->setViews(s.viewSpecs.back().views, 0, s.nodeEyes(s.head));
    }
    s.tuning = std::make_unique<WallTuning>(*s.master, *s.live, s.baseSettings, s.baseCodec, s.log,
                                            [&s](DenoiseSettings::Mode m) { s.setDenoiseMode(m, "operating point: denoise"); });
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
    s.runOperator(*this);  // the console's commands, after the keys'
    if (s.input->takeWarpDebugPresses() % 2) {
        s.warpDebug = !s.warpDebug;
        s.log(std::string("reproject: debug colours ") + (s.warpDebug ? "on" : "off"));
    }
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
        if (s.reproject) {
            s.recordPresentation(true);
            s.refresher->presented();
        }
    } else {
        s.setPostWarpEyes();
        s.input->show(s.shown, s.report, s.frameTimes.back());
        s.recordPresentation(s.reproject);
        if (s.refresher) s.refresher->presented();
    }
    s.bytes += s.report.bytes;
    s.tuning->observe(s.frame, s.report, s.moved);
    s.writeFiles();
    s.ranToTheEnd = s.config.frames > 0 && s.frame >= s.config.frames;
    s.notifyObservers(*this);
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

std::optional<NodePicture> WallSession::nodePicture(int width, std::chrono::milliseconds timeout) const {
    if (!impl_->onNodes) return std::nullopt;
    return impl_->master->nodePicture(width, int(std::min<int64_t>(timeout.count(), INT32_MAX)));
}
bool WallSession::windowed() const { return impl_->input->windowed(); }

RunSummary WallSession::summary() const {
    const Impl& s = *impl_;
    RunSummary r;
    r.frames = s.frameTimes.size();
    r.medianFps = r.frames ? 1.0 / median(s.frameTimes) : 0.0;
    r.megabytesPerFrame = r.frames ? double(s.bytes) * 1e-6 / double(r.frames) : 0.0;
    r.accumulatedFrames = s.compositor.accumulatedFrames();
    r.onNodes = s.onNodes;
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
        if (r.onNodes)
            out += "the display nodes composed the frames (accumulated or denoised there; the master holds no pixels)\n";
        else if (r.accumulatedFrames > 0)
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
