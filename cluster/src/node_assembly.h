// What a display node holds of a frame (issue 19). Render clients send each tile only to the
// nodes whose screens show it (TileRouting in rtwall/display.h gives a node mask per tile), so a
// node assembles just those tiles: each decoded once, straight into its copy of the frame. It
// holds the frame when every tile routed to it is in; that is what it reports to the swap
// barrier. Tiles of other frames, tiles not routed to it and repeats are refused. A plain class
// like FrameAssembler: no sockets; claim/commit are safe from several decode threads.
#pragma once

#include <rtwall/engine.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace rtwall::cluster {

class NodeAssembly {
public:
    // `routes[t]`: the node mask of tile t of makeTiles(width, height, tileSize); this node is
    // bit `node`. Throws std::invalid_argument when the masks do not match the tiling or node
    // is not below 64.
    void beginFrame(uint32_t frame, int width, int height, int tileSize, const std::vector<uint64_t>& routes, unsigned node);

    enum class Claim { Granted, Stale, Duplicate, NotRouted, Invalid };
    // Granted: write the tile's pixels into `view` (rect gives the size), then commit() it, or
    // release() it when decoding failed.
    Claim claim(uint32_t frame, uint32_t tile, TileRect& rect, TileView& view);
    void commit(uint32_t tile);
    void release(uint32_t tile);

    bool complete() const { return done_.load() == expected_; }
    size_t expected() const { return expected_; }  // tiles routed to this node
    size_t missing() const { return expected_ - done_.load(); }
    uint32_t frame() const { return frame_; }
    const std::vector<TileRect>& tiles() const { return tiles_; }
    const Image& image() const { return image_; }

private:
    uint32_t frame_ = 0;
    Image image_;
    std::vector<TileRect> tiles_;
    // 0 missing, 1 being written, 2 done, 3 not routed here
    std::unique_ptr<std::atomic<uint8_t>[]> state_;
    size_t stateSize_ = 0;
    size_t expected_ = 0;
    std::atomic<size_t> done_{0};
};

}  // namespace rtwall::cluster
