// The wall's side of display nodes (issue 19): the cluster routes tiles by masks it is given,
// and knows nothing of screens; this turns the wall config into those masks.
#include <rtwall/wall.h>

#include <algorithm>
#include <utility>

namespace rtwall {

std::vector<std::vector<DenoiseWindow>> denoiseWindows(const TileRouting& routing, int width, int height,
                                                       const std::vector<FrameView>& views, const std::vector<int>& eyes) {
    auto meets = [](const TileRect& a, const TileRect& b) { return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1; };
    const size_t count = std::max<size_t>(1, views.size());
    std::vector<std::vector<DenoiseWindow>> out(count);
    for (size_t v = 0; v < count; ++v) {
        const int eye = v < eyes.size() && eyes[v] == 1 ? 1 : 0;
        std::vector<TileRect> regions;
        if (v < views.size())
            for (const ViewRegion& g : views[v].regions)
                regions.push_back(scaledRegion(g, views[v].refWidth, views[v].refHeight, width, height));
        std::vector<DenoiseWindow>& list = out[v];
        for (size_t n = 0; n < routing.nodes().size(); ++n)
            for (const auto& screen : routing.needs(n)) {
                const PixelRect& p = screen[size_t(eye)];
                if (p.width <= 0 || p.height <= 0) continue;
                const TileRect r{std::max(0, p.x), std::max(0, p.y), std::min(width, p.x + p.width), std::min(height, p.y + p.height)};
                if (r.width() <= 0 || r.height() <= 0) continue;
                if (!regions.empty() && std::none_of(regions.begin(), regions.end(), [&](const TileRect& g) { return meets(g, r); }))
                    continue;
                list.push_back({r, uint64_t(1) << n});
            }
        // Overlapping windows become one (their bounding box), until none overlap.
        for (bool merged = true; merged;) {
            merged = false;
            for (size_t a = 0; a < list.size() && !merged; ++a)
                for (size_t b = a + 1; b < list.size() && !merged; ++b) {
                    if (!meets(list[a].rect, list[b].rect)) continue;
                    TileRect& r = list[a].rect;
                    const TileRect& q = list[b].rect;
                    r = {std::min(r.x0, q.x0), std::min(r.y0, q.y0), std::max(r.x1, q.x1), std::max(r.y1, q.y1)};
                    list[a].nodes |= list[b].nodes;
                    list.erase(list.begin() + long(b));
                    merged = true;
                }
        }
    }
    return out;
}

std::vector<std::vector<TileRect>> denoiseWindowRects(const std::vector<std::vector<DenoiseWindow>>& windows, int node) {
    std::vector<std::vector<TileRect>> out(windows.size());
    for (size_t v = 0; v < windows.size(); ++v)
        for (const DenoiseWindow& w : windows[v])
            if (node < 0 || (node < 64 && ((w.nodes >> node) & 1))) out[v].push_back(w.rect);
    return out;
}

DisplayNodeSettings displayNodeSettings(const WallConfig& wall, std::string wallText, std::vector<int> viewEyes,
                                        bool reproject, int denoiseRing) {
    DisplayNodeSettings out;
    out.names = wall.nodes();
    out.wallText = std::move(wallText);
    out.viewEyes = viewEyes;
    out.reproject = reproject;
    out.routes = [wall, viewEyes, reproject, denoiseRing](int width, int height, int tileSize, const std::vector<FrameView>& views) {
        const TileRouting routing(wall, width, height);
        // Re-projecting, a node warps pixels across its screens' edges: it also gets the ring of
        // tiles around what its screens show, so that a move of up to a tile at the seam between
        // two nodes is warped from pixels, not filled.
        const int ring = reproject ? tileSize : 0;
        if (views.empty() && ring == 0 && denoiseRing == 0) return routing.routeTiles(tileSize, 0);
        // Denoising, a node filters each window of its screens with the pixels within the ring
        // around it: it gets the tiles that meet that.
        std::vector<std::vector<DenoiseWindow>> windows;
        if (denoiseRing > 0) windows = denoiseWindows(routing, width, height, views, viewEyes);
        std::vector<uint64_t> masks;
        const std::vector<ViewTile> tiles = views.empty() ? viewTiles({FrameView{}}, width, height, tileSize)
                                                          : viewTiles(views, width, height, tileSize);
        for (const ViewTile& t : tiles) {
            TileRect r = t.rect;
            r.x0 -= ring;
            r.y0 -= ring;
            r.x1 += ring;
            r.y1 += ring;
            uint64_t mask = 0;
            if (views.empty()) {
                mask = routing.route(r.x0, r.y0, r.x1, r.y1, 0);
            } else {
                const int eye = t.view < viewEyes.size() ? viewEyes[t.view] : -2;
                if (eye == -2) mask = routing.route(r.x0, r.y0, r.x1, r.y1, 0) | routing.route(r.x0, r.y0, r.x1, r.y1, 1);
                else mask = routing.route(r.x0, r.y0, r.x1, r.y1, eye < 0 ? 0 : eye);
            }
            if (t.view < windows.size())
                for (const DenoiseWindow& w : windows[t.view])
                    if (t.rect.x0 < w.rect.x1 + denoiseRing && w.rect.x0 - denoiseRing < t.rect.x1 &&
                        t.rect.y0 < w.rect.y1 + denoiseRing && w.rect.y0 - denoiseRing < t.rect.y1)
                        mask |= w.nodes;
            masks.push_back(mask);
        }
        return masks;
    };
    return out;
}

}  // namespace rtwall
