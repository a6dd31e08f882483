// The wall's side of display nodes (issue 19): the cluster routes tiles by masks it is given,
// and knows nothing of screens; this turns the wall config into those masks.
#include <rtwall/wall.h>

#include <utility>

namespace rtwall {

DisplayNodeSettings displayNodeSettings(const WallConfig& wall, std::string wallText, std::vector<int> viewEyes,
                                        bool reproject) {
    DisplayNodeSettings out;
    out.names = wall.nodes();
    out.wallText = std::move(wallText);
    out.viewEyes = viewEyes;
    out.reproject = reproject;
    out.routes = [wall, viewEyes, reproject](int width, int height, int tileSize, const std::vector<FrameView>& views) {
        const TileRouting routing(wall, width, height);
        // Re-projecting, a node warps pixels across its screens' edges: it also gets the ring of
        // tiles around what its screens show, so that a move of up to a tile at the seam between
        // two nodes is warped from pixels, not filled.
        const int ring = reproject ? tileSize : 0;
        if (views.empty() && ring == 0) return routing.routeTiles(tileSize, 0);
        std::vector<uint64_t> masks;
        const std::vector<ViewTile> tiles = views.empty() ? viewTiles({FrameView{}}, width, height, tileSize)
                                                          : viewTiles(views, width, height, tileSize);
        for (const ViewTile& t : tiles) {
            TileRect r = t.rect;
            r.x0 -= ring;
            r.y0 -= ring;
            r.x1 += ring;
            r.y1 += ring;
            if (views.empty()) {
                masks.push_back(routing.route(r.x0, r.y0, r.x1, r.y1, 0));
                continue;
            }
            const int eye = t.view < viewEyes.size() ? viewEyes[t.view] : -2;
            if (eye == -2) masks.push_back(routing.route(r.x0, r.y0, r.x1, r.y1, 0) | routing.route(r.x0, r.y0, r.x1, r.y1, 1));
            else masks.push_back(routing.route(r.x0, r.y0, r.x1, r.y1, eye < 0 ? 0 : eye));
        }
        return masks;
    };
    return out;
}

}  // namespace rtwall
