// Display nodes (issue 19) on the CPU: the node assignment in wall configs, and tile-to-node
// routing checked against the presentation itself: a node that receives only the tiles routed to
// it shows exactly the screens one machine with the whole frame shows, and every tile routed to a
// node changes what it shows.
#include "display_test_util.h"

#include <bit>
#include <random>

namespace rtwall {
namespace {

using test::wallError;

const std::string kGrid2x2 = "[wall]\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = 64\nscreen_height = 48\n";

TEST(DisplayNodes, GridRegionsAssignEveryScreenANode) {
    const WallConfig w = parseWallConfig(kGrid2x2 + "[[node]]\nname = \"left\"\ncolumns = [0, 0]\n"
                                                    "[[node]]\nname = \"right\"\ncolumns = [1, 1]\n",
                                         "w.toml");
    ASSERT_EQ(w.screens.size(), 4u);
    EXPECT_EQ(w.screens[0].node, "left");   // c0r0
    EXPECT_EQ(w.screens[1].node, "right");  // c1r0
    EXPECT_EQ(w.screens[2].node, "left");   // c0r1
    EXPECT_EQ(w.screens[3].node, "right");  // c1r1
    EXPECT_EQ(w.nodes(), (std::vector<std::string>{"left", "right"}));
    const WallConfig left = nodeWall(w, "left");
    ASSERT_EQ(left.screens.size(), 2u);
    EXPECT_EQ(left.screens[0].name, "c0r0");
    EXPECT_EQ(left.screens[1].name, "c0r1");
    EXPECT_EQ(left.width, w.width);
    EXPECT_THROW(nodeWall(w, "middle"), std::invalid_argument);
    // Written as explicit screens with their nodes, and read back the same.
    const std::string text = writeWallConfig(w);
    EXPECT_NE(text.find("node = \"right\""), std::string::npos);
    EXPECT_EQ(parseWallConfig(text, "again.toml"), w);
    // Without nodes the master drives everything: no node names anywhere.
    const WallConfig plain = parseWallConfig(kGrid2x2, "w.toml");
    EXPECT_TRUE(plain.nodes().empty());
    EXPECT_EQ(writeWallConfig(plain).find("node"), std::string::npos);
}

TEST(DisplayNodes, PassiveStereoRegionsTakeBothEyes) {
    const WallConfig w = parseWallConfig("[wall]\n[stereo]\nmode = \"passive\"\n[grid]\ncolumns = 2\nrows = 1\n"
                                         "screen_width = 64\nscreen_height = 48\n"
                                         "[[node]]\nname = \"a\"\ncolumns = [0, 0]\n[[node]]\nname = \"b\"\ncolumns = [1, 1]\n",
                                         "w.toml");
    ASSERT_EQ(w.screens.size(), 4u);
    EXPECT_EQ(w.screens[0].node, "a");  // c0r0L
    EXPECT_EQ(w.screens[2].node, "a");  // c0r0R
    EXPECT_EQ(w.screens[3].node, "b");  // c1r0R
}

TEST(DisplayNodes, ScreenListNamesNodes) {
    const WallConfig w = parseWallConfig("[wall]\nwidth = 100\nheight = 50\n[[screen]]\nname = \"a\"\nviewport = [0, 0, 50, 50]\n"
                                         "node = \"pc-2\"\n[[screen]]\nname = \"b\"\nviewport = [50, 0, 50, 50]\nnode = \"pc_1\"\n",
                                         "w.toml");
    EXPECT_EQ(w.nodes(), (std::vector<std::string>{"pc-2", "pc_1"}));
}

TEST(DisplayNodes, EveryMistakeIsOneLineWithFileLineAndKey) {
    const std::string two = "[wall]\nwidth = 100\nheight = 50\n[[screen]]\nname = \"a\"\nviewport = [0, 0, 50, 50]\nnode = \"n1\"\n"
                            "[[screen]]\nname = \"b\"\nviewport = [50, 0, 50, 50]\n";  // b is line 8, its viewport line 10
    EXPECT_EQ(wallError(two), "wall.toml:10: screen 'b': key 'node': missing; screen 'a' is on node 'n1', so every screen needs a node");
    EXPECT_EQ(wallError(two + "node = \"bad name\"\n"),
              "wall.toml:11: [[screen]] #2: key 'node': 'bad name' is not a node name (1 to 32 letters, digits, '-' or '_')");
    EXPECT_EQ(wallError(two + "node = 3\n"), "wall.toml:11: [[screen]] #2: key 'node': expected a string, got an integer");
    EXPECT_EQ(wallError(two + "[[node]]\nname = \"n1\"\n"),
              "wall.toml:11: [[node]] regions are for a [grid]; with [[screen]] give node = \"NAME\" on each screen");
    EXPECT_EQ(wallError(kGrid2x2 + "[[node]]\nname = \"l\"\ncolumns = [0, 0]\n"),
              "wall.toml:7: [[node]]: screen c1r0 is in no node's region (every screen needs a node)");
    EXPECT_EQ(wallError(kGrid2x2 + "[[node]]\nname = \"l\"\n[[node]]\nname = \"r\"\nrows = [1, 1]\n"),
              "wall.toml:11: [[node]] #2: screen c0r1 is in the region of node 'l' too");
    EXPECT_EQ(wallError(kGrid2x2 + "[[node]]\nname = \"l\"\ncolumns = [0, 2]\n"),
              "wall.toml:9: [[node]] #1: key 'columns': [0, 2] is not a first and last column of the grid's 0..1");
    EXPECT_EQ(wallError(kGrid2x2 + "[[node]]\nname = \"l\"\nrows = [1, 0]\n"),
              "wall.toml:9: [[node]] #1: key 'rows': [1, 0] is not a first and last row of the grid's 0..1");
    EXPECT_EQ(wallError(kGrid2x2 + "[[node]]\ncolumns = [0, 1]\n"), "wall.toml:7: [[node]] #1: missing required key 'name'");
    EXPECT_EQ(wallError(kGrid2x2 + "[[node]]\nname = \"l\"\ncolumns = [0, 0]\n[[node]]\nname = \"l\"\ncolumns = [1, 1]\n"),
              "wall.toml:11: [[node]] #2: key 'name': node 'l' has a region already (one [[node]] per node)");
    EXPECT_EQ(wallError(kGrid2x2 + "[[node]]\nname = \"l\"\nhost = \"x\"\n"), "wall.toml:9: [[node]] #1: unknown key 'host'");
    EXPECT_EQ(wallError(kGrid2x2 + "[[node]]\nname = \"\"\n"),
              "wall.toml:8: [[node]] #1: key 'name': '' is not a node name (1 to 32 letters, digits, '-' or '_')");
    EXPECT_EQ(wallError(kGrid2x2 + "node = \"x\"\n"), "wall.toml:7: [grid]: unknown key 'node'");
    // Node sets are 64-bit masks: 64 nodes are fine, a 65th is refused when the config is read.
    auto oneNodePerScreen = [](int columns, int rows) {
        std::string text = "[wall]\n[grid]\ncolumns = " + std::to_string(columns) + "\nrows = " + std::to_string(rows) +
                           "\nscreen_width = 8\nscreen_height = 8\n";
        for (int y = 0; y < rows; ++y)
            for (int x = 0; x < columns; ++x)
                text += "[[node]]\nname = \"n" + std::to_string(y * columns + x) + "\"\ncolumns = [" + std::to_string(x) + ", " +
                        std::to_string(x) + "]\nrows = [" + std::to_string(y) + ", " + std::to_string(y) + "]\n";
        return text;
    };
    EXPECT_EQ(parseWallConfig(oneNodePerScreen(8, 8), "w.toml").nodes().size(), 64u);
    EXPECT_EQ(wallError(oneNodePerScreen(13, 5)), "wall.toml:1: the screens name 65 display nodes, at most 64 are supported");
}

// A frame of random pixels (both eyes for stereo walls).
WallFrame randomFrame(const WallConfig& wall, int width, int height, uint32_t seed) {
    std::mt19937 rng(seed);
    WallFrame f;
    f.left = {width, height, std::vector<uint8_t>(size_t(width) * height * 3)};
    for (uint8_t& v : f.left.rgb) v = uint8_t(rng());
    if (wall.stereo.mode != StereoMode::None) {
        f.right = {width, height, std::vector<uint8_t>(size_t(width) * height * 3)};
        for (uint8_t& v : f.right.rgb) v = uint8_t(rng());
    }
    return f;
}

std::vector<Image> presentNode(const WallConfig& nodeWall, const WallFrame& frame) {
    std::vector<Image> out;
    for (size_t i = 0; i < nodeWall.screens.size(); ++i) {
        out.push_back(presentScreen(nodeWall, i, frame, {}));
        if (nodeWall.stereo.mode == StereoMode::QuadBuffer) out.push_back(presentScreen(nodeWall, i, frame, {.quadBufferEye = 1}));
    }
    return out;
}

void fill(Image& image, int x0, int y0, int x1, int y1, uint8_t value) {
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 3; ++c) image.pixel(x, y)[c] = uint8_t(value + c * 7);
}

// For every node: a frame whose tiles not routed to it are overwritten looks the same on its
// screens (routing is complete), and overwriting any one routed tile changes them (routing sends
// nothing a node does not need). Returns the routes, row-major per eye.
std::vector<uint64_t> checkRouting(const WallConfig& wall, int frameWidth, int frameHeight, int tile, bool minimal = true) {
    const TileRouting routing(wall, frameWidth, frameHeight);
    const std::vector<std::string> names = wall.nodes();
    EXPECT_EQ(routing.nodes(), names);
    const WallFrame frame = randomFrame(wall, frameWidth, frameHeight, 7);
    const int eyes = wall.stereo.mode == StereoMode::None ? 1 : 2;
    std::vector<uint64_t> routes;
    for (int eye = 0; eye < eyes; ++eye)
        for (int y = 0; y < frameHeight; y += tile)
            for (int x = 0; x < frameWidth; x += tile)
                routes.push_back(routing.route(x, y, std::min(x + tile, frameWidth), std::min(y + tile, frameHeight), eye));
    for (int eye = 0; eye < eyes; ++eye) {
        const std::vector<uint64_t> table = routing.routeTiles(tile, eye);
        const size_t perEye = routes.size() / size_t(eyes);
        EXPECT_EQ(table, std::vector<uint64_t>(routes.begin() + long(eye * perEye), routes.begin() + long((eye + 1) * perEye)));
    }
    for (size_t n = 0; n < names.size(); ++n) {
        SCOPED_TRACE("node " + names[n]);
        const WallConfig mine = nodeWall(wall, names[n]);
        const std::vector<Image> reference = presentNode(mine, frame);
        WallFrame partial = frame;
        size_t i = 0;
        for (int eye = 0; eye < eyes; ++eye)
            for (int y = 0; y < frameHeight; y += tile)
                for (int x = 0; x < frameWidth; x += tile, ++i)
                    if (!(routes[i] >> n & 1))
                        fill(eye ? partial.right : partial.left, x, y, std::min(x + tile, frameWidth), std::min(y + tile, frameHeight), 0);
        const std::vector<Image> shown = presentNode(mine, partial);
        for (size_t s = 0; s < shown.size(); ++s) EXPECT_EQ(shown[s].rgb, reference[s].rgb) << "screen " << s;
        if (!minimal) continue;
        i = 0;
        for (int eye = 0; eye < eyes; ++eye)
            for (int y = 0; y < frameHeight; y += tile)
                for (int x = 0; x < frameWidth; x += tile, ++i) {
                    if (!(routes[i] >> n & 1)) continue;
                    WallFrame changed = frame;
                    Image& img = eye ? changed.right : changed.left;
                    fill(img, x, y, std::min(x + tile, frameWidth), std::min(y + tile, frameHeight), 0);
                    WallFrame changed2 = frame;
                    fill(eye ? changed2.right : changed2.left, x, y, std::min(x + tile, frameWidth), std::min(y + tile, frameHeight), 255);
                    bool differs = false;
                    const auto a = presentNode(mine, changed), b = presentNode(mine, changed2);
                    for (size_t s = 0; s < a.size(); ++s) differs |= a[s].rgb != b[s].rgb;
                    EXPECT_TRUE(differs) << "tile at " << x << "," << y << " eye " << eye << " is routed but not shown";
                }
    }
    return routes;
}

TEST(TileRouting, BezelsSendStraddlingTilesToBothNodesAndHiddenOnesToNone) {
    // 2x2 screens of 64x48 with 8-pixel bezels on every edge: 16 hidden pixels between screens.
    const WallConfig w = parseWallConfig("[wall]\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = 64\nscreen_height = 48\n"
                                         "bezel = [8, 8, 8, 8]\n[[node]]\nname = \"left\"\ncolumns = [0, 0]\n"
                                         "[[node]]\nname = \"right\"\ncolumns = [1, 1]\n",
                                         "w.toml");
    ASSERT_EQ(w.width, 144);
    const TileRouting r(w, w.width, w.height);
    EXPECT_EQ(r.route(0, 0, 16, 16, 0), 1u);          // left screens only
    EXPECT_EQ(r.route(128, 0, 144, 16, 0), 2u);       // right screens only
    EXPECT_EQ(r.route(64, 0, 80, 16, 0), 0u);         // wholly under the bezel: nobody shows it
    EXPECT_EQ(r.route(56, 0, 72, 16, 0), 1u);         // the left screen's last 8 columns
    EXPECT_EQ(r.route(60, 0, 84, 16, 0), 3u);         // across the bezel: both
    EXPECT_EQ(r.route(0, 0, 16, 16, 1), 0u);          // a mono wall has no right eye
    // 16-pixel tiles: some lie wholly under a bezel; 28-pixel ones straddle the middle bezel.
    const auto aligned = checkRouting(w, w.width, w.height, 16);
    EXPECT_NE(std::count(aligned.begin(), aligned.end(), 0u), 0);
    const auto straddling = checkRouting(w, w.width, w.height, 28);
    EXPECT_NE(std::count(straddling.begin(), straddling.end(), 3u), 0);
}

TEST(TileRouting, BlendedOverlapGoesToBothProjectors) {
    const WallConfig w = parseWallConfig("[wall]\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = 64\nscreen_height = 48\n"
                                         "overlap = 16\n[[node]]\nname = \"top\"\nrows = [0, 0]\n[[node]]\nname = \"bottom\"\nrows = [1, 1]\n",
                                         "w.toml");
    ASSERT_EQ(w.height, 80);
    const TileRouting r(w, w.width, w.height);
    EXPECT_EQ(r.route(0, 32, 8, 48, 0), 3u);  // rows 32..47 are both rows' blend region
    EXPECT_EQ(r.route(0, 24, 8, 32, 0), 1u);
    EXPECT_EQ(r.route(0, 48, 8, 56, 0), 2u);
    checkRouting(w, w.width, w.height, 8);
}

TEST(TileRouting, PassiveStereoRoutesEachEyeToItsScreens) {
    // Left-eye projectors on one PC, right-eye ones on another (a common passive set-up).
    const WallConfig w = parseWallConfig(R"([wall]
width = 96
height = 48
[stereo]
mode = "passive"
[[screen]]
name = "l"
viewport = [0, 0, 96, 48]
eye = "left"
node = "pcL"
[[screen]]
name = "r"
viewport = [0, 0, 96, 48]
eye = "right"
node = "pcR"
)",
                                         "w.toml");
    const TileRouting r(w, w.width, w.height);
    EXPECT_EQ(r.route(0, 0, 16, 16, 0), 1u);
    EXPECT_EQ(r.route(0, 0, 16, 16, 1), 2u);
    const auto routes = checkRouting(w, w.width, w.height, 16);
    EXPECT_EQ(std::count(routes.begin(), routes.end(), 3u), 0);
}

