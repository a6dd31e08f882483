// What a display node holds of a frame (issue 19). Render clients send each tile only to the
// nodes whose screens show it (TileRouting in rtwall/display.h gives a node mask per tile), so a
// node assembles just those tiles: each decoded once, straight into its copy of the frame (one
// image per view of a multi-view frame: both eyes, a CAVE's planes). It holds the frame when
// every tile routed to it is in; that is what it reports to the swap barrier. Tiles of other
// frames, tiles not routed to it and repeats are refused. A plain class like FrameAssembler: no
// sockets; claim/commit are safe from several decode threads.
//
// NodeImages then makes what the node shows of a frame it holds, as the single-PC wall
// (WallSession) makes it of the same frame: each view accumulated when the frame is stochastic,
// the views composed into the eyes.
#pragma once

#include "protocol.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace rtwall::cluster {

class NodeAssembly {
public:
    // `routes[t]`: the node mask of tile t of makeTiles(width, height, tileSize); this node is
    // bit `node`. Throws std::invalid_argument when the masks do not match the tiling or node
    // is not below 64.
    void beginFrame(uint32_t frame, int width, int height, int tileSize, const std::vector<uint64_t>& routes, unsigned node);
    // A frame of `views` images of width x height whose tiles are `tiles` (viewTiles; every
    // view below `views`), routed by `routes[t]`. With `linear` its tiles come as linear RGB:
    // each view also has a linear buffer (3 floats a pixel) for linearAt.
    void beginFrame(uint32_t frame, int width, int height, const std::vector<ViewTile>& tiles, uint32_t views,
                    const std::vector<uint64_t>& routes, unsigned node, bool linear);

    enum class Claim { Granted, Stale, Duplicate, NotRouted, Invalid };
    // Granted: write the tile's pixels into `view` (rect gives the size; of a linear frame also
    // into linearAt(viewOf(tile), rect.x0, rect.y0)), then commit() it, or release() it when
    // decoding failed.
    Claim claim(uint32_t frame, uint32_t tile, TileRect& rect, TileView& view);
    void commit(uint32_t tile);
    void release(uint32_t tile);

    bool complete() const { return done_.load() == expected_; }
    size_t expected() const { return expected_; }  // tiles routed to this node
    size_t missing() const { return expected_ - done_.load(); }
    uint32_t frame() const { return frame_; }
    const std::vector<TileRect>& tiles() const { return tiles_; }
    uint32_t viewOf(uint32_t tile) const { return view_.empty() ? 0 : view_[tile]; }
    size_t views() const { return images_.size(); }
    const Image& image(size_t view = 0) const { return images_[view]; }
    bool linear() const { return linear_; }
    const std::vector<float>& linearImage(size_t view) const { return linearImages_[view]; }
    float* linearAt(size_t view, int x, int y) {
        return linearImages_[view].data() + (size_t(y) * size_t(images_[view].width) + size_t(x)) * 3;
    }

private:
    uint32_t frame_ = 0;
    std::vector<Image> images_ = std::vector<Image>(1);  // one per view
    std::vector<std::vector<float>> linearImages_;       // one per view of a linear frame
    bool linear_ = false;
    std::vector<TileRect> tiles_;
    std::vector<uint32_t> view_;  // each tile's view (empty: all of view 0)
    // 0 missing, 1 being written, 2 done, 3 not routed here
    std::unique_ptr<std::atomic<uint8_t>[]> state_;
    size_t stateSize_ = 0;
    size_t expected_ = 0;
    std::atomic<size_t> done_{0};
};

// The images a node presents of the frames it holds, frame after frame. A stochastic frame
// refines as on the single-PC wall (WallSession): a frame without views is added to a running
// mean that restarts when the state's sequence number changes; each view of a multi-view frame
// has its own, which restarts when the state or the view's camera changes (or the number of
// views). Linear frames are summed in linear RGB (Accumulator::addLinear), 8-bit ones as 8-bit.
// The views are then composed into the eyes: a view without regions is its eye's whole image,
// one with regions gives its eye those pixels (the rest stays black).
class NodeImages {
public:
    // `frame` describes what `held` holds (held.complete(), held.frame() == frame.frame).
    void show(const NodeFrame& frame, const NodeAssembly& held);
    std::optional<uint32_t> frame() const { return frame_; }
    const Image& left() const { return left_; }    // the mono image, or the left eye's
    const Image& right() const { return right_; }  // the right eye's: empty unless a view is of eye 1
    size_t restarts() const { return restarts_; }  // running means restarted (tests)

private:
    struct ViewSum {
        Accumulator sum;
        uint32_t stateSeq = UINT32_MAX;
        std::optional<CameraDesc> camera;
    };
    std::optional<uint32_t> frame_;
    Image left_, right_;
    Accumulator progressive_;  // frames without views
    uint32_t progressiveSeq_ = UINT32_MAX;
    std::vector<ViewSum> viewSums_;
    std::vector<Image> images_;  // this frame's view images, accumulated
    size_t restarts_ = 0;
};

}  // namespace rtwall::cluster
