#include "assembler.h"

#include <algorithm>

namespace rtwall::cluster {

namespace {
constexpr uint8_t kMissing = 0;
constexpr uint8_t kWriting = 1;
constexpr uint8_t kDone = 2;
}  // namespace

void FrameAssembler::resize(size_t views, int width, int height) {
    width = std::max(0, width);
    height = std::max(0, height);
    images_.resize(std::max<size_t>(1, views));
    // Same size: the previous frame's pixels stay, so a tile that never arrives shows last
    // frame's content on the wall instead of a black hole.
    for (Image& image : images_)
        if (width != image.width || height != image.height) {
            image.width = width;
            image.height = height;
            image.rgb.assign(size_t(width) * size_t(height) * 3, 0);
        }
}

void FrameAssembler::resetStates(size_t previous) {
    if (!state_ || previous != tiles_.size())
        state_ = std::make_unique<std::atomic<uint8_t>[]>(tiles_.size());  // value-initialised: all missing
    else
        for (size_t t = 0; t < tiles_.size(); ++t) state_[t].store(kMissing, std::memory_order_relaxed);
    done_.store(0);
}

void FrameAssembler::beginFrame(uint32_t frame, int width, int height, int tileSize) {
    resize(1, width, height);
    const size_t previous = tiles_.size();
    tiles_ = makeTiles(std::max(0, width), std::max(0, height), tileSize);
    view_.clear();
    resetStates(previous);
    frame_ = frame;
}

void FrameAssembler::beginFrame(uint32_t frame, int width, int height, const std::vector<ViewTile>& tiles, uint32_t views) {
    resize(views, width, height);
    const size_t previous = tiles_.size();
    tiles_.resize(tiles.size());
    view_.resize(tiles.size());
    for (size_t t = 0; t < tiles.size(); ++t) {
        tiles_[t] = tiles[t].rect;
        view_[t] = std::min(tiles[t].view, uint32_t(images_.size() - 1));
    }
    resetStates(previous);
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
    Image& image = images_[viewOf(tile)];
    view.data = image.pixel(rect.x0, rect.y0);
    view.stride = size_t(image.width) * 3;
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