TEST(TileRouting, SideBySideAndQuadBufferScreensNeedBothEyes) {
    for (const char* mode : {"side_by_side", "quad_buffer"}) {
        SCOPED_TRACE(mode);
        const WallConfig w = parseWallConfig(std::string("[wall]\n[stereo]\nmode = \"") + mode +
                                                 "\"\n[grid]\ncolumns = 2\nrows = 1\nscreen_width = 64\nscreen_height = 32\n"
                                                 "[[node]]\nname = \"a\"\ncolumns = [0, 0]\n[[node]]\nname = \"b\"\ncolumns = [1, 1]\n",
                                             "w.toml");
        const TileRouting r(w, w.width, w.height);
        EXPECT_EQ(r.route(0, 0, 16, 16, 0), 1u);
        EXPECT_EQ(r.route(0, 0, 16, 16, 1), 1u);
        EXPECT_EQ(r.route(112, 0, 128, 16, 1), 2u);
        // Side-by-side screens show half their columns per eye: some wall pixels are skipped,
        // so not every routed tile changes the picture; routing stays complete.
        checkRouting(w, w.width, w.height, 16, std::string(mode) == "quad_buffer");
    }
}

TEST(TileRouting, AFrameSmallerThanTheWallRoutesWhatUpscalingReads) {
    const WallConfig w = parseWallConfig(kGrid2x2 + "[[node]]\nname = \"left\"\ncolumns = [0, 0]\n"
                                                    "[[node]]\nname = \"right\"\ncolumns = [1, 1]\n",
                                         "w.toml");
    // 128x96 wall, 64x48 frame: the left screens' last wall column (63) reads frame columns
    // 31 and 32 (bilinear), the right screens' first (64) reads 31 and 32 as well.
    const TileRouting r(w, 64, 48);
    EXPECT_EQ(r.route(24, 0, 28, 8, 0), 1u);
    EXPECT_EQ(r.route(28, 0, 32, 8, 0), 3u);
    EXPECT_EQ(r.route(32, 0, 36, 8, 0), 3u);
    EXPECT_EQ(r.route(36, 0, 40, 8, 0), 2u);
    checkRouting(w, 64, 48, 4);
    // A scale that is not a power of two, tiles cut at the edge. Weights can be as small as
    // 1/256 here, too small to tell 0 from 255 after rounding, so completeness only.
    checkRouting(w, 50, 37, 5, false);
    EXPECT_THROW(TileRouting(w, 129, 96), std::invalid_argument);
}

