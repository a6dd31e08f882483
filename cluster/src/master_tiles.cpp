// Tile scheduling on the network thread: hand-outs on request, results and acks, tiles lost on
// the way or stuck in a render thread, and tiles that failed.
#include "master_impl.h"

#include <algorithm>
#include <cstdio>
#include <bit>

namespace rtwall {

void Master::Impl::serve(ClientState& c) {
    if (!frameActive || !c.ready || c.credits == 0 || c.stateSeq > frameSeq || c.deathReason) return;
    const double now = nowSeconds();
    if (now < c.retryAt) return;
    TileAssign assign;
    assign.frame = currentFrame;
    assign.tiles = scheduler.request(c.id, c.credits, now);
    if (assign.tiles.empty()) return;
    if (send(c, assign, currentFrame) == SendResult::Sent) {
        c.credits -= uint32_t(assign.tiles.size());
        c.tilesAssigned += uint32_t(assign.tiles.size());
        return;
    }
    // They never reached it: back to the queue for whoever asks next (this client too, later).
    for (uint32_t t : assign.tiles) scheduler.release(c.id, currentFrame, t, false);
}

void Master::Impl::serveAll() {
    for (auto& [peer, c] : clients)
        if (!c.deathReason) serve(c);
}

// A client sent a tile to its nodes: the scheduler completes it as it would a TileResult.
void Master::Impl::onTileDone(ClientState& c, const Header& h, const TileDone& d) {
    c.busySeconds += d.renderMicros * 1e-6;
    if (!withNodes()) {
        unexpected("a tile ack, but this wall has no display nodes");
        return;
    }
    if (!frameActive || h.frame != currentFrame || d.frame != currentFrame) {
        stale("a tile ack for frame " + std::to_string(d.frame) + ", which is not being rendered");
        return;
    }
    const auto result = scheduler.complete(c.id, d.frame, d.tile, nowSeconds());
    if (result == TileScheduler::Result::Unexpected) {
        unexpected("a tile ack for tile " + std::to_string(d.tile) + ", which it was not given");
        return;
    }
    c.credits = std::min<uint32_t>(c.credits + 1, kMaxCredits);
    if (result == TileScheduler::Result::Accepted) {
        ++display.tilesDone;
        const uint64_t sent = uint64_t(d.bytes) * uint64_t(std::popcount(display.routes[d.tile]));
        frameBytes += sent;
        c.frameBytes += sent;
    }
    serve(c);
}

void Master::Impl::onTileResult(ClientState& c, const Header& h, const uint8_t* data, size_t size) {
    TileResult r = decodePayload<TileResult>(data, size);
    if (withNodes()) {
        // The master never takes pixels of a wall with display nodes: the frame ends on acks.
        unexpected("a tile's pixels, but this wall's tiles go to its display nodes");
        return;
    }
    c.busySeconds += r.renderMicros * 1e-6;
    if (!frameActive || h.frame != currentFrame || r.frame != currentFrame) {
        stale("a result for frame " + std::to_string(r.frame) + ", which is not being rendered");
        return;
    }
    if (r.format != framePixels) {
        unexpected("a result in another pixel format than the frame's");
        return;
    }
    if (r.depth.empty() == settings.depth) {
        unexpected(settings.depth ? "a result without the depth its frame asked for" : "a result with depth its frame did not ask for");
        return;
    }
    if (r.features.empty() == (frameFeatures != 0)) {
        unexpected(frameFeatures ? "a result without the features its frame asked for"
                                 : "a result with features its frame did not ask for");
        return;
    }
    const auto result = scheduler.complete(c.id, r.frame, r.tile, nowSeconds());
    if (result == TileScheduler::Result::Unexpected) {
        // A tile never handed to this client (replayed from another frame's hand-outs, or made up).
        unexpected("a result for tile " + std::to_string(r.tile) + ", which it was not given");
        return;
    }
    // A result for a tile it was given is also a request for the next tile; a duplicate
    // (the tile was done by a re-issue, or the result was replayed) is counted in the report.
    c.credits = std::min<uint32_t>(c.credits + 1, kMaxCredits);
    if (result == TileScheduler::Result::Accepted) {
        TileRect rect;
        TileView view;
        if (assembler.claim(r.frame, r.tile, rect, view) == FrameAssembler::Claim::Granted) {
            frameBytes += r.pixels.size() + r.depth.size() + r.features.size();
            c.frameBytes += r.pixels.size() + r.depth.size() + r.features.size();
            const uint32_t v = assembler.viewOf(r.tile);
            const bool wide = r.format == TilePixels::LinearHalf;
            const size_t width = size_t(assembler.image(v).width);
            decoder->push({std::move(r.pixels), r.codec, r.tile, rect, view, r.format,
                           wide ? assembler.linearAt(v, rect.x0, rect.y0) : nullptr, width * 3, std::move(r.depth),
                           settings.depth ? assembler.depthAt(v, rect.x0, rect.y0) : nullptr, width, std::move(r.features),
                           frameFeatures, frameFeatures ? assembler.featuresAt(v, rect.x0, rect.y0) : FeatureView{}});
        }
    }
    serve(c);
}

// An idle client that has seen every tile it was sent this frame holds none of its
// hand-outs: those still awaiting a result are lost (dropped on the way, or never rendered)
// and go to the next client that asks, this one included. This is what recovers a lost
// result when it is the only client.
void Master::Impl::onHeartbeat(ClientState& c, const Heartbeat& hb) {
    if (!hb.idle || !frameActive || hb.frame != currentFrame || hb.tilesSeen != c.tilesAssigned ||
        c.frameBegun != currentFrame)
        return;
    const size_t lost = scheduler.release(c.id);
    // Everything it asked for is free again, also credits of results that were lost.
    c.credits = std::min(kMaxCredits, std::max(c.credits, c.window));
    if (lost == 0) {
        serve(c);
        return;
    }
    uint64_t n;
    {
        std::lock_guard lock(countersMutex);
        n = (counts.lostHandOuts += lost);
    }
    if (n - lost < kLoggedPerKind)
        std::fprintf(stderr, "rtwall master: client %u is idle without %zu tile%s of frame %u it was given: handed out again\n",
                     c.id, lost, lost == 1 ? "" : "s", currentFrame);
    serveAll();
}

// A render thread of this client is stuck on a tile: the tile goes to another client, or
// to another thread of this one when it is the only client (it still renders tiles on its
// other threads, so its stuck slot is given back as a credit).
// A report for a tile that is done already (a straggler re-issue finished it, or the frame
// completed) is still counted and logged: the operator should know about a stuck thread.
void Master::Impl::onTileStalled(ClientState& c, const TileStalled& st) {
    const bool outstanding = frameActive && st.frame == currentFrame && scheduler.release(c.id, st.frame, st.tile, true);
    count(&MasterCounters::stalledTiles, "a stuck render thread",
          "frame " + std::to_string(st.frame) + ", tile " + std::to_string(st.tile) + " has been rendering for " +
              std::to_string(st.elapsedMs) + " ms" + (outstanding ? ": handed out again" : " (done by another)"));
    if (!outstanding) return;
    c.credits = std::min<uint32_t>(c.credits + 1, kMaxCredits);
    serveAll();
}

// A client's tile threw (it says goodbye next): kept, with the camera and settings of its
// frame, for the application to say how to replay it. A report that does not match a tile
// of a recent frame is dropped: it could not be replayed.
void Master::Impl::onTileFailed(ClientState& c, const TileFailed& f) {
    auto rec = std::find_if(recentFrames.begin(), recentFrames.end(), [&](const FrameRecord& r) { return r.frame == f.frame; });
    if (rec == recentFrames.end()) {
        unexpected("a failed tile of frame " + std::to_string(f.frame) + ", which is not a recent frame");
        return;
    }
    std::vector<TileRect> tiles;
    CameraDesc replayCamera = rec->camera;
    if (rec->views.empty()) {
        tiles = makeTiles(rec->settings.width, rec->settings.height, rec->settings.tileSize);
    } else {
        // A multi-view frame's tile is replayed with its view's camera.
        const std::vector<ViewTile> vt = viewTiles(rec->views, rec->settings.width, rec->settings.height, rec->settings.tileSize);
        for (const ViewTile& t : vt) tiles.push_back(t.rect);
        if (f.tile < vt.size()) replayCamera = rec->views[vt[f.tile].view].camera;
    }
    const TileRect& r = f.rect;
    if (f.tile >= tiles.size() || tiles[f.tile].x0 != r.x0 || tiles[f.tile].y0 != r.y0 || tiles[f.tile].x1 != r.x1 ||
        tiles[f.tile].y1 != r.y1) {
        unexpected("a failed tile " + std::to_string(f.tile) + " whose pixels are not that tile's in frame " +
                   std::to_string(f.frame));
        return;
    }
    std::lock_guard lock(failuresMutex);
    tileFailures.push_back({c.id, f.frame, f.tile, r, f.reason, replayCamera, rec->settings, f.packetWidth});
    if (tileFailures.size() > 64) tileFailures.pop_front();
}

}  // namespace rtwall
