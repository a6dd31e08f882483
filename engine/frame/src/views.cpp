// The tiling of a multi-view frame (rtwall/frame.h): one function for master, clients and nodes.
#include <rtwall/frame.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rtwall {

TileRect scaledRegion(const ViewRegion& v, int refWidth, int refHeight, int width, int height) {
    if (refWidth <= 0 || refHeight <= 0) return {};
    // 64-bit: a wall of 30k pixels times a frame of 30k would overflow int.
    TileRect r;
    r.x0 = int(int64_t(v.x) * width / refWidth);
    r.x1 = int((int64_t(v.x + v.width) * width + refWidth - 1) / refWidth);
    r.y0 = int(int64_t(v.y) * height / refHeight);
    r.y1 = int((int64_t(v.y + v.height) * height + refHeight - 1) / refHeight);
    r.x0 = std::clamp(r.x0, 0, width);
    r.x1 = std::clamp(r.x1, r.x0, width);
    r.y0 = std::clamp(r.y0, 0, height);
    r.y1 = std::clamp(r.y1, r.y0, height);
    return r;
}

std::vector<ScreenWarp> frameWarps(const FrameView& view, std::span<const std::shared_ptr<const PixelWarp>> grids,
                                   int width, int height) {
    std::vector<ScreenWarp> out;
    out.reserve(view.warps.size());
    for (const WarpRef& ref : view.warps) {
        if (ref.grid >= grids.size() || !grids[ref.grid])
            throw std::out_of_range("warp grid " + std::to_string(ref.grid) + " of " + std::to_string(grids.size()));
        ScreenWarp w;
        w.rect = scaledRegion(ref.rect, view.refWidth, view.refHeight, width, height);
        w.warp = grids[ref.grid];
        w.room = ref.room;
        // Exactly 1 at the reference size: the offsets then land where they were made to.
        if (width != view.refWidth) w.offsetScaleX = float(double(width) / view.refWidth);
        if (height != view.refHeight) w.offsetScaleY = float(double(height) / view.refHeight);
        out.push_back(std::move(w));
    }
    return out;
}

std::vector<ViewTile> viewTiles(const std::vector<FrameView>& views, int width, int height, int tileSize) {
    const std::vector<TileRect> tiles = makeTiles(width, height, tileSize);
    std::vector<ViewTile> out;
    std::vector<TileRect> regions;
    for (size_t v = 0; v < views.size(); ++v) {
        regions.clear();
        for (const ViewRegion& g : views[v].regions)
            regions.push_back(scaledRegion(g, views[v].refWidth, views[v].refHeight, width, height));
        for (const TileRect& t : tiles) {
            bool meets = views[v].regions.empty();
            for (const TileRect& g : regions)
                meets = meets || (t.x0 < g.x1 && g.x0 < t.x1 && t.y0 < g.y1 && g.y0 < t.y1);
            if (meets) out.push_back({uint32_t(v), t});
        }
    }
    return out;
}

}  // namespace rtwall
