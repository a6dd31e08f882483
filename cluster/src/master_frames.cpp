// Frame sequencing: the network thread runs the application's commands in sequence order, begins
// a frame and finishes it; the application thread begins frames and waits for them
// (Master::renderViews).
#include "master_impl.h"

#include <rtwall/denoise.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace rtwall {

void Master::Impl::beginFrame(Command&& cmd) {
    const uint32_t frame = cmd.frame, stateSeq = cmd.update.seq;
    const RenderSettings& rs = cmd.settings;
    const TilePixels pixels = cmd.pixels;
    currentFrame = frame;
    framePixels = pixels;
    frameStochastic = cmd.stochastic;
    // Features travel with linear frames only (the denoiser works in linear light). Display
    // nodes denoise what they hold as the application said (setDenoise), with a mode whose
    // features the tiles carry.
    frameFeatures = pixels == TilePixels::LinearHalf ? settings.features : 0;
    frameDenoise.reset();
    if (withNodes() && frameFeatures && settings.depth && cmd.denoise.mode != DenoiseSettings::Mode::Off &&
        (featureBitsFor(cmd.denoise.mode) & ~frameFeatures) == 0)
        frameDenoise = NodeDenoise{cmd.denoise, cmd.denoiseRing, frameFeatures, stateSeq, cmd.camera};
    frameViews = std::move(cmd.views);
    frameViewsTag = cmd.viewsTag;
    frameRoomEyes = cmd.roomEyes;
    shownSeq = cmd.shownSeq;
    // The views are the frame's only camera on the wire (protocol 13): a mono frame is one
    // view of the whole image, whose tiling is makeTiles'.
    if (frameViews.empty()) beginViews.assign(1, FrameView{cmd.camera, {}, 0, 0});
    else beginViews = frameViews;
    frameSeq = stateSeq;
    // The frame's state: the last one and every update up to stateSeq, which were all sent
    // before this frame began (runCommands flushes first) and no later one was (commands
    // come in sequence order).
    if (!sentSince.empty() || frameState.updateSeq != stateSeq) {
        const Update since = sentSince.take();
        if (since.seq != stateSeq || since.baseSeq != frameState.updateSeq) {
            // An invariant, not an input: going on would hand out tiles of a state nobody holds.
            std::fprintf(stderr, "rtwall master: internal error: frame %u renders state %u, but the updates sent "
                                 "since state %u cover %u to %u\n",
                         frame, stateSeq, frameState.updateSeq, since.baseSeq, since.seq);
            std::abort();
        }
        for (const Change& change : since.changes) applyChange(frameState, change);
        frameState.updateSeq = stateSeq;
        frameStateMessage.reset();
    }
    // What a client's failed tile of this frame is replayed with (onTileFailed).
    recentFrames.push_back({frame, beginViews.front().camera, frameState.settings, frameViews});
    if (recentFrames.size() > kRecentFrames) recentFrames.pop_front();
    frameActive = true;
    frameStart = nowSeconds();
    frameBytes = 0;
    frameDecoded = false;
    // A LinearHalf frame's tiles go into the assembler's linear buffers too. Every tile writes
    // its part; no clearing. (Swapped with the completed frame's buffers, so a still view
    // allocates nothing.) A mono frame's one view is the whole image: its tiling is makeTiles'.
    FrameHolding holding;
    holding.linear = pixels == TilePixels::LinearHalf;
    holding.depth = settings.depth;
    holding.features = frameFeatures;
    assembler.beginFrame(frame, rs.width, rs.height, viewTiles(beginViews, rs.width, rs.height, rs.tileSize),
                         uint32_t(beginViews.size()), holding);
    scheduler.beginFrame(frame, uint32_t(assembler.tiles().size()));
    if (withNodes()) beginNodeFrame(rs);
    for (auto& [peer, c] : clients) {
        c.credits = 0;
        c.window = 0;
        c.tilesAssigned = 0;
        c.busySeconds = 0;
        c.frameBytes = 0;
        if (c.ready && c.stateSeq <= frameSeq && !c.deathReason) sendFrameBegin(c);
    }
}

