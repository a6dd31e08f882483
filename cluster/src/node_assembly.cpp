#include "node_assembly.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rtwall::cluster {

namespace {
constexpr uint8_t kMissing = 0;
constexpr uint8_t kWriting = 1;
constexpr uint8_t kDone = 2;
constexpr uint8_t kNotRouted = 3;
}  // namespace

void NodeAssembly::beginFrame(uint32_t frame, int width, int height, int tileSize, const std::vector<uint64_t>& routes,
                              unsigned node) {
    if (node >= 64) throw std::invalid_argument("NodeAssembly: node " + std::to_string(node) + " is not below 64");
    std::vector<TileRect> tiles = makeTiles(std::max(0, width), std::max(0, height), tileSize);
    if (routes.size() != tiles.size())
        throw std::invalid_argument("NodeAssembly: " + std::to_string(routes.size()) + " tile routes for a tiling of " +
                                    std::to_string(tiles.size()) + " tiles");
    // Same size: the previous frame's pixels stay (as on the master), so the node never shows
    // uninitialised memory.
    if (width != image_.width || height != image_.height) {
        image_.width = width;
        image_.height = height;
        image_.rgb.assign(size_t(width) * size_t(height) * 3, 0);
    }
    tiles_ = std::move(tiles);
    if (!state_ || stateSize_ != tiles_.size()) {
        state_ = std::make_unique<std::atomic<uint8_t>[]>(tiles_.size());
        stateSize_ = tiles_.size();
    }
    expected_ = 0;
    for (size_t t = 0; t < tiles_.size(); ++t) {
        const bool mine = (routes[t] >> node) & 1;
        expected_ += mine;
        state_[t].store(mine ? kMissing : kNotRouted, std::memory_order_relaxed);
    }
    done_.store(0);
    frame_ = frame;
}

NodeAssembly::Claim NodeAssembly::claim(uint32_t frame, uint32_t tile, TileRect& rect, TileView& view) {
    if (frame != frame_) return Claim::Stale;
    if (tile >= tiles_.size()) return Claim::Invalid;
    uint8_t expected = kMissing;
    if (!state_[tile].compare_exchange_strong(expected, kWriting, std::memory_order_acq_rel))
        return expected == kNotRouted ? Claim::NotRouted : Claim::Duplicate;
    rect = tiles_[tile];
    view.data = image_.pixel(rect.x0, rect.y0);
    view.stride = size_t(image_.width) * 3;
    return Claim::Granted;
}

void NodeAssembly::commit(uint32_t tile) {
    if (tile >= tiles_.size()) return;
    uint8_t expected = kWriting;
    if (state_[tile].compare_exchange_strong(expected, kDone, std::memory_order_acq_rel)) done_.fetch_add(1, std::memory_order_acq_rel);
}

void NodeAssembly::release(uint32_t tile) {
    if (tile >= tiles_.size()) return;
    uint8_t expected = kWriting;
    state_[tile].compare_exchange_strong(expected, kMissing, std::memory_order_acq_rel);
}

}  // namespace rtwall::cluster
