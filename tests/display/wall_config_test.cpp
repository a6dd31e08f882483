#include "display_test_util.h"
#include "wall_config_keys.h"

namespace rtwall {
namespace {

using test::wallError;

std::vector<std::filesystem::path> shippedWalls() {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(test::sourceDir() / "configs/wall"))
        if (e.path().extension() == ".toml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

// Equalizer's loader test: load every shipped config, write it out, reload, compare.
TEST(WallConfig, EveryShippedConfigLoadsWritesAndReloads) {
    const auto files = shippedWalls();
    ASSERT_GE(files.size(), 5u);
    for (const auto& file : files) {
        SCOPED_TRACE(file.string());
        const WallConfig a = loadWallConfig(file);
        const std::string text = writeWallConfig(a);
        const WallConfig b = parseWallConfig(text, "written.toml");
        EXPECT_EQ(a, b) << text;
        EXPECT_EQ(writeWallConfig(b), text);
        EXPECT_TRUE(checkWall(file).empty());
    }
}

// Mitsuba's rule, every key read: the parser reads only keys of its tables, and every key of the
// tables is documented, with the tables' help, in configs/README.md.
TEST(WallConfig, EveryKeyOfTheTablesIsDocumented) {
    const std::vector<std::string> missing =
        toml_reader::undocumentedKeys(wall_keys::kAll, test::sourceDir() / "configs/README.md");
    EXPECT_TRUE(missing.empty()) << ::testing::PrintToString(missing);
}

TEST(WallConfig, TheReferenceWallIsTwoByTwoProjectors) {
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/projectors-2x2.toml");
    EXPECT_EQ(w.width, 1600);
    EXPECT_EQ(w.height, 1200);
    ASSERT_EQ(w.screens.size(), 4u);
    EXPECT_EQ(w.screens[0].viewport, (PixelRect{0, 0, 800, 600}));
    EXPECT_EQ(w.screens[1].viewport, (PixelRect{800, 0, 800, 600}));
    EXPECT_EQ(w.screens[2].viewport, (PixelRect{0, 600, 800, 600}));
    EXPECT_EQ(w.screens[3].viewport, (PixelRect{800, 600, 800, 600}));
    EXPECT_EQ(w.screens[3].window, (std::array<int, 2>{800, 600}));
}

TEST(WallConfig, BezelsInMillimetresBecomeHiddenPixels) {
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/monitors-3x2-bezels.toml");
    // 4.15 mm of a 531 mm, 1920-pixel screen is 15 pixels; between two screens 30 are hidden.
    EXPECT_EQ(w.width, 3 * 1920 + 2 * 30);
    EXPECT_EQ(w.height, 2 * 1080 + 30);
    ASSERT_EQ(w.screens.size(), 6u);
    EXPECT_EQ(w.screens[1].viewport, (PixelRect{1950, 0, 1920, 1080}));
    EXPECT_EQ(w.screens[4].viewport, (PixelRect{1950, 1110, 1920, 1080}));
    EXPECT_EQ(w.screens[5].monitor, 5);
}

TEST(WallConfig, GridOverlapGetsBlendRampsOnInnerEdges) {
    const WallConfig w = parseWallConfig("[wall]\n[grid]\ncolumns = 2\nrows = 1\nscreen_width = 800\nscreen_height = 600\noverlap = 100\n",
                                         "w.toml");
    EXPECT_EQ(w.width, 1500);
    EXPECT_EQ(w.screens[0].blend, (std::array<int, 4>{0, 100, 0, 0}));
    EXPECT_EQ(w.screens[1].blend, (std::array<int, 4>{100, 0, 0, 0}));
    EXPECT_EQ(w.screens[1].viewport.x, 700);
}

TEST(WallConfig, PassiveStereoGridMakesAScreenPerEye) {
    const WallConfig w = parseWallConfig("[wall]\n[stereo]\nmode = \"passive\"\n[grid]\ncolumns = 2\nrows = 1\n"
                                         "screen_width = 640\nscreen_height = 480\n",
                                         "w.toml");
    ASSERT_EQ(w.screens.size(), 4u);
    EXPECT_EQ(w.screens[0].eye, Eye::Left);
    EXPECT_EQ(w.screens[2].eye, Eye::Right);
    EXPECT_EQ(w.screens[2].viewport, w.screens[0].viewport);
}

const char* kPair = R"([wall]
width = 1500
height = 600

[[screen]]
name = "a"
viewport = [0, 0, 800, 600]

[[screen]]
name = "b"
viewport = [700, 0, 800, 600]
)";

TEST(WallConfig, OverlappingScreensWithoutBlendingAreAnError) {
    EXPECT_EQ(wallError(kPair), "wall.toml:11: screen 'b': key 'viewport': overlaps screen 'a' by 100x600 wall pixels "
                                "that no blend ramp of both screens covers");
    // One side blended is not enough.
    std::string oneSide = kPair;
    oneSide.insert(oneSide.find("\n\n[[screen]]\nname = \"b\""), "\nblend = [0, 100, 0, 0]");
    EXPECT_NE(wallError(oneSide).find("overlaps screen 'a'"), std::string::npos);
    // Both sides blended over the whole overlap: fine.
    std::string both = oneSide + "blend = [100, 0, 0, 0]\n";
    EXPECT_NO_THROW(parseWallConfig(both, "wall.toml"));
    // Left and right eye may share pixels; two left-eye screens may not.
    const std::string eyes = "[stereo]\nmode = \"passive\"\n" + std::string(kPair);
    EXPECT_NE(wallError(eyes).find("key 'eye': passive stereo needs"), std::string::npos);
}

TEST(WallConfig, EveryKindOfMistakeNamesLineAndKey) {
    struct Case {
        std::string text, expected;
    };
    const std::string grid = "[wall]\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = 800\nscreen_height = 600\n";
    const std::string tracked =
        "[stereo]\nlower_left = [-1, -1, 0]\nlower_right = [1, -1, 0]\nupper_left = [-1, 1, 0]\n[tracking]\n";  // [tracking] is line 11
    const std::vector<Case> cases = {
        {grid + "bezel = [500, 400, 0, 0]\n", "wall.toml:7: [grid]: the bezel (900 pixels left and right) is wider than the screen (800)"},
        {grid + "bezel = [0, 0, 300, 300]\n", "wall.toml:7: [grid]: the bezel (600 pixels top and bottom) is taller than the screen (600)"},
        {grid + "bezel_mm = [5, 5, 5, 5]\n", "wall.toml:7: [grid]: key 'bezel_mm' needs 'screen_mm'"},
        {grid + "colums = 3\n", "wall.toml:7: [grid]: unknown key 'colums'"},
        {"[wall]\n[grid]\ncolumns = 2\nscreen_width = \"800\"\nscreen_height = 600\n",
         "wall.toml:4: [grid]: key 'screen_width': expected an integer, got a string"},
        {grid + "bezel = [1, 2, 3]\n", "wall.toml:7: [grid]: key 'bezel': expected an array of 4 integers"},
        {grid + "bezel = [1, 2.5, 3, 4]\n", "wall.toml:7: [grid]: key 'bezel': element 1 is a float, not an integer"},
        {grid + "gamma = -1\n", "wall.toml:7: [grid]: key 'gamma': -1 is out of range"},
        {grid + "overlap = 10\nbezel = [1, 1, 1, 1]\n", "wall.toml:7: [grid]: overlapping projectors have no bezels"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [50, 0, 100, 100]\n",
         "wall.toml:5: [[screen]] #1: key 'viewport': [50, 0, 100, 100] reaches outside the 100x100 wall"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\nblend = [60, 60, 0, 0]\n",
         "wall.toml:6: [[screen]] #1: key 'blend': the ramps are wider than the screen's viewport"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nname = \"x\"\nviewport = [0, 0, 50, 100]\n"
         "[[screen]]\nname = \"x\"\nviewport = [50, 0, 50, 100]\n",
         "wall.toml:8: [[screen]] #2: key 'name': 'x' is used by another screen"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\neye = \"left\"\n",
         "wall.toml:5: screen 'screen1': key 'eye': 'left' needs a [stereo] mode"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\neye = \"center\"\n",
         "wall.toml:6: [[screen]] #1: key 'eye': 'center' is not one of mono, left, right, both"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\nshader = \"nope.frag\"\n",
         "wall.toml:6: [[screen]] #1: key 'shader': no such file"},
        {"[wall]\nwidth = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\n", "[wall]: missing required key 'height'"},
        {"[wall]\nwidht = 100\n", "wall.toml:2: [wall]: unknown key 'widht'"},
        {"[grid]\ncolumns = 1\n", "missing required table [wall]"},
        {"[wall]\nwidth = 10\nheight = 10\n", "a wall needs a [grid] or a list of [[screen]]"},
        {grid + "[[screen]]\nviewport = [0, 0, 1, 1]\n", "give either [grid] or [[screen]], not both"},
        {"screen = 3\n[wall]\nwidth = 10\nheight = 10\n", "wall.toml:1: 'screen' must be an array of tables"},
        {"[wall]\nname = \"x\n", "wall.toml:2: "},
        {grid + "[stereo]\nmode = \"anaglyph\"\n", "wall.toml:8: [stereo]: key 'mode': 'anaglyph' is not one of"},
        {grid + "[stereo]\nmode = \"passive\"\nupper_left = [-1, -0.75, 0]\n", "wall.toml:9: [stereo]: the wall's corners must span a rectangle"},
        {grid + "[stereo]\nmode = \"passive\"\nupper_left = [0, 0.75, 0]\n", "wall.toml:9: [stereo]: lower_left->lower_right and lower_left->upper_left must be at right angles"},
        {grid + "[headless]\nvideo = \"a'; rm -rf x.mp4\"\n",
         "wall.toml:8: [headless]: key 'video': a plain file name of letters, digits, '.', '-' and '_' (it goes to ffmpeg)"},
        {grid + "[headless]\nvideo = \"-y.mp4\"\n",
         "wall.toml:8: [headless]: key 'video': a plain file name of letters, digits, '.', '-' and '_' (it goes to ffmpeg)"},
        {grid + "[headless]\nwrite_every = true\n", "wall.toml:8: [headless]: key 'write_every': expected an integer, got a boolean"},
        {grid + "[tracking]\n", "wall.toml:7: [tracking]: a tracked wall needs its physical corners"},
        {grid + tracked + "source = \"udp://0.0.0.0:5000\"\n",
         "wall.toml:12: [tracking]: key 'source': expected dtrack://ADDRESS:PORT with an IPv4 address to listen on and a UDP port"},
        {grid + tracked + "source = \"dtrack://0.0.0.0:70000\"\n", "[tracking]: key 'source': expected dtrack://"},
        {grid + tracked + "source = \"dtrack://300.0.0.1:5000\"\n", "[tracking]: key 'source': expected dtrack://"},
        {grid + tracked + "source = \"dtrack://localhost:5000\"\n", "[tracking]: key 'source': expected dtrack://"},
        {grid + tracked + "head_body = -1\n", "wall.toml:12: [tracking]: key 'head_body': -1 is out of range"},
        {grid + tracked + "flystick = \"0\"\n", "wall.toml:12: [tracking]: key 'flystick': expected an integer, got a string"},
        {grid + tracked + "room_scale = 0\n", "wall.toml:12: [tracking]: key 'room_scale': 0 is out of range"},
        {grid + tracked + "room_rotate = [0, 400, 0]\n", "wall.toml:12: [tracking]: key 'room_rotate': angles are degrees in [-360, 360]"},
        {grid + tracked + "room_translate = [0, 0]\n", "wall.toml:12: [tracking]: key 'room_translate': expected an array of 3 numbers"},
        {grid + tracked + "timeout_ms = 0\n", "wall.toml:12: [tracking]: key 'timeout_ms': 0 is out of range"},
        {grid + tracked + "prediction_ms = -5\n", "wall.toml:12: [tracking]: key 'prediction_ms': -5 is out of range"},
        {grid + tracked + "filter = \"kalman\"\n", "wall.toml:12: [tracking]: key 'filter': 'kalman' is not one of none, one_euro"},
        {grid + tracked + "beta = 3\n", "wall.toml:12: [tracking]: key 'beta': a one-euro filter setting, but filter is \"none\""},
        {grid + tracked + "filter = \"one_euro\"\nmin_cutoff = 0\n", "wall.toml:13: [tracking]: key 'min_cutoff': 0 is out of range"},
        {grid + tracked + "head = 1\n", "wall.toml:12: [tracking]: unknown key 'head'"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\nlower_left = [0, 0, 0]\n",
         "wall.toml:6: [[screen]] #1: give all three physical corners (lower_left, lower_right, upper_left; metres) or none"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\nlower_left = [0, 0, 0]\n"
         "lower_right = [1, 0, 0]\nupper_left = [1, 1, 0]\n",
         "wall.toml:8: [[screen]] #1: lower_left->lower_right and lower_left->upper_left must be at right angles"},
        {"[wall]\nwidth = 100\nheight = 100\n[[screen]]\nname = \"a\"\nviewport = [0, 0, 50, 100]\nlower_left = [0, 0, 0]\n"
         "lower_right = [1, 0, 0]\nupper_left = [0, 1, 0]\n[[screen]]\nname = \"b\"\nviewport = [50, 0, 50, 100]\n",
         "screen 'b': give the physical corners (lower_left, lower_right, upper_left) on every screen or on none"},
        {"[wall]\nwidth = 200\nheight = 600\n[grid]\ncolumns = 2\nrows = 1\nscreen_width = 800\nscreen_height = 600\n",
         "wall.toml:2: [wall]: key 'width': 200 differs from the grid's 1600"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.text);
        const std::string e = wallError(c.text);
        EXPECT_NE(e.find(c.expected), std::string::npos) << "got: " << e << "\nexpected: " << c.expected;
        EXPECT_EQ(e.find('\n'), std::string::npos) << "one line";
    }
}

TEST(WallConfig, TheTrackedStereoWallListensForDTrack) {
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/tracked-stereo-2x2.toml");
    const TrackingConfig& t = w.tracking;
    EXPECT_TRUE(t.enabled);
    EXPECT_EQ(t.address, "0.0.0.0");
    EXPECT_EQ(t.port, 5000);
    EXPECT_EQ(t.headBody, 0);
    EXPECT_EQ(t.flystick, 0);
    EXPECT_DOUBLE_EQ(t.roomScale, 0.001);
    EXPECT_EQ(t.roomRotate, (std::array<double, 3>{-90, 0, 0}));
    EXPECT_EQ(t.roomTranslate, (std::array<double, 3>{0, -1.5, 2.5}));
    EXPECT_EQ(t.filter, TrackingFilter::OneEuro);
    EXPECT_EQ(w.stereo.mode, StereoMode::Passive);
    EXPECT_EQ(w.screens.size(), 8u);
    // Without [tracking] nothing listens.
    EXPECT_FALSE(loadWallConfig(test::sourceDir() / "configs/wall/stereo-passive.toml").tracking.enabled);
    // A mono wall is tracked with its corners in [stereo] mode "none", and written back with them.
    const std::string mono = "[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\n[stereo]\nmode = \"none\"\n"
                             "lower_left = [-1, -1, 0]\nlower_right = [1, -1, 0]\nupper_left = [-1, 1, 0]\n[tracking]\n"
                             "source = \"dtrack://127.0.0.1:5123\"\nprediction_ms = 20\n";
    const WallConfig m = parseWallConfig(mono, "mono.toml");
    EXPECT_EQ(m.tracking.address, "127.0.0.1");
    EXPECT_EQ(m.tracking.port, 5123);
    EXPECT_DOUBLE_EQ(m.tracking.predictionMs, 20);
    EXPECT_EQ(parseWallConfig(writeWallConfig(m), "again.toml"), m);
}

TEST(WallConfig, RtwallCheckReportsATrackingMistake) {
    const std::filesystem::path file = std::filesystem::temp_directory_path() / "rtwall_bad_tracking.toml";
    std::ofstream(file) << "[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\n[stereo]\n"
                           "lower_left = [-1, -1, 0]\nlower_right = [1, -1, 0]\nupper_left = [-1, 1, 0]\n[tracking]\ntimeout_ms = 1.5\n";
    try {
        checkWall(file);
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("rtwall_bad_tracking.toml:11: [tracking]: key 'timeout_ms': expected an integer"), std::string::npos)
            << e.what();
    }
    std::filesystem::remove(file);
}

TEST(WallConfig, MissingFileIsAnInputError) {
    EXPECT_THROW(loadWallConfig(test::sourceDir() / "configs/wall/none.toml"), InputError);
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// GLX_NV_swap_group (issue 19): off by default, read strictly, a barrier only with a group, and
// written back.
TEST(WallConfig, SwapGroupAndBarrierAreReadStrictly) {
    const std::string screen = "[[screen]]\nviewport = [0, 0, 100, 100]\n";
    const WallConfig plain = parseWallConfig("[wall]\nwidth = 100\nheight = 100\n" + screen, "wall.toml");
    EXPECT_EQ(plain.swapGroup, 0);
    EXPECT_EQ(plain.swapBarrier, 0);
    const WallConfig grouped =
        parseWallConfig("[wall]\nwidth = 100\nheight = 100\nswap_group = 1\nswap_barrier = 2\n" + screen, "wall.toml");
    EXPECT_EQ(grouped.swapGroup, 1);
    EXPECT_EQ(grouped.swapBarrier, 2);
    EXPECT_EQ(parseWallConfig(writeWallConfig(grouped), "written.toml"), grouped);
    EXPECT_FALSE(parseWallConfig(writeWallConfig(grouped), "written.toml") == plain);
    EXPECT_EQ(test::wallError("[wall]\nwidth = 100\nheight = 100\nswap_barrier = 1\n" + screen),
              "wall.toml:4: [wall]: key 'swap_barrier': needs swap_group (a barrier binds a swap group)");
    EXPECT_EQ(test::wallError("[wall]\nwidth = 100\nheight = 100\nswap_group = -1\n" + screen),
              "wall.toml:4: [wall]: key 'swap_group': -1 is out of range [0, 1048576]");
    EXPECT_NE(test::wallError("[wall]\nwidth = 100\nheight = 100\nswap_group = true\n" + screen)
                  .find("wall.toml:4: [wall]: key 'swap_group': expected an integer"),
              std::string::npos);
    EXPECT_NE(test::wallError("[wall]\nwidth = 100\nheight = 100\nswap_groups = 1\n" + screen).find("wall.toml:4: [wall]: unknown key 'swap_groups'"),
              std::string::npos);
}

// Issue 27: the room's scale in the scene, read strictly and written back.
TEST(WallConfig, NavigationScaleIsReadStrictlyAndWrittenBack) {
    const std::string wall = "[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\n";
    const WallConfig plain = parseWallConfig(wall, "wall.toml");
    EXPECT_EQ(plain.navigation.scale, 1.0) << "1 metre is 1 scene unit unless said";
    EXPECT_EQ(writeWallConfig(plain).find("[navigation]"), std::string::npos) << "the default is not written";
    const WallConfig scaled = parseWallConfig(wall + "[navigation]\nscale = 2.5\n", "wall.toml");
    EXPECT_EQ(scaled.navigation.scale, 2.5);
    EXPECT_FALSE(scaled == plain);
    const std::string text = writeWallConfig(scaled);
    EXPECT_NE(text.find("[navigation]\nscale = 2.5\n"), std::string::npos) << text;
    EXPECT_EQ(parseWallConfig(text, "written.toml"), scaled);
    EXPECT_EQ(parseWallConfig(wall + "[navigation]\nscale = 1000\n", "wall.toml").navigation.scale, 1000.0) << "an integer is a number";
    // Zero, negative, not a number, infinite, the wrong type, an unknown key: one line each.
    const std::vector<std::pair<std::string, std::string>> bad = {
        {"scale = 0", "wall.toml:7: [navigation]: key 'scale': 0 is out of range [1e-06, 1e+06]"},
        {"scale = -2.5", "wall.toml:7: [navigation]: key 'scale': -2.5 is out of range [1e-06, 1e+06]"},
        {"scale = nan", "wall.toml:7: [navigation]: key 'scale': value must be finite"},
        {"scale = inf", "wall.toml:7: [navigation]: key 'scale': value must be finite"},
        {"scale = \"2\"", "wall.toml:7: [navigation]: key 'scale': expected a number, got a string"},
        {"scale = [1, 2]", "wall.toml:7: [navigation]: key 'scale': expected a number, got an array"},
        {"scael = 2", "wall.toml:7: [navigation]: unknown key 'scael'"},
    };
    for (const auto& [line, want] : bad) EXPECT_EQ(wallError(wall + "[navigation]\n" + line + "\n"), want) << line;
    EXPECT_NE(wallError("navigation = 2\n" + wall).find("wall.toml:1: 'navigation' must be a table"), std::string::npos)
        << wallError("navigation = 2\n" + wall);
}

}  // namespace
}  // namespace rtwall
