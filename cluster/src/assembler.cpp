#include "assembler.h"

#include <algorithm>

namespace rtwall::cluster {

namespace {
constexpr uint8_t kMissing = 0;
constexpr uint8_t kWriting = 1;
constexpr uint8_t kDone = 2;
}  // namespace

void FrameAssembler::beginFrame(uint32_t frame, int width, int height, int tileSize) {
    width = std::max(0, width);
    height = std::max(0, height);
    // Same size: the previous frame's pixels stay, so a tile that never arrives shows last
    // frame's content on the wall instead of a black hole.
    if (width != image_.width || height != image_.height) {
        image_.width = width;
        image_.height = height;
        image_.rgb.assign(size_t(width) * size_t(height) * 3, 0);
    }
    const size_t previous = tiles_.size();
    tiles_ = makeTiles(width, height, tileSize);
    if (!state_ || previous != tiles_.size())
        state_ = std::make_unique<std::atomic<uint8_t>[]>(tiles_.size());  // value-initialised: all missing
    else
        for (size_t t = 0; t < tiles_.size(); ++t) state_[t].store(kMissing, std::memory_order_relaxed);
    done_.store(0);
    frame_ = frame;
}

FrameAssembler::Claim FrameAssembler::claim(uint32_t frame, uint32_t tile, TileRect& rect, TileView& view) {
    // Frame first: a tile of another frame may index a different tiling.
    if (frame != frame_) return Claim::Stale;
    if (tile >= tiles_.size()) return Claim::Invalid;
    uint8_t expected = kMissing;
    // A tile another thread is writing is refused rather than waited for: decode threads never
    // block each other, and the copy being written is as good as this one.
    if (!state_[tile].compare_exchange_strong(expected, kWriting, std::memory_order_acq_rel))
        return Claim::Duplicate;
    rect = tiles_[tile];
    view.data = image_.pixel(rect.x0, rect.y0);
    view.stride = size_t(image_.width) * 3;
    return Claim::Granted;
}

void FrameAssembler::commit(uint32_t tile) {
    // Only the holder of a claim may commit; a stray call must not count a tile twice.
    if (tile >= tiles_.size()) return;
    uint8_t expected = kWriting;
    if (state_[tile].compare_exchange_strong(expected, kDone, std::memory_order_acq_rel))
        done_.fetch_add(1, std::memory_order_acq_rel);  // release: the pixels are visible to whoever sees complete()
}

void FrameAssembler::release(uint32_t tile) {
    if (tile >= tiles_.size()) return;
    uint8_t expected = kWriting;
    state_[tile].compare_exchange_strong(expected, kMissing, std::memory_order_acq_rel);
}

}  // namespace rtwall::cluster
