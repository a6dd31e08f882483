// The operator console's picture of a wall on display nodes (issue 31): an application thread
// asks (Master::nodePicture) and waits; the network thread sends every node present a
// NodePreviewAsk and adds up the cells of their answers (NodePreview, in parts). Each pixel is
// summed by one node only, so the sums add up to the picture of the whole frame. A node that
// leaves counts as missing at once; a wrong part is dropped and its node counted as missing.
#include "codec.h"
#include "master_impl.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace rtwall {

namespace {
constexpr size_t kMaxPicturesAtOnce = 8;
constexpr size_t kMaxPictureCells = size_t(1) << 22;  // a box-filtered picture's cells per eye (a thumbnail)
}  // namespace

std::optional<NodePicture> Master::nodePicture(int width, int timeoutMs) {
    Impl& s = *impl_;
    if (!s.withNodes()) return std::nullopt;
    if (width < 1 || width > kNodePictureEveryPixel)
        throw std::invalid_argument("Master::nodePicture: width " + std::to_string(width) + " (1 to " +
                                    std::to_string(kNodePictureEveryPixel) + ")");
    uint32_t id;
    {
        std::lock_guard lock(s.pictureMutex);
        if (s.pictures.size() >= kMaxPicturesAtOnce) return std::nullopt;
        id = ++s.nextPicture;
        if (id == 0) id = ++s.nextPicture;
        s.pictures[id].width = width;
    }
    s.wake();
    std::unique_lock lock(s.pictureMutex);
    s.pictureCv.wait_for(lock, std::chrono::milliseconds(std::max(0, timeoutMs)), [&] {
        const Impl::PictureTake& t = s.pictures.at(id);
        return t.sent && (t.answered | t.refused) == t.asked;
    });
    Impl::PictureTake take = std::move(s.pictures.at(id));
    s.pictures.erase(id);
    lock.unlock();
    if (take.sent && take.asked == 0) return std::nullopt;
    NodePicture out;
    const std::vector<std::string>& names = s.settings.displayNodes.names;
    for (size_t i = 0; i < names.size(); ++i)
        if (!(take.answered >> i & 1) || ((take.refused | take.blank) >> i & 1)) out.missing.push_back(names[i]);
    if (take.srcWidth == 0) return out;  // no pixels came
    out.frame = take.newest;
    out.oneFrame = take.oldest == take.newest;
    for (int e = 0; e < (take.stereo ? 2 : 1); ++e) {
        Impl::PictureEye& eye = take.eyes[e];
        Image& im = e == 0 ? out.left : out.right;
        if (eye.direct && !eye.image.rgb.empty()) {
            im = std::move(eye.image);
        } else if (!eye.direct && !eye.sums.empty()) {
            im = boxMeans(eye.grid, eye.sums.data());
        } else {  // no part of this eye came: black
            im.width = eye.grid.width;
            im.height = eye.grid.height;
            im.rgb.assign(eye.grid.cells() * 3, 0);
        }
    }
    return out;
}

// On the network thread, after a wake: the asks not yet sent go to every node present.
void Master::Impl::sendPictureAsks() {
    std::lock_guard lock(pictureMutex);
    bool any = false;
    for (auto& [id, take] : pictures) {
        if (take.sent) continue;
        for (const auto& [peer, n] : display.nodes)
            if (!n.deathReason) take.asked |= uint64_t(1) << n.index;
        for (auto& [peer, n] : display.nodes)
            if ((take.asked >> n.index & 1) && !n.deathReason && !sendNode(n, NodePreviewAsk{id, take.width, take.asked}))
                take.refused |= uint64_t(1) << n.index;
        take.sent = any = true;
    }
    if (any) pictureCv.notify_all();
}

// A node left: the pictures waiting for it stop waiting.
void Master::Impl::pictureNodeGone(uint32_t node) {
    std::lock_guard lock(pictureMutex);
    for (auto& [id, take] : pictures)
        if ((take.asked >> node & 1) && !(take.answered >> node & 1)) take.refused |= uint64_t(1) << node;
    pictureCv.notify_all();
}

