// Frame assembly: tiles of the current frame are decoded straight into the framebuffer, each
// at most once; tiles of any other frame are refused. A multi-view frame (both eyes, a CAVE's
// planes) has one framebuffer per view, and each tile goes into its view's. A plain class without sockets; safe to
// call from several decode threads at once (claim/commit use atomics per tile).
#pragma once

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace rtwall::cluster {

class FrameAssembler {
public:
    // Starts a frame: the framebuffer is (re)sized and every tile marked missing.
    void beginFrame(uint32_t frame, int width, int height, int tileSize);
    // A frame of `views` images of width x height, whose tiles are `tiles` (viewTiles).
    void beginFrame(uint32_t frame, int width, int height, const std::vector<ViewTile>& tiles, uint32_t views);

    enum class Claim { Granted, Stale, Duplicate, Invalid };
    // Reserves tile `tile` of `frame` for writing. Granted: write the pixels into `view`
    // (rect gives the size) and call commit(), or release() if decoding failed.
    Claim claim(uint32_t frame, uint32_t tile, TileRect& rect, TileView& view);
    void commit(uint32_t tile);
    void release(uint32_t tile);

    bool complete() const { return done_.load() == tiles_.size(); }
    size_t missing() const { return tiles_.size() - done_.load(); }
    uint32_t frame() const { return frame_; }
    const std::vector<TileRect>& tiles() const { return tiles_; }
    uint32_t viewOf(uint32_t tile) const { return view_.empty() ? 0 : view_[tile]; }
    Image& image(size_t view = 0) { return images_[view]; }
    const Image& image(size_t view = 0) const { return images_[view]; }
    std::vector<Image>& images() { return images_; }

private:
    uint32_t frame_ = 0;
    std::vector<Image> images_ = std::vector<Image>(1);  // one per view
    std::vector<TileRect> tiles_;
    std::vector<uint32_t> view_;  // each tile's view (empty: all of view 0)
    // 0 = missing, 1 = being written, 2 = done
    std::unique_ptr<std::atomic<uint8_t>[]> state_;
    std::atomic<size_t> done_{0};

    void resize(size_t views, int width, int height);
    void resetStates(size_t previous);
};

}  // namespace rtwall::cluster
