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
    std::vector<ViewTile> tiles;
    for (const TileRect& t : makeTiles(std::max(0, width), std::max(0, height), tileSize)) tiles.push_back({0, t});
    beginFrame(frame, width, height, tiles, 1, routes, node, false);
}

void NodeAssembly::beginFrame(uint32_t frame, int width, int height, const std::vector<ViewTile>& tiles, uint32_t views,
                              const std::vector<uint64_t>& routes, unsigned node, bool linear) {
    if (node >= 64) throw std::invalid_argument("NodeAssembly: node " + std::to_string(node) + " is not below 64");
    if (routes.size() != tiles.size())
        throw std::invalid_argument("NodeAssembly: " + std::to_string(routes.size()) + " tile routes for a tiling of " +
                                    std::to_string(tiles.size()) + " tiles");
    views = std::max(1u, views);
    for (const ViewTile& t : tiles)
        if (t.view >= views)
            throw std::invalid_argument("NodeAssembly: a tile of view " + std::to_string(t.view) + " in a frame of " +
                                        std::to_string(views) + " views");
    // Same size: the previous frame's pixels stay (as on the master), so the node never shows
    // uninitialised memory.
    images_.resize(views);
    for (Image& image : images_) {
        if (width == image.width && height == image.height) continue;
        image.width = width;
        image.height = height;
        image.rgb.assign(size_t(width) * size_t(height) * 3, 0);
    }
    linear_ = linear;
    if (linear) {
        linearImages_.resize(views);
        for (std::vector<float>& l : linearImages_) l.resize(size_t(width) * size_t(height) * 3, 0.0f);
    }
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
    Image& image = images_[viewOf(tile)];
    view.data = image.pixel(rect.x0, rect.y0);
    view.stride = size_t(image.width) * 3;
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

void NodeImages::show(const NodeFrame& f, const NodeAssembly& held) {
    frame_ = f.frame;
    images_.resize(held.views());
    for (size_t v = 0; v < held.views(); ++v) images_[v] = held.image(v);
    // The single-PC wall's accumulation (WallSession::render), step for step.
    if (f.views.empty()) {
        if (f.stochastic) {
            if (f.stateSeq != progressiveSeq_) {
                progressive_.reset();
                ++restarts_;
            }
            progressiveSeq_ = f.stateSeq;
            if (held.linear()) progressive_.addLinear(held.linearImage(0).data(), images_[0].width, images_[0].height);
            else progressive_.add(images_[0]);
            images_[0] = progressive_.resolve();
        } else {
            progressiveSeq_ = UINT32_MAX;  // deterministic: every frame of a state is the same image
        }
    } else if (f.stochastic) {
        if (viewSums_.size() != images_.size()) viewSums_ = std::vector<ViewSum>(images_.size());
        for (size_t v = 0; v < images_.size(); ++v) {
            ViewSum& s = viewSums_[v];
            const CameraDesc& camera = f.views[v].camera;
            if (s.stateSeq != f.stateSeq || !s.camera || !(*s.camera == camera)) {
                s.sum.reset();
                s.stateSeq = f.stateSeq;
                s.camera = camera;
                ++restarts_;
            }
            if (held.linear()) s.sum.addLinear(held.linearImage(v).data(), images_[v].width, images_[v].height);
            else s.sum.add(images_[v]);
            images_[v] = s.sum.resolve();
        }
    }
    // The eyes (WallSession's composeEyes): without views the one image is the mono one.
    left_ = Image{};
    right_ = Image{};
    if (f.views.empty()) {
        left_ = std::move(images_[0]);
        return;
    }
    for (size_t v = 0; v < images_.size() && v < f.views.size() && v < f.eyes.size(); ++v) {
        Image& eye = f.eyes[v] == 1 ? right_ : left_;
        const FrameView& view = f.views[v];
        const Image& from = images_[v];
        if (view.regions.empty()) {
            eye = std::move(images_[v]);
            continue;
        }
        if (eye.rgb.empty()) {
            eye.width = from.width;
            eye.height = from.height;
            eye.rgb.assign(from.rgb.size(), 0);
        }
        for (const ViewRegion& g : view.regions) {
            const TileRect r = scaledRegion(g, view.refWidth, view.refHeight, from.width, from.height);
            for (int y = r.y0; y < r.y1; ++y) {
                const size_t row = (size_t(y) * size_t(from.width) + size_t(r.x0)) * 3;
                std::copy(from.rgb.begin() + long(row), from.rgb.begin() + long(row + size_t(r.width()) * 3), eye.rgb.begin() + long(row));
            }
        }
    }
}

}  // namespace rtwall::cluster