TEST(TileRouting, AWallWithoutNodesHasTheMasterOnly) {
    const WallConfig w = parseWallConfig(kGrid2x2, "w.toml");
    const TileRouting r(w, w.width, w.height);
    EXPECT_EQ(r.nodes(), (std::vector<std::string>{""}));
    EXPECT_EQ(r.route(0, 0, 128, 96, 0), 1u);
}

TEST(TileRouting, ShippedTwoNodeWallSplitsInHalves) {
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/two-nodes-2x2.toml");
    ASSERT_EQ(w.nodes().size(), 2u);
    const TileRouting r(w, w.width, w.height);
    EXPECT_EQ(r.route(0, 0, 32, 32, 0), 1u);
    EXPECT_EQ(r.route(w.width - 32, w.height - 32, w.width, w.height, 0), 2u);
    checkRouting(w, w.width / 8, w.height / 8, 16, false);
}

// Each pixel's owner for the console's picture (issue 31): the lowest-numbered node asked
// whose screens read it, nobody under a bezel; a node not asked owns nothing, and its pixels
// go to another that reads them, where one does.
TEST(TileRouting, EachPixelHasOneOwnerTheLowestNodeAskedThatShowsIt) {
    const WallConfig w = parseWallConfig("[wall]\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = 64\nscreen_height = 48\n"
                                         "overlap = 16\n[[node]]\nname = \"top\"\nrows = [0, 0]\n[[node]]\nname = \"bottom\"\nrows = [1, 1]\n",
                                         "w.toml");
    const TileRouting r(w, w.width, w.height);
    const std::vector<uint8_t> both = r.owners(0, 3), bottom = r.owners(0, 2);
    ASSERT_EQ(both.size(), size_t(w.width) * w.height);
    auto at = [&](const std::vector<uint8_t>& o, int x, int y) { return int(o[size_t(y) * w.width + x]); };
    EXPECT_EQ(at(both, 5, 10), 0);
    EXPECT_EQ(at(both, 5, 40), 0);   // the blend rows: both read them, the top node owns them
    EXPECT_EQ(at(both, 5, 60), 1);
    EXPECT_EQ(at(bottom, 5, 10), 0xFF);  // the top node was not asked: nobody
    EXPECT_EQ(at(bottom, 5, 40), 1);     // the blend rows go to the bottom node
    EXPECT_EQ(r.owners(1, 3), std::vector<uint8_t>(both.size(), 0xFF));  // a mono wall has no right eye

    const WallConfig b = loadWallConfig(test::sourceDir() / "configs/wall/two-nodes-2x2.toml");
    const TileRouting rb(b, b.width, b.height);
    const std::vector<uint8_t> o = rb.owners(0, 3);
    // Every pixel a node's screens read is owned by one node, and exactly those are.
    for (int y = 0; y < b.height; y += 7)
        for (int x = 0; x < b.width; ++x) {
            const uint64_t needs = rb.route(x, y, x + 1, y + 1, 0);
            const int owner = o[size_t(y) * b.width + x];
            if (needs == 0) EXPECT_EQ(owner, 0xFF) << x << "," << y;
            else EXPECT_EQ(owner, std::countr_zero(needs)) << x << "," << y;
        }
    EXPECT_EQ(std::count(o.begin(), o.end(), 0xFF), 8 * b.height + 8 * b.width - 64) << "the bezels' pixels (8 wide)";
}

}  // namespace
}  // namespace rtwall
