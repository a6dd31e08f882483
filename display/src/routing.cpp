// Tile-to-node routing: which display nodes read a frame tile's pixels. Derived from the same
// arithmetic that presents the screens (mapPixel, resizeBilinear), so a node that gets exactly
// the tiles routed to it shows the same pixels as one machine with the whole frame.
#include <rtwall/display.h>

#include <algorithm>
#include <stdexcept>

namespace rtwall {

namespace {

// The frame pixels [lo, hi] that bilinear upscaling from `frame` to `wall` pixels reads with a
// weight above zero for the wall pixels [first, last] (resizeBilinear's arithmetic; monotonic,
// so the ends decide).
std::pair<int, int> frameSpan(int first, int last, int wall, int frame) {
    if (wall == frame) return {first, last};
    const double s = double(frame) / wall;
    auto at = [&](int w) { return std::clamp((w + 0.5) * s - 0.5, 0.0, double(frame - 1)); };
    const double lo = at(first), hi = at(last);
    const int hiPixel = int(hi);
    return {int(lo), std::min(hiPixel + (hi > hiPixel ? 1 : 0), frame - 1)};
}

// The frame rectangle screen `s` reads of eye `eye`, or an empty one where it shows no such eye.
PixelRect screenNeeds(const WallConfig& wall, const ScreenConfig& s, int eye, int frameWidth, int frameHeight) {
    int outX0 = 0, outX1 = s.outputWidth - 1;
    if (s.eye == Eye::Both && wall.stereo.mode == StereoMode::SideBySide) {
        const int half = s.outputWidth / 2;
        if (eye == 0) outX1 = half - 1;
        else outX0 = half;
        if (outX1 < outX0) return {};
    } else if (s.eye == Eye::Both) {
        // Quad-buffered: both eyes over the whole screen.
    } else if ((s.eye == Eye::Right) != (eye == 1)) {
        return {};
    }
    const ScreenSample a = mapPixel(s, wall.stereo.mode, outX0, 0);
    const ScreenSample b = mapPixel(s, wall.stereo.mode, outX1, s.outputHeight - 1);
    const auto [x0, x1] = frameSpan(a.wallX, b.wallX, wall.width, frameWidth);
    const auto [y0, y1] = frameSpan(a.wallY, b.wallY, wall.height, frameHeight);
    return {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
}

}  // namespace

TileRouting::TileRouting(const WallConfig& wall, int frameWidth, int frameHeight) {
    if (frameWidth < 1 || frameHeight < 1 || frameWidth > wall.width || frameHeight > wall.height)
        throw std::invalid_argument("TileRouting: a " + std::to_string(frameWidth) + "x" + std::to_string(frameHeight) +
                                    " frame for a " + std::to_string(wall.width) + "x" + std::to_string(wall.height) +
                                    " wall: a frame is at most the wall's size");
    frameWidth_ = frameWidth;
    frameHeight_ = frameHeight;
    nodes_ = wall.nodes();
    if (nodes_.empty()) nodes_.push_back("");
    if (nodes_.size() > kMaxDisplayNodes)
        throw std::invalid_argument("TileRouting: " + std::to_string(nodes_.size()) + " display nodes, at most " +
                                    std::to_string(kMaxDisplayNodes));
    needs_.resize(nodes_.size());
    for (const ScreenConfig& s : wall.screens) {
        const size_t node = size_t(std::find(nodes_.begin(), nodes_.end(), s.node) - nodes_.begin());
        needs_[node].push_back({screenNeeds(wall, s, 0, frameWidth, frameHeight), screenNeeds(wall, s, 1, frameWidth, frameHeight)});
    }
}

uint64_t TileRouting::route(int x0, int y0, int x1, int y1, int eye) const {
    uint64_t mask = 0;
    if (eye < 0 || eye > 1) return 0;
    for (size_t n = 0; n < needs_.size(); ++n)
        for (const auto& screen : needs_[n]) {
            const PixelRect& r = screen[size_t(eye)];
            if (r.width > 0 && x0 < r.x + r.width && r.x < x1 && y0 < r.y + r.height && r.y < y1) {
                mask |= uint64_t(1) << n;
                break;
            }
        }
    return mask;
}

std::vector<uint8_t> TileRouting::owners(int eye, uint64_t nodes) const {
    std::vector<uint8_t> out(size_t(frameWidth_) * size_t(frameHeight_), 0xFF);
    if (eye < 0 || eye > 1) return out;
    for (size_t n = 0; n < needs_.size(); ++n) {
        if (!((nodes >> n) & 1)) continue;
        for (const auto& screen : needs_[n]) {
            const PixelRect& r = screen[size_t(eye)];
            const int x0 = std::max(0, r.x), x1 = std::min(frameWidth_, r.x + r.width);
            for (int y = std::max(0, r.y); y < std::min(frameHeight_, r.y + r.height); ++y) {
                uint8_t* row = out.data() + size_t(y) * size_t(frameWidth_);
                for (int x = x0; x < x1; ++x)
                    if (row[x] == 0xFF) row[x] = uint8_t(n);
            }
        }
    }
    return out;
}

std::vector<uint64_t> TileRouting::routeTiles(int tileSize, int eye) const {
    std::vector<uint64_t> masks;
    if (tileSize < 1) return masks;
    for (int y = 0; y < frameHeight_; y += tileSize)
        for (int x = 0; x < frameWidth_; x += tileSize)
            masks.push_back(route(x, y, std::min(frameWidth_, x + tileSize), std::min(frameHeight_, y + tileSize), eye));
    return masks;
}

}  // namespace rtwall
