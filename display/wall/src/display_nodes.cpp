// The wall's side of display nodes (issue 19): the cluster routes tiles by masks it is given,
// and knows nothing of screens; this turns the wall config into those masks.
#include <rtwall/wall.h>

#include <utility>

namespace rtwall {

DisplayNodeSettings displayNodeSettings(const WallConfig& wall, std::string wallText, std::vector<int> viewEyes) {
    DisplayNodeSettings out;
    out.names = wall.nodes();
    out.wallText = std::move(wallText);
    out.viewEyes = viewEyes;
    out.routes = [wall, viewEyes](int width, int height, int tileSize, const std::vector<FrameView>& views) {
        const TileRouting routing(wall, width, height);
        if (views.empty()) return routing.routeTiles(tileSize, 0);
        std::vector<uint64_t> masks;
        for (const ViewTile& t : viewTiles(views, width, height, tileSize)) {
            const TileRect& r = t.rect;
            const int eye = t.view < viewEyes.size() ? viewEyes[t.view] : -2;
            if (eye == -2) masks.push_back(routing.route(r.x0, r.y0, r.x1, r.y1, 0) | routing.route(r.x0, r.y0, r.x1, r.y1, 1));
            else masks.push_back(routing.route(r.x0, r.y0, r.x1, r.y1, eye < 0 ? 0 : eye));
        }
        return masks;
    };
    return out;
}

}  // namespace rtwall
