// Frame assembly: tiles of the current frame are decoded straight into the framebuffer, each
// at most once; tiles of any other frame are refused. A plain class without sockets; safe to
// call from several decode threads at once (claim/commit use atomics per tile).
#pragma once

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
    Image& image() { return image_; }
    const Image& image() const { return image_; }

private:
    uint32_t frame_ = 0;
    Image image_;
    std::vector<TileRect> tiles_;
    // 0 = missing, 1 = being written, 2 = done
    std::unique_ptr<std::atomic<uint8_t>[]> state_;
    std::atomic<size_t> done_{0};
};

}  // namespace rtwall::cluster