void Master::Impl::finishFrameIfDone() {
    if (!frameActive) return;
    if (withNodes() ? display.tilesDone < scheduler.tileCount() : !frameDecoded.load()) return;
    frameActive = false;
    const double seconds = nowSeconds() - frameStart;
    FrameReport r;
    r.frame = currentFrame;
    r.stateSeq = shownSeq;
    r.sceneSeq = frameSeq;
    r.seconds = seconds;
    r.bytes = frameBytes;
    const SchedulerStats& st = scheduler.stats();
    r.tilesStolen = st.stolen;
    r.tilesReissued = st.reissued;
    r.duplicatesDropped = st.duplicates;
    r.staleDropped = st.stale;
    r.affinityHits = st.affinityHits;
    r.tileOwners.assign(scheduler.owners().begin(), scheduler.owners().end());
    r.stochastic = frameStochastic;
    r.linear = framePixels == TilePixels::LinearHalf;
    r.depth = settings.depth;
    r.features = frameFeatures;
    r.camera = beginViews.front().camera;
    r.views = frameViews.size();
    r.viewsTag = frameViewsTag;
    r.counters = countersNow();
    if (withNodes()) {
        const SwapBarrierStats& b = display.barrier.stats();
        r.displayNodes = display.nodes.size();
        r.swapsReleased = b.released;
        r.nodesLeftOut = b.leftOut;
        r.lastSwapSkew = b.lastSkew;
        r.maxSwapSkew = b.maxSkew;
    }
    const std::vector<double>& lat = scheduler.latencies();
    double sum = 0;
    for (double l : lat) sum += l;
    r.meanTileLatency = lat.empty() ? 0.0 : sum / double(lat.size());
    for (const auto& [peer, c] : clients) {
        ClientReport cr;
        cr.id = c.id;
        auto done = st.completedBy.find(c.id);
        cr.tiles = done == st.completedBy.end() ? 0 : done->second;
        auto stolen = st.stolenBy.find(c.id);
        cr.stolen = stolen == st.stolenBy.end() ? 0 : stolen->second;
        cr.bytes = c.frameBytes;
        cr.busyFraction = seconds > 0 ? c.busySeconds / (seconds * std::max(1u, c.threads)) : 0;
        r.clients.push_back(cr);
    }
    {
        std::lock_guard lock(m);
        // With nodes the pixels are on the nodes: empty images, one per view.
        if (withNodes()) completedImages.assign(std::max<size_t>(1, frameViews.size()), Image{});
        else completedImages = std::exchange(assembler.images(), std::vector<Image>(1));  // the assembler starts the next frame afresh
        if (framePixels == TilePixels::LinearHalf) completedLinear.swap(assembler.linearImages());
        else completedLinear.clear();
        if (settings.depth && !withNodes()) completedDepth.swap(assembler.depthImages());
        else completedDepth.clear();
        if (frameFeatures) completedFeatures.swap(assembler.featureImages());
        else completedFeatures.clear();
        completedReport = std::move(r);
        completedFrame = currentFrame;
    }
    cv.notify_all();
}

void Master::Impl::reopenFailedTiles() {
    std::vector<uint32_t> failed;
    {
        std::lock_guard lock(failedMutex);
        failed.swap(failedTiles);
    }
    if (failed.empty()) return;
    add(&MasterCounters::undecodableTiles, failed.size());
    for (uint32_t t : failed) scheduler.reopen(currentFrame, t);
    serveAll();
}

// Runs the queued commands; false when one of them is kStop (the loop then ends). The stop
// is seen in the list taken here: checking the shared queue first and taking it afterwards
// could swallow a stop queued in between, and the destructor would wait forever.
bool Master::Impl::runCommands() {
    std::deque<Command> pending;
    {
        std::lock_guard lock(m);
        pending.swap(commands);
    }
    for (const Command& cmd : pending)
        if (cmd.kind == Command::kStop) return false;
    for (Command& cmd : pending) {
        if (cmd.kind == Command::kUpdate) {
            unsent.add(std::move(cmd.update));
            continue;
        }
        // Never merge across a frame: a frame's state must be a point in the sequence.
        flushUpdates();
        if (cmd.kind == Command::kBeginFrame)
            beginFrame(std::move(cmd));
        if (cmd.kind == Command::kCodec) {
            settings.codec = cmd.codec;  // for clients that join later
            for (auto& [peer, c] : clients)
                if (!c.deathReason) c.needsWelcome = send(c, welcomeFor(c)) == SendResult::Full;
            // The state's sequence number moves on (an update without changes), so frames
            // after the switch are seen as another state and an accumulation restarts.
            unsent.add(std::move(cmd.update));
        }
    }
    if (nowSeconds() - lastUpdateSent > kUpdateIntervalSeconds) flushUpdates();
    return true;
}

Image Master::renderFrame(FrameReport* report, std::vector<float>* linear, std::vector<float>* depth) {
    // The caller's buffers go round for a later frame.
    std::vector<std::vector<float>> linearViews, depthViews;
    if (linear) linearViews.emplace_back().swap(*linear);
    if (depth) depthViews.emplace_back().swap(*depth);
    std::vector<Image> images = renderViews(report, linear ? &linearViews : nullptr, depth ? &depthViews : nullptr);
    for (auto [one, views] : {std::pair{linear, &linearViews}, std::pair{depth, &depthViews}}) {
        if (!one) continue;
        one->clear();
        if (!views->empty()) one->swap(views->front());
    }
    return std::move(images.front());
}

