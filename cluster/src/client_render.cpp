// A render client's work: the frames the master begins, the tiles it assigns, the render
// threads that render and encode them, the stall watch and the replay mode of benchmarks.
#include "client_runtime.h"

#include <pthread.h>

#include <cstdio>
#include <stdexcept>

namespace rtwall::cluster {

void ClientRuntime::onFrameBegin(const FrameBegin& fb) {
    // Frames only move forward. An older FrameBegin, or the one being rendered again, is a
    // replay: obeying it would throw away the work in progress. (The master repeats the
    // current frame's FrameBegin after a resync, when this client renders nothing.)
    if (fb.frame < lastFrameBegun_ || (fb.frame != 0 && fb.frame == frame_.load())) {
        drop();
        return;
    }
    dropWork();
    deferredFrame_.reset();
    blockedFrame_.reset();
    if (ready_ && updateFilesMissing()) {  // a changed material's file is on its way
        deferredFrame_ = fb;
        return;
    }
    if (!ready_) return;
    switch (catchUp(fb.updateSeq)) {
    case CatchUp::CannotRender: return;
    case CatchUp::Busy:
        blockedFrame_ = fb;
        if (blockedSince_ == 0) blockedSince_ = nowSeconds();
        return;
    case CatchUp::Done: break;
    }
    blockedSince_ = 0;
    blockedLogged_ = false;
    framePixels_ = fb.pixels;
    frameDepth_ = fb.depth;
    frameFeatures_ = fb.features;
    // At the state's resolution and tile size, which catchUp just brought to the frame's.
    auto layout = std::make_shared<FrameLayout>();
    const int width = renderSettings_.width, height = renderSettings_.height;
    try {
        for (const FrameView& v : fb.views) layout->cameras.emplace_back(v.camera, width, height, frameWarps(v, warpGrids_, width, height));
    } catch (const std::out_of_range& e) {
        // A grid the master never sent this client: it cannot render the frame as the others
        // do, so it renders none of it (the others do).
        if (!saidWarpGrid_) std::fprintf(stderr, "rtwall client %u: frame %u names a %s; its tiles are left to others\n", id_, fb.frame, e.what());
        saidWarpGrid_ = true;
        drop();
        return;
    }
    layout->tiles = viewTiles(fb.views, renderSettings_.width, renderSettings_.height, renderSettings_.tileSize);
    frameLayout_ = std::move(layout);
    frame_.store(fb.frame);
    lastFrameBegun_ = fb.frame;
    send(TileRequest{fb.frame, prefetch_}, fb.frame);
}

void ClientRuntime::onAssign(const TileAssign& a) {
    // Every tile the master sent for a frame counts as seen, used or not: the heartbeat's
    // tilesSeen tells the master that nothing it sent is still on its way.
    if (a.frame > assignFrame_) {
        assignFrame_ = a.frame;
        assignSeen_ = 0;
    }
    if (a.frame == assignFrame_) assignSeen_ += uint32_t(a.tiles.size());
    if (!ready_ || a.frame != frame_.load()) {
        drop();
        return;
    }
    size_t queued = 0;
    {
        std::lock_guard lock(workMutex_);
        for (uint32_t t : a.tiles) {
            if (work_.size() >= kMaxQueuedTiles) break;
            work_.push_back({a.frame, t, stateSeq_, codec_, framePixels_, frameDepth_, frameFeatures_, frameLayout_});
            ++queued;
        }
        held_ += int64_t(queued);
    }
    if (queued < a.tiles.size() && settings_.counters) settings_.counters->droppedAssignments += a.tiles.size() - queued;
    workCv_.notify_all();
}

void ClientRuntime::dropWork() {
    std::lock_guard lock(workMutex_);
    held_ -= int64_t(work_.size());
    work_.clear();
    frame_.store(0);
}

// A render thread far past its expected time on a tile of the current frame is reported
// (once per tile): the master hands the tile to another client, or to this one's other
// threads. "Expected": 16 times this client's mean tile time, at least minStallMs.
void ClientRuntime::watchStalls() {
    const uint64_t timed = tilesTimed_.load();
    const double meanNs = timed ? double(tileNs_.load()) / double(timed) : 0.0;
    const int64_t threshold = std::max<int64_t>(int64_t(settings_.minStallMs) * 1'000'000, int64_t(16.0 * meanNs));
    const int64_t now = steadyNs();
    for (int i = 0; i < threads_; ++i) {
        Slot& slot = slots_[size_t(i)];
        const int64_t start = slot.startNs.load();
        if (start == 0 || start == slot.reportedStartNs || now - start < threshold) continue;
        const uint64_t job = slot.job.load();
        if (slot.startNs.load() != start) continue;  // it moved on meanwhile
        slot.reportedStartNs = start;
        const uint32_t frame = uint32_t(job >> 32), tile = uint32_t(job);
        const uint32_t ms = uint32_t(std::min<int64_t>((now - start) / 1'000'000, UINT32_MAX));
        std::fprintf(stderr, "rtwall client %u: render thread %d has been on frame %u, tile %u for %u ms (mean tile %.1f ms): "
                     "reported to the master\n", id_, i, frame, tile, ms, meanNs * 1e-6);
        if (settings_.counters) ++settings_.counters->stalledTiles;
        if (session_.load()) send(TileStalled{frame, tile, ms});
    }
}

// Replay mode (benchmarks of the master and the link): a tile rendered once is sent again
// from memory, so the client costs next to nothing. Valid only while the view is still.
bool ClientRuntime::replaySend(zmq::socket_t& out, const Work& w) {
    TileResult result;
    {
        std::lock_guard lock(replayMutex_);
        auto it = replay_.find(w.tile);
        // A tile kept without depth is rendered again for a frame that asks for it.
        if (it == replay_.end() || (w.depth && it->second.depth.empty())) return false;
        result.codec = it->second.codec;
        result.pixels = it->second.pixels;  // renderMicros stays 0: a replay costs no rendering
        if (w.depth) result.depth = it->second.depth;
    }
    result.frame = w.frame;
    result.tile = w.tile;
    const std::vector<uint8_t> bytes = encodeMessage(header(MsgType::TileResult, w.frame, w.stateSeq), result);
    sendResult(out, bytes);
    return true;
}

// Render threads hand results to the network thread without blocking either: with its queue
// full (the master reads slowly and the network thread's own queue is full too) the result
// is dropped and counted, and the master re-issues the tile as a straggler.
void ClientRuntime::sendResult(zmq::socket_t& out, const std::vector<uint8_t>& bytes) {
    if (!sendNow(out, bytes)) {
        ++droppedResults_;
        --held_;
    }
}

// The injected stall (ClientFaults::stallMs): once, cut short when the client stops.
void ClientRuntime::maybeStall(uint32_t frame) {
    if (faults_.stallMs <= 0 || frame < faults_.stallFrame || stallInjected_.exchange(true)) return;
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(faults_.stallMs);
    while (std::chrono::steady_clock::now() < end && !stopRequested_.load())
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
}

// A rendered tile's result: its pixels through the session's codec, and its depth when the frame
// asked for it.
void ClientRuntime::encodeResult(const Work& w, const TileRect& r, const std::vector<uint8_t>& pixels,
                                 const std::vector<float>& linear, const std::vector<float>& depth,
                                 const FeatureView& features, std::vector<uint8_t>& scratch, TileResult& result) {
    result.frame = w.frame;
    result.tile = w.tile;
    if (w.pixels == TilePixels::LinearHalf) {
        result.codec = wideCodec(w.codec.codec);
        result.format = TilePixels::LinearHalf;
        encodeWideTile(w.codec, linear.data(), r.width(), r.height(), size_t(r.width()) * 3, scratch, result.pixels);
    } else {
        result.codec = w.codec.codec;
        encodeTile(w.codec, pixels.data(), r.width(), r.height(), size_t(r.width()) * 3, result.pixels);
    }
    if (!w.depth) return;
    encodeDepthTile(kDepthCodec, depth.data(), r.width(), r.height(), size_t(r.width()), scratch, result.depth);
    if (w.features) encodeFeatureTile(w.features, features, r.width(), r.height(), scratch, result.features);
    // Injected damage (tests): the depth cut in half no longer decompresses to the tile's size.
    const int n = faults_.corruptEveryNthDepth;
    if (n > 0 && ++depthsOut_ % uint64_t(n) == 0) result.depth.resize(result.depth.size() / 2);
}

void ClientRuntime::workerLoop(Slot& slot) {
    pthread_setname_np(pthread_self(), "rtw-render");  // rtwall bench cluster attributes CPU time by thread name
    zmq::socket_t out(ctx_, zmq::socket_type::push);
    out.set(zmq::sockopt::linger, 0);
    out.connect(kResultsAddress);
    std::vector<uint8_t> pixels, scratch;
    std::vector<float> linear, depth, albedo, normal;
    std::vector<uint32_t> ids;
    for (;;) {
        Work w;
        {
            std::unique_lock lock(workMutex_);
            workCv_.wait(lock, [&] { return stopping_ || !work_.empty(); });
            if (stopping_) return;
            w = work_.front();
            work_.pop_front();
        }
        const bool wide = w.pixels == TilePixels::LinearHalf;
        try {
            std::shared_lock lock(sceneMutex_);
            if (w.frame != frame_.load() || !scene_ || !w.layout || w.tile >= w.layout->tiles.size()) {  // stale or bogus
                --held_;
                continue;
            }
            if (settings_.replay && !wide && replaySend(out, w)) continue;
            // A view's tile renders as it would in a frame of that view's camera alone.
            const TileRect r = w.layout->tiles[w.tile].rect;
            const Camera& camera = w.layout->cameras[w.layout->tiles[w.tile].view];
            const auto t0 = std::chrono::steady_clock::now();
            // For the stall watch (watchStalls): this thread is on this tile since now.
            slot.job.store(uint64_t(w.frame) << 32 | w.tile);
            slot.startNs.store(steadyNs());
            // Depth only when the frame asks for it: without, the call is the one of a wall
            // without re-projection (DepthView's null data is that call too).
            depth.resize(w.depth ? size_t(r.width()) * r.height() : 0);
            const DepthView depthView{w.depth ? depth.data() : nullptr, size_t(r.width())};
            // The denoiser's features only when the frame asks for them (a linear frame with depth).
            const size_t pixelCount = size_t(r.width()) * size_t(r.height());
            albedo.resize((w.features & kFeatureAlbedo) ? pixelCount * 3 : 0);
            normal.resize((w.features & kFeatureNormal) ? pixelCount * 3 : 0);
            ids.resize((w.features & kFeatureId) ? pixelCount : 0);
            const FeatureView featureView{albedo.empty() ? nullptr : albedo.data(), normal.empty() ? nullptr : normal.data(),
                                          ids.empty() ? nullptr : ids.data(), size_t(r.width())};
            if (wide) {
                // Part of an accumulation: linear, before the 8-bit quantisation.
                linear.resize(size_t(r.width()) * r.height() * 3);
                renderTileLinear(*scene_, camera, r, w.frame, renderSettings_, linear.data(), size_t(r.width()) * 3,
                                 depthView, featureView, trace_);
            } else {
                pixels.resize(size_t(r.width()) * r.height() * 3);
                renderTile(*scene_, camera, r, w.frame, renderSettings_, {pixels.data(), size_t(r.width()) * 3}, depthView,
                           trace_);
            }
            if (faults_.extraTileDelayMs > 0)
                std::this_thread::sleep_for(std::chrono::milliseconds(faults_.extraTileDelayMs));
            maybeStall(w.frame);
            slot.startNs.store(0);
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            tileNs_ += uint64_t(seconds * 1e9);
            ++tilesTimed_;
            TileResult result;
            result.renderMicros = uint32_t(std::min(seconds * 1e6, 4e9));
            encodeResult(w, r, pixels, linear, depth, featureView, scratch, result);
            if (settings_.replay && !wide) {
                std::lock_guard replayLock(replayMutex_);
                replay_[w.tile] = {w.codec.codec, result.pixels, result.depth};
            }
            const std::vector<uint8_t> bytes = encodeMessage(header(MsgType::TileResult, w.frame, w.stateSeq), result);
            sendResult(out, bytes);
        } catch (const TileError& e) {
            // Tell the master why before going away (the network thread sends it): the
            // frame, the tile's number and pixels, and what went wrong.
            const TileRect& r = e.rect();
            std::lock_guard lock(workMutex_);
            if (failure_.empty()) {
                failure_ = "frame " + std::to_string(e.frame()) + ", tile " + std::to_string(w.tile) + " (pixels " +
                           std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.x1) + "," +
                           std::to_string(r.y1) + "): " + e.reason();
                // The width this thread traced with (0 asks for this CPU's widest).
                const int width = settings_.packetWidth != 0 ? settings_.packetWidth : packetWidth();
                failedTile_ = TileFailed{e.frame(), w.tile, r, width, e.reason().substr(0, kMaxStringBytes)};
            }
            return;
        } catch (const std::exception& e) {
            std::lock_guard lock(workMutex_);
            if (failure_.empty())
                failure_ = "frame " + std::to_string(w.frame) + ", tile " + std::to_string(w.tile) + ": " + e.what();
            return;
        }
    }
}

}  // namespace rtwall::cluster