void Master::Impl::onNodePreview(NodeState& n, const NodePreview& part) {
    std::lock_guard lock(pictureMutex);
    const auto it = pictures.find(part.id);
    if (it == pictures.end()) return;  // a picture no longer waited for (it timed out)
    PictureTake& take = it->second;
    const uint64_t bit = uint64_t(1) << n.index;
    auto refuse = [&](const std::string& why) {
        take.refused |= bit;
        pictureCv.notify_all();
        unexpected("a picture part from display node '" + n.name + "': " + why);
    };
    if (!(take.asked & bit) || ((take.answered | take.refused) & bit)) {
        if (!(take.refused & bit)) refuse("it was not asked for one, or already answered");
        return;
    }
    if (part.frame != 0) {
        // A frame the nodes were sent lately, at its size (a node's word alone would let it set
        // the picture's size for the honest ones).
        const auto& sizes = display.frameSizes;
        const auto sent = std::find_if(sizes.begin(), sizes.end(), [&](const DisplayNodes::FrameSize& f) { return f.frame == part.frame; });
        if (sent == sizes.end()) return refuse("frame " + std::to_string(part.frame) + ", which the nodes were not sent lately");
        if (sent->width != part.srcWidth || sent->height != part.srcHeight)
            return refuse("frame " + std::to_string(part.frame) + " at " + std::to_string(part.srcWidth) + "x" +
                          std::to_string(part.srcHeight) + ", not " + std::to_string(sent->width) + "x" + std::to_string(sent->height));
        if (take.srcWidth == 0) {
            BoxGrid grid;
            try {
                grid = boxGrid(part.srcWidth, part.srcHeight, take.width);
            } catch (const std::invalid_argument& e) {
                return refuse(e.what());
            }
            const bool direct = grid.width == part.srcWidth && grid.height == part.srcHeight;
            if (!direct && grid.cells() > kMaxPictureCells) return refuse("a picture of " + std::to_string(grid.cells()) + " cells");
            take.srcWidth = part.srcWidth;
            take.srcHeight = part.srcHeight;
            for (PictureEye& eye : take.eyes) {
                eye.grid = grid;
                eye.direct = direct;
            }
        } else if (part.srcWidth != take.srcWidth || part.srcHeight != take.srcHeight) {
            // An honest node that presented a frame of another size (the resolution changed
            // between the nodes' frames): not in this picture, and not counted as dropped.
            take.refused |= bit;
            pictureCv.notify_all();
            return;
        }
        take.oldest = std::min(take.oldest, part.frame);
        take.newest = std::max(take.newest, part.frame);
    }
    const size_t cells = size_t(part.x1 - part.x0) * size_t(part.y1 - part.y0);
    if (cells > 0) {
        PictureEye& eye = take.eyes[part.eye];
        const BoxGrid& g = eye.grid;
        if (part.x1 > g.width || part.y1 > g.height)
            return refuse("cells up to " + std::to_string(part.x1) + "," + std::to_string(part.y1) + " of a " +
                          std::to_string(g.width) + "x" + std::to_string(g.height) + " picture");
        std::vector<uint32_t> values(cells * 4);
        try {
            decodePreviewCells(part.cells.data(), part.cells.size(), cells, part.valueBytes, values.data(), pictureScratch);
        } catch (const DecodeError& e) {
            return refuse(e.what());
        }
        if (eye.direct && eye.image.rgb.empty()) {
            eye.image.width = g.width;
            eye.image.height = g.height;
            eye.image.rgb.assign(g.cells() * 3, 0);
        } else if (!eye.direct && eye.sums.empty()) {
            eye.sums.assign(g.cells() * 4, 0);
        }
        // Every cell's sums must be those of at most its pixels (a node cannot claim more).
        for (int y = part.y0, i = 0; y < part.y1; ++y) {
            const int64_t rows = int64_t(y + 1) * g.srcHeight / g.height - int64_t(y) * g.srcHeight / g.height;
            for (int x = part.x0; x < part.x1; ++x, i += 4) {
                const int64_t area = rows * (int64_t(x + 1) * g.srcWidth / g.width - int64_t(x) * g.srcWidth / g.width);
                const uint32_t* v = values.data() + i;
                const size_t cell = size_t(y) * size_t(g.width) + size_t(x);
                uint32_t* sum = eye.direct ? nullptr : eye.sums.data() + cell * 4;
                const int64_t count = int64_t(v[3]) + (sum ? sum[3] : 0);
                if (count > area || int64_t(v[0]) > 255 * int64_t(v[3]) || int64_t(v[1]) > 255 * int64_t(v[3]) ||
                    int64_t(v[2]) > 255 * int64_t(v[3]))
                    return refuse("cell " + std::to_string(x) + "," + std::to_string(y) + " holds more than its pixels");
                if (sum) {
                    for (int k = 0; k < 4; ++k) sum[k] += v[k];
                } else if (v[3] == 1) {
                    for (int k = 0; k < 3; ++k) eye.image.rgb[cell * 3 + size_t(k)] = uint8_t(v[k]);
                }
            }
        }
        if (part.eye == 1) take.stereo = true;
    }
    if (part.frame == 0) take.blank |= bit;  // nothing presented yet: not in the picture
    if (part.last) {
        take.answered |= bit;
        pictureCv.notify_all();
    }
}

}  // namespace rtwall
