// FrameAssembler (rtwall/frame.h): the master's and the display nodes' one way of gathering tiles.
#include <rtwall/frame.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace rtwall {

namespace {
constexpr uint8_t kMissing = 0;
constexpr uint8_t kWriting = 1;
constexpr uint8_t kDone = 2;
constexpr uint8_t kNotRouted = 3;
}  // namespace

void FrameAssembler::resize(size_t views, int width, int height, const FrameHolding& holding) {
    width = std::max(0, width);
    height = std::max(0, height);
    images_.resize(std::max<size_t>(1, views));
    // Same size: the previous frame's pixels stay, so a tile that never arrives shows last
    // frame's content on the wall instead of a black hole (and a node never shows uninitialised
    // memory).
    for (Image& image : images_)
        if (width != image.width || height != image.height) {
            image.width = width;
            image.height = height;
            image.rgb.assign(size_t(width) * size_t(height) * 3, 0);
        }
    linear_ = holding.linear;
    if (linear_) {
        linearImages_.resize(images_.size());
        for (std::vector<float>& l : linearImages_) l.resize(size_t(width) * size_t(height) * 3, 0.0f);
    }
    // Unlike the pixels, depth never shows last frame's: a stale depth would put last frame's
    // surfaces where this frame has none. What no tile writes stays a hole.
    depth_ = holding.depth;
    if (depth_) {
        depthImages_.resize(images_.size());
        for (std::vector<float>& d : depthImages_) d.assign(size_t(width) * size_t(height), std::numeric_limits<float>::quiet_NaN());
    } else {
        depthImages_.clear();
    }
    // Features likewise start from zero (id 0: nothing, never another frame's object).
    features_ = holding.features;
    if (features_) {
        const size_t n = size_t(width) * size_t(height);
        featureImages_.resize(images_.size());
        for (FeatureImages& f : featureImages_) {
            if (features_ & kFeatureAlbedo) f.albedo.assign(n * 3, 0.0f);
            else f.albedo.clear();
            if (features_ & kFeatureNormal) f.normal.assign(n * 3, 0.0f);
            else f.normal.clear();
            if (features_ & kFeatureId) f.id.assign(n, 0u);
            else f.id.clear();
        }
    } else {
        featureImages_.clear();
    }
}

void FrameAssembler::beginFrame(uint32_t frame, int width, int height, int tileSize) {
    std::vector<ViewTile> tiles;
    for (const TileRect& t : makeTiles(std::max(0, width), std::max(0, height), tileSize)) tiles.push_back({0, t});
    beginFrame(frame, width, height, tiles, 1);
}

void FrameAssembler::beginFrame(uint32_t frame, int width, int height, const std::vector<ViewTile>& tiles, uint32_t views,
                                const FrameHolding& o) {
    views = std::max(1u, views);
    if (o.routes && o.node >= 64)
        throw std::invalid_argument("FrameAssembler: node " + std::to_string(o.node) + " is not below 64");
    if (o.routes && o.routes->size() != tiles.size())
        throw std::invalid_argument("FrameAssembler: " + std::to_string(o.routes->size()) + " tile routes for a tiling of " +
                                    std::to_string(tiles.size()) + " tiles");
    for (const ViewTile& t : tiles)
        if (t.view >= views)
            throw std::invalid_argument("FrameAssembler: a tile of view " + std::to_string(t.view) + " in a frame of " +
                                        std::to_string(views) + " views");
    resize(views, width, height, o);
    tiles_.resize(tiles.size());
    view_.clear();
    for (size_t t = 0; t < tiles.size(); ++t) {
        tiles_[t] = tiles[t].rect;
        if (views > 1) view_.push_back(tiles[t].view);
    }
    if (!state_ || stateSize_ != tiles_.size()) {
        state_ = std::make_unique<std::atomic<uint8_t>[]>(tiles_.size());
        stateSize_ = tiles_.size();
    }
    expected_ = 0;
    for (size_t t = 0; t < tiles_.size(); ++t) {
        const bool mine = !o.routes || (((*o.routes)[t] >> o.node) & 1);
        expected_ += mine;
        state_[t].store(mine ? kMissing : kNotRouted, std::memory_order_relaxed);
    }
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
        return expected == kNotRouted ? Claim::NotRouted : Claim::Duplicate;
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

}  // namespace rtwall
