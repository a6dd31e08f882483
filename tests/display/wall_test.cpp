// The wall library's plain parts: camera paths (one format, read and written in one file), the
// control table and run configs.
#include "display_test_util.h"

#include <rtwall/wall.h>

#include <cmath>
#include <set>

namespace rtwall {
namespace {

CameraKey key(int frame, Float3 position, float fov = 45.0f) {
    CameraKey k;
    k.frame = frame;
    k.camera.position = position;
    k.camera.lookAt = {0, 0, 0};
    k.camera.fovY = fov;
    return k;
}

// Recorded paths are written in world coordinates: the scene's rebasing origin is added back in
// double precision, so a float pose at 1e6 comes out exact, and reading the file with the same
// origin gives the very floats back.
TEST(CameraPath, WrittenInWorldCoordinatesAndReadBackExactly) {
    const std::array<double, 3> origin{1e6, -2e5, 3e5 + 0.5};
    CameraKey a = key(0, {0.25f, 1.0f, -2.0f}, 40.0f), b = key(7, {1.0f / 3.0f, -0.1f, 5e-3f}, 61.5f);
    b.camera.up = {0.0f, 0.8f, 0.6f};
    const std::string text = writeCameraPath({a, b}, origin);
    EXPECT_NE(text.find("position = [1000000.25, -199999, 299998.5]"), std::string::npos) << text;
    EXPECT_NE(text.find("look_at = [1000000, -200000, 300000.5]"), std::string::npos) << text;
    const auto file = test::writeFile(test::scratchDir() / "path.toml", text);
    const std::vector<CameraKey> back = readCameraPath(file, origin);
    ASSERT_EQ(back.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
        const CameraKey& w = i ? b : a;
        EXPECT_EQ(back[i].frame, w.frame);
        EXPECT_EQ(back[i].camera.position.x, w.camera.position.x) << i;
        EXPECT_EQ(back[i].camera.position.y, w.camera.position.y) << i;
        EXPECT_EQ(back[i].camera.position.z, w.camera.position.z) << i;
        EXPECT_EQ(back[i].camera.up.y, w.camera.up.y) << i;
        EXPECT_EQ(back[i].camera.fovY, w.camera.fovY) << i;
    }
    // Without an origin the numbers are the scene's own.
    EXPECT_NE(writeCameraPath({a}, {0, 0, 0}).find("position = [0.25, 1, -2]"), std::string::npos);
}

TEST(CameraPath, InterpolatesBetweenKeysAndHoldsAfterTheLast) {
    const std::vector<CameraKey> keys{key(10, {0, 0, 4}, 40), key(20, {10, 0, 4}, 60)};
    EXPECT_EQ(cameraAt(keys, 0).position.x, 0.0f);
    EXPECT_EQ(cameraAt(keys, 15).position.x, 5.0f);
    EXPECT_EQ(cameraAt(keys, 15).fovY, 50.0f);
    EXPECT_EQ(cameraAt(keys, 99).position.x, 10.0f);
}

TEST(CameraPath, BadFilesAreOneLineErrors) {
    const auto dir = test::scratchDir();
    auto error = [&](const std::string& text) {
        const auto file = test::writeFile(dir / "bad.toml", text);
        try {
            readCameraPath(file, {0, 0, 0});
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(error("").find("at least one [[key]]"), std::string::npos);
    EXPECT_NE(error("[[key]]\nframe = 3\nposition = [0,0,1]\nlook_at = [0,0,0]\n[[key]]\nframe = 3\nposition = [0,0,1]\n"
                    "look_at = [0,0,0]\n")
                  .find("bad.toml:6"),
              std::string::npos);
    EXPECT_NE(error("[[key]]\nframe = 1\nposition = [0,0,1]\nlook_at = [0,0,0]\nfield_of_view = 30\n").find("field_of_view"),
              std::string::npos);
}

TEST(Controls, EveryControlHasOneNameAndAppliesWithinItsRange) {
    std::set<std::string> names;
    RenderSettings base;
    base.width = 1600;
    base.height = 1200;
    for (const Control& c : controls()) {
        EXPECT_TRUE(names.insert(c.name).second) << "two controls named " << c.name;
        OperatingPoint p;
        p.name = "test";
        bool changed = false;  // at one end of its range at least, a control changes a setting
        for (double v : {c.min, c.max}) {
            p.controls = {{c.name, v}};
            const Knobs k = knobsOf(p, base, {});
            changed |= k.settings.tileSize != base.tileSize || k.settings.width != base.width ||
                       k.settings.supersample != base.supersample || k.settings.pruneThreshold != base.pruneThreshold ||
                       k.settings.gi != base.gi || k.codec.codec != CodecSettings{}.codec ||
                       k.codec.jpegQuality != CodecSettings{}.jpegQuality || k.volumeStep != 0 ||
                       k.denoise == DenoiseSettings::Mode::Svgf;
        }
        EXPECT_TRUE(changed) << c.name << " changes nothing";
        for (double v : c.sweep) EXPECT_TRUE(v >= c.min && v <= c.max) << c.name << " sweeps " << v;
        p.controls = {{c.name, c.max * 2 + 1}};
        EXPECT_THROW(knobsOf(p, base, {}), InputError) << c.name << " out of range";
    }
    OperatingPoint unknown;
    unknown.name = "p1";
    unknown.controls = {{"tile_size", 32}};
    try {
        knobsOf(unknown, base, {});
        ADD_FAILURE() << "an unknown control was applied";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'tile_size'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("gi_spp"), std::string::npos) << "names the known controls: " << e.what();
    }
    // What the sweep and the operating point mean by scale: a fraction of the wall's pixels.
    OperatingPoint half;
    half.controls = {{"scale", 0.5}};
    EXPECT_EQ(knobsOf(half, base, {}).settings.width, 800);
    // The denoise control names its modes; a point without it leaves the filter alone, and a
    // value between two modes is refused with their names.
    OperatingPoint dn;
    dn.name = "p2";
    EXPECT_FALSE(knobsOf(dn, base, {}).denoise);
    dn.controls = {{"denoise", 1}};
    EXPECT_EQ(knobsOf(dn, base, {}).denoise, DenoiseSettings::Mode::Temporal);
    dn.controls = {{"denoise", 1.5}};
    try {
        knobsOf(dn, base, {});
        ADD_FAILURE() << "denoise 1.5 was applied";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "operating point 'p2': control 'denoise' = 1.500000 is not a whole number (0 off, 1 temporal, 2 svgf)");
    }
}

TEST(Controls, TheJsonTheSweepReadsHasEveryControl) {
    const std::string json = controlsJson();
    for (const Control& c : controls()) {
        EXPECT_NE(json.find("\"name\" : \"" + std::string(c.name) + "\""), std::string::npos) << c.name;
        if (*c.option) {
            EXPECT_NE(json.find("\"option\" : \"" + std::string(c.option) + "\""), std::string::npos) << c.name;
        }
        for (const std::string& n : c.names) EXPECT_NE(json.find("\"" + n + "\""), std::string::npos) << c.name << ": " << n;
    }
}

// The README's first command runs the knot demo on the reference wall, the shipped 2x2 projector
// config built into the binary, holding an interactive frame rate.
TEST(RunConfig, TheEmbeddedDefaultIsTheKnotDemoOnTheReferenceWall) {
    const RunConfig c = defaultRunConfig();
    EXPECT_EQ(c.scene, "builtin:knots");
    EXPECT_EQ(c.width, 0);  // the wall sets the size
    EXPECT_EQ(c.cluster.localClients, 2);
    EXPECT_EQ(c.frames, 60);
    EXPECT_EQ(c.writeEvery, 30);
    EXPECT_EQ(c.targetFps, kDefaultTargetFps);
    ASSERT_TRUE(c.loadedWall);
    EXPECT_TRUE(c.hasWall());
    EXPECT_EQ(c.wall, "configs/wall/projectors-2x2.toml");
    EXPECT_EQ(c.loadedWall->width, 1600);
    EXPECT_EQ(c.loadedWall->height, 1200);
    EXPECT_EQ(c.loadedWall->screens.size(), 4u);
    EXPECT_EQ(c.loadedWall->writeEvery, c.writeEvery);  // projector images with the demo's frames, not every frame
    // Built from the shipped file: equal to it but for how often the headless wall writes.
    WallConfig shipped = loadWallConfig(test::sourceDir() / "configs/wall/projectors-2x2.toml");
    shipped.writeEvery = c.writeEvery;
    EXPECT_TRUE(*c.loadedWall == shipped);
    EXPECT_TRUE(checkWall(*c.loadedWall).empty());
}

TEST(RunConfig, PathsAreRelativeToTheFileAndTyposAreErrorsWithTheirLine) {
    const auto dir = test::scratchDir();
    const auto file = test::writeFile(dir / "run.toml", "scene = \"scene.toml\"\nwall = \"w.toml\"\n[run]\ncamera_path = \"p.toml\"\n");
    const RunConfig c = readRunConfig(file);
    EXPECT_EQ(c.scene, (dir / "scene.toml").string());
    EXPECT_EQ(c.wall, dir / "w.toml");
    EXPECT_EQ(c.cameraPath, dir / "p.toml");
    EXPECT_EQ(c.orbit, 0.0) << "a camera path replaces the orbit";
    const auto typo = test::writeFile(dir / "typo.toml", "scene = \"x.toml\"\n[cluster]\nclient = 3\n");
    try {
        readRunConfig(typo);
        ADD_FAILURE() << "a typo was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("typo.toml:3"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("'client'"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// The master's display-node settings from a wall config (issue 19): the nodes in the wall's
// order, and tile masks that are TileRouting's, per view by its eye.
// Two columns of two 320x240 screens with 4-pixel bezels, a node per column.
WallConfig twoNodeWall() {
    return parseWallConfig(R"([wall]
[grid]
columns = 2
rows = 2
screen_width = 320
screen_height = 240
bezel = [4, 4, 4, 4]
[[node]]
name = "left"
columns = [0, 0]
[[node]]
name = "right"
columns = [1, 1]
)",
                           "two-nodes.toml");
}

TEST(DisplayNodeSettings, RoutesTilesByTheWallsScreens) {
    const WallConfig wall = twoNodeWall();
    const DisplayNodeSettings d = displayNodeSettings(wall, "the text", {0, 1});
    EXPECT_EQ(d.names, (std::vector<std::string>{"left", "right"}));
    EXPECT_EQ(d.wallText, "the text");
    ASSERT_TRUE(d.routes);
    const TileRouting routing(wall, wall.width, wall.height);
    const std::vector<uint64_t> mono = d.routes(wall.width, wall.height, 48, {});
    EXPECT_EQ(mono, routing.routeTiles(48, 0));
    // Both nodes get some tiles, and the tiles at x = 288..335, under the middle bezel, go to both.
    EXPECT_NE(std::count(mono.begin(), mono.end(), 1u), 0);
    EXPECT_NE(std::count(mono.begin(), mono.end(), 2u), 0);
    EXPECT_NE(std::count(mono.begin(), mono.end(), 3u), 0);

    // Two views of the whole image: each view's tiles routed by its eye; a mono wall's screens
    // show no right eye, so the second view's tiles go nowhere.
    FrameView whole;
    const std::vector<uint64_t> views = d.routes(wall.width, wall.height, 48, {whole, whole});
    ASSERT_EQ(views.size(), 2 * mono.size());
    EXPECT_EQ(std::vector<uint64_t>(views.begin(), views.begin() + ptrdiff_t(mono.size())), mono);
    EXPECT_EQ(std::count(views.begin() + ptrdiff_t(mono.size()), views.end(), 0u), ptrdiff_t(mono.size()));
    // A view of unknown eye goes wherever either eye is shown.
    const std::vector<uint64_t> unknown = displayNodeSettings(wall, "", {}).routes(wall.width, wall.height, 48, {whole});
    EXPECT_EQ(unknown, mono);
}

// Denoising on a wall of several screens (issue 28): each screen is a window of its own (the
// filter's edges are the screen's and the ring's), overlapping screens share one, a view's
// windows are its regions' screens; and each node also gets the tiles within the ring of its
// windows, so that it filters them with the pixels the single-PC wall has.
TEST(DenoiseWindows, OneWindowPerScreenOverlapsMergedEachWithItsNodes) {
    const WallConfig wall = twoNodeWall();
    const TileRouting routing(wall, wall.width, wall.height);
    const auto mono = denoiseWindows(routing, wall.width, wall.height, {}, {});
    ASSERT_EQ(mono.size(), 1u);
    ASSERT_EQ(mono[0].size(), 4u);
    int left = 0, right = 0;
    for (const DenoiseWindow& w : mono[0]) {
        EXPECT_EQ(w.rect.width(), 320);
        EXPECT_EQ(w.rect.height(), 240);
        (w.rect.x0 < 320 ? left : right) += 1;
        EXPECT_EQ(w.nodes, w.rect.x0 < 320 ? 1u : 2u);
    }
    EXPECT_EQ(left, 2);
    EXPECT_EQ(right, 2);
    EXPECT_EQ(denoiseWindowRects(mono, 0)[0].size(), 2u);
    EXPECT_EQ(denoiseWindowRects(mono, 1)[0].size(), 2u);
    EXPECT_EQ(denoiseWindowRects(mono)[0].size(), 4u);

    // The ring: a tile 40 pixels right of the left screens (under the right ones) goes to both
    // nodes when they denoise with a 64-pixel ring, to the right one alone otherwise.
    const int tile = 16;
    const std::vector<uint64_t> plain = displayNodeSettings(wall, "", {-1}).routes(wall.width, wall.height, tile, {});
    const std::vector<uint64_t> ringed = displayNodeSettings(wall, "", {-1}, false, 64).routes(wall.width, wall.height, tile, {});
    ASSERT_EQ(plain.size(), ringed.size());
    const int columns = (wall.width + tile - 1) / tile;
    auto at = [&](const std::vector<uint64_t>& m, int x, int y) { return m[size_t(y / tile) * size_t(columns) + size_t(x / tile)]; };
    EXPECT_EQ(at(plain, 324 + 40, 100), 2u);
    EXPECT_EQ(at(ringed, 324 + 40, 100), 3u);
    EXPECT_EQ(at(ringed, 324 + 100, 100), 2u);  // beyond the ring
    for (size_t t = 0; t < plain.size(); ++t) EXPECT_EQ(ringed[t] & plain[t], plain[t]) << "tile " << t << ": the ring adds, never takes";

    // Two projectors blended over each other: one window over both, shown by both.
    const WallConfig blend = loadWallConfig(test::sourceDir() / "configs/wall/projector-pair-blend.toml");
    const auto merged = denoiseWindows(TileRouting(blend, blend.width, blend.height), blend.width, blend.height, {}, {});
    ASSERT_EQ(merged[0].size(), 1u);
    EXPECT_EQ(merged[0][0].rect, (TileRect{0, 0, blend.width, blend.height}));

    // Views with regions (a CAVE's planes): each view's windows are the screens of its regions,
    // of its eye.
    const WallConfig cave = loadWallConfig(test::sourceDir() / "configs/wall/cave-3.toml");
    std::vector<FrameView> views;
    std::vector<int> eyes;
    for (int eye : {0, 1})
        for (const ScreenConfig& sc : cave.screens) {
            if ((sc.eye == Eye::Right) != (eye == 1)) continue;
            FrameView v;
            v.regions = {{sc.viewport.x, sc.viewport.y, sc.viewport.width, sc.viewport.height}};
            v.refWidth = cave.width, v.refHeight = cave.height;
            views.push_back(v);
            eyes.push_back(eye);
        }
    ASSERT_FALSE(views.empty());
    const auto planes = denoiseWindows(TileRouting(cave, cave.width, cave.height), cave.width, cave.height, views, eyes);
    ASSERT_EQ(planes.size(), views.size());
    for (size_t v = 0; v < views.size(); ++v) {
        ASSERT_EQ(planes[v].size(), 1u) << "view " << v;
        const ViewRegion& g = views[v].regions[0];
        EXPECT_EQ(planes[v][0].rect, (TileRect{g.x, g.y, g.x + g.width, g.y + g.height})) << "view " << v;
    }
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// Display nodes started on this PC (issue 19) unless the run config says they run on their own PCs.
TEST(RunConfig, LocalDisplayNodesAreOnUnlessTurnedOff) {
    EXPECT_TRUE(defaultRunConfig().localDisplayNodes);
    const auto dir = test::scratchDir();
    EXPECT_FALSE(readRunConfig(test::writeFile(dir / "off.toml", "[cluster]\nlocal_display_nodes = false\n")).localDisplayNodes);
    EXPECT_TRUE(readRunConfig(test::writeFile(dir / "on.toml", "[cluster]\nlocal_display_nodes = true\n")).localDisplayNodes);
    try {
        readRunConfig(test::writeFile(dir / "bad.toml", "[cluster]\nclients = 1\nlocal_display_nodes = 0\n"));
        ADD_FAILURE() << "an integer was taken for a boolean";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.toml:3: [cluster]: key 'local_display_nodes': expected true or false, got an integer"), std::string::npos)
            << e.what();
    }
}

// How long the swap barrier waits for a slow display node before it leaves it out of a frame.
TEST(RunConfig, NodeStallTimeIsAKeyOfTheCluster) {
    EXPECT_EQ(defaultRunConfig().cluster.displayNodes.stallSeconds, 0.5);
    const auto dir = test::scratchDir();
    EXPECT_EQ(readRunConfig(test::writeFile(dir / "s.toml", "[cluster]\nnode_stall_ms = 2500\n")).cluster.displayNodes.stallSeconds, 2.5);
    try {
        readRunConfig(test::writeFile(dir / "bad.toml", "[cluster]\nnode_stall_ms = 0\n"));
        ADD_FAILURE() << "a stall time of 0 was taken";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.toml:2: [cluster]: key 'node_stall_ms': 0 is out of range"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace rtwall