namespace {
constexpr int kNodeHistoryWaitMs = 3000;
}

std::vector<Image> Master::renderViews(FrameReport* report, std::vector<std::vector<float>>* linear,
                                       std::vector<std::vector<float>>* depth, std::vector<FeatureImages>* features) {
    Impl& s = *impl_;
    auto begin = [&] {
        // A denoising display node filters each frame with the one before as its history and
        // holds two (the newest, and the one before until its swap): a third would overtake one
        // unseen and restart its history. So with nodes present, the frame two before this one
        // is swapped first (bounded: the barrier leaves a stalled node out within its stall
        // time); the nodes' filter, not the clients, then sets the pace. Every caller (the wall
        // session, benchmarks, tests) gets that from here.
        bool nodesDenoise = false;
        {
            std::lock_guard lock(s.app.stateMutex);
            nodesDenoise = s.app.denoise.mode != DenoiseSettings::Mode::Off;
        }
        if (s.withNodes() && s.lastBegun >= 2 && nodesDenoise) {
            const uint32_t before = s.lastBegun - 1;  // two before the frame begun now
            if (!displayNodesPresent().empty() && !waitForSwap(before, kNodeHistoryWaitMs))
                std::fprintf(stderr, "rtwall master: display nodes: frame %u was not swapped within %d ms; a node may "
                                     "skip a frame and restart its denoiser's history\n", before, kNodeHistoryWaitMs);
        }
        const uint32_t frame = ++s.lastBegun;
        {
            // The frame renders the state as it is now; later updates belong to later frames.
            // O(1): the network thread brings its copy of the state up to this sequence number.
            std::lock_guard lock(s.app.stateMutex);
            Command cmd{.kind = Command::kBeginFrame, .frame = frame, .settings = s.app.scene.settings};
            cmd.update.seq = s.app.seq;
            if (s.app.stochasticStale) {
                s.app.stateStochastic = rendersStochastically(s.app.scene);
                s.app.stochasticStale = false;
            }
            cmd.stochastic = s.app.stateStochastic;
            cmd.views = s.app.views;
            cmd.viewsTag = s.app.viewsTag;
            cmd.roomEyes = s.app.roomEyes;
            cmd.camera = s.app.camera;
            cmd.denoise = s.app.denoise;
            cmd.denoiseRing = s.app.denoiseRing;
            // Each update and each camera move once: the sequence numbers reports gave when the
            // camera was an update (frames of one state and one camera accumulate).
            cmd.shownSeq = s.app.seq + s.app.cameraMoves;
            if (cmd.stochastic && s.settings.wideAccumulation) cmd.pixels = TilePixels::LinearHalf;
            queueLocked(s, std::move(cmd));
        }
        s.wake();
        s.inFlight = true;
        return frame;
    };
    auto wait = [&](uint32_t frame) {
        std::unique_lock lock(s.m);
        // Never a silent hang: with no render client at all for a while, the frame cannot end.
        const auto patience = std::chrono::milliseconds(std::max(5000, 2 * s.settings.timeoutMs));
        auto lastSeenClients = std::chrono::steady_clock::now();
        while (!s.cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return s.completedFrame >= frame; })) {
            if (const std::atomic<bool>* flag = s.stopFlag.load(); flag && flag->load()) {
                std::fprintf(stderr, "rtwall master: stopped while frame %u was rendering (%d clients ready)\n", frame,
                             s.readyClients);
                throw Cancelled();
            }
            const auto now = std::chrono::steady_clock::now();
            if (s.readyClients > 0) lastSeenClients = now;
            else if (now - lastSeenClients > patience)
                throw std::runtime_error("frame " + std::to_string(frame) + " cannot finish: no render client is connected");
        }
        s.inFlight = false;
        if (report) *report = s.completedReport;
        // The caller's buffers come back for a later frame.
        for (auto [mine, completed] : {std::pair{linear, &s.completedLinear}, std::pair{depth, &s.completedDepth}}) {
            if (!mine) continue;
            for (std::vector<float>& l : *mine) l.clear();
            mine->swap(*completed);
        }
        if (features) features->swap(s.completedFeatures);  // the caller's buffers come back too
        return std::move(s.completedImages);
    };
    if (!s.settings.async) return wait(begin());
    // Asynchronous: finish the frame in flight, start the next at once (it carries every update
    // made so far), and return the finished one while the clients already render its successor.
    const uint32_t waitFor = s.inFlight ? s.lastBegun : begin();
    std::vector<Image> img = wait(waitFor);
    begin();
    return img;
}

}  // namespace rtwall
