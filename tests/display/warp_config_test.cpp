// [warp] in wall configs (issue 30): the MPCDI file and the screen each buffer drives, read with
// the config, checked against the file by checkWall (what `rtwall check` prints), one line per
// problem and every problem at once. Files from tools/mpcdi_testgen.py (the curved example).
#include "scratch.h"

#include <rtwall/display.h>
#include <rtwall/input_error.h>
#include <rtwall/mpcdi.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <regex>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

// The cylinder calibration and its wall config in `dir`; `extra`: testgen options.
fs::path cylinderWall(const fs::path& dir, const std::string& extra = "") {
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 32x24 --wall " + (dir / "c.toml").string() + " " + extra);
    return dir / "c.toml";
}

std::string text(const fs::path& f) {
    std::ifstream in(f);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// The config with `from` replaced by `to` (regex), written beside it as `name`.
fs::path edited(const fs::path& config, const std::string& from, const std::string& to, const std::string& name) {
    const std::string t = text(config), e = std::regex_replace(t, std::regex(from), to);
    EXPECT_NE(t, e) << "the edit " << from << " changed nothing";
    return test::writeFile(config.parent_path() / name, e);
}

std::string loadError(const fs::path& config) {
    try {
        loadWallConfig(config);
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

TEST(WarpConfig, TheCurvedWallReadsChecksCleanAndWritesBack) {
    const fs::path dir = test::scratchDir();
    const WallConfig w = loadWallConfig(cylinderWall(dir));
    ASSERT_TRUE(w.warp.has_value());
    EXPECT_EQ(w.warp->mpcdi, dir / "c.mpcdi") << "relative to the config";
    EXPECT_EQ(w.warp->mode, WarpMode::Direct);
    const std::vector<std::pair<std::string, std::string>> mapped{{"proj0", "proj0"}, {"proj1", "proj1"}, {"proj2", "proj2"}};
    EXPECT_EQ(w.warp->buffers, mapped);
    EXPECT_EQ(checkWarp(w), std::vector<std::string>{});
    EXPECT_EQ(checkWall(w), std::vector<std::string>{});
    const WallConfig again = parseWallConfig(writeWallConfig(w), dir / "again.toml");
    EXPECT_TRUE(again == w);
    WallConfig post = w;
    post.warp->mode = WarpMode::Post;
    EXPECT_FALSE(post == w);
    EXPECT_TRUE(parseWallConfig(writeWallConfig(post), dir / "post.toml") == post);
    // A chord frames its projector's part of the cylinder: each screen's frame is its corners.
    const EyeWindow f = screenFrame(w, 1);
    EXPECT_EQ(f.lowerLeft, w.screens[1].lowerLeft);
    EXPECT_EQ(f.right, w.screens[1].lowerRight - w.screens[1].lowerLeft);
}

TEST(WarpConfig, MillimetresAreMetresTooButAWrongUnitIsNamed) {
    const fs::path mm = test::scratchDir() / "mm", wrong = test::scratchDir() / "wrong";
    fs::create_directories(mm);
    fs::create_directories(wrong);
    EXPECT_EQ(checkWarp(loadWallConfig(cylinderWall(mm, "--unit mm"))), std::vector<std::string>{});
    const std::vector<std::string> p = checkWarp(loadWallConfig(cylinderWall(wrong, "--unit mm --declare m")));
    ASSERT_EQ(p.size(), 3u) << "one line per projector";
    for (const std::string& line : p) {
        EXPECT_TRUE(std::regex_search(line, std::regex(" ([0-9]+) of \\1 warp samples lie outside the screen's frame"))) << line;
        EXPECT_NE(line.find("far off its plane); is the geometric unit right?"), std::string::npos) << line;
    }
}

TEST(WarpConfig, ConfigMistakesAreOneLineWithFileLineAndKey) {
    const fs::path dir = test::scratchDir();
    const fs::path c = cylinderWall(dir);
    auto error = [&](const std::string& from, const std::string& to) {
        return loadError(edited(c, from, to, "e.toml"));
    };
    EXPECT_EQ(error("proj2 = \"proj2\"", "proj2 = \"nowhere\""),
              (dir / "e.toml").string() + ":42: [warp]: key 'buffers': buffer 'proj2' names screen 'nowhere', which the wall has not");
    EXPECT_EQ(error("proj2 = \"proj2\"", "proj2 = \"proj1\""),
              (dir / "e.toml").string() + ":42: [warp]: key 'buffers': screen 'proj1' is driven by two buffers");
    EXPECT_EQ(error("proj2 = \"proj2\"", "proj2 = 3"),
              (dir / "e.toml").string() + ":42: [warp]: key 'buffers': buffer 'proj2' must name a screen (a string)");
    EXPECT_EQ(error("buffers = \\{.*\\}", "buffers = {}"), (dir / "e.toml").string() + ":42: [warp]: key 'buffers': no buffer is mapped");
    EXPECT_EQ(error("buffers = \\{.*\\}", "buffers = 1"),
              (dir / "e.toml").string() + ":42: [warp]: key 'buffers': a table of buffer id = \"screen name\", e.g. { proj0 = \"left\" }");
    EXPECT_NE(error("buffers = \\{.*\\}", "").find("[warp]: missing required key 'buffers'"), std::string::npos);
    EXPECT_NE(error("mpcdi = \"c.mpcdi\"", "").find("[warp]: missing required key 'mpcdi'"), std::string::npos);
    EXPECT_EQ(error("mpcdi = \"c.mpcdi\"", "mpcdi = \"\""), (dir / "e.toml").string() + ":41: [warp]: key 'mpcdi': an empty path");
    EXPECT_NE(error("mpcdi = \"c.mpcdi\"", "mpcdi = \"c.mpcdi\"\nmode = \"bent\"").find("key 'mode': 'bent' is not one of direct, post"),
              std::string::npos);
    EXPECT_NE(error("mpcdi = \"c.mpcdi\"", "mpcdi = \"c.mpcdi\"\nwarp_it = true").find("warp_it"), std::string::npos);
}

// Several faults at once: every one is a line of its own.
TEST(WarpConfig, CheckNamesEveryMismatchBetweenFileAndWall) {
    const fs::path dir = test::scratchDir();
    const fs::path c = cylinderWall(dir);
    const fs::path several =
        edited(edited(c, "proj2 = \"proj2\"", "proj3 = \"proj2\"", "a.toml"), "viewport = \\[32, 0, 32, 24\\]",
               "viewport = [32, 0, 32, 24]\nresolution = [16, 12]", "several.toml");
    const std::vector<std::string> p = checkWall(several);
    const std::string at = several.string() + ": [warp]: ";
    const std::vector<std::string> expected{
        at + "buffer 'proj2' of c.mpcdi drives no screen (map it in 'buffers')",
        at + "buffer 'proj1' (screen 'proj1'): 32x24 pixels, the screen has 16x12",
        at + "buffer 'proj3' is not in c.mpcdi (it has proj0, proj1, proj2)",
    };
    EXPECT_EQ(p, expected);
    // A frame that does not hold the surface: the middle screen's lower edge half a metre up.
    const fs::path up = edited(c, "(lower_(left|right) = \\[-?1.13[0-9]*, )-1.2,", "$1-0.7,", "up.toml");
    const std::vector<std::string> frame = checkWall(up);
    ASSERT_EQ(frame.size(), 1u);
    EXPECT_EQ(frame[0].rfind(up.string() + ": [warp]: buffer 'proj1' (screen 'proj1'): region 'proj1_region': ", 0), 0u) << frame[0];
    EXPECT_NE(frame[0].find("warp samples lie outside the screen's frame, first sample ("), std::string::npos) << frame[0];
    // An unreadable calibration: one line, the config's name and the file's problem.
    fs::remove(dir / "c.mpcdi");
    const std::vector<std::string> gone = checkWall(c);
    ASSERT_EQ(gone.size(), 1u);
    EXPECT_EQ(gone[0], c.string() + ": [warp]: " + (dir / "c.mpcdi").string() +
                           ": cannot read it (No such file or directory)");
}

// The expected ray of frustum coordinates (u, v), derived apart from the reader's matrices: the
// frustum's axis, right and up vectors from the meaning of yaw (a turn right about the room's
// up), pitch (up) and roll (the right side down), then the image plane spanned by the angles.
Float3 expectedDirection(const MpcdiFrustum& f, double u, double v) {
    const double k = 3.14159265358979323846 / 180, y = f.yaw * k, p = f.pitch * k, r = f.roll * k;
    const double forward[3] = {std::sin(y) * std::cos(p), std::sin(p), -std::cos(y) * std::cos(p)};
    const double right0[3] = {std::cos(y), 0, std::sin(y)};
    const double up0[3] = {-std::sin(y) * std::sin(p), std::cos(p), std::cos(y) * std::sin(p)};
    const double tx = std::tan(f.leftAngle * k) + u * (std::tan(f.rightAngle * k) - std::tan(f.leftAngle * k));
    const double ty = std::tan(f.downAngle * k) + v * (std::tan(f.upAngle * k) - std::tan(f.downAngle * k));
    double d[3];
    for (int i = 0; i < 3; ++i) {
        const double right = right0[i] * std::cos(r) - up0[i] * std::sin(r), up = right0[i] * std::sin(r) + up0[i] * std::cos(r);
        d[i] = forward[i] + tx * right + ty * up;
    }
    return {float(d[0]), float(d[1]), float(d[2])};
}

// A 3D-simulation (`3d`) file: the cylinder's projector pixels as coordinates in each
// projector's frustum (yawed, pitched and rolled) from the viewer. Its points lie at the frustum
// distance along each pixel's frustum direction from the eye point (the config's viewer, or
// `eyepoint`), the direction derived apart; checked clean; and the directions from the eye point
// are the a3 file's to the cylinder's surface (the same pixels, written two ways).
TEST(WarpConfig, The3dSimulationProfileTracesEachPixelAlongItsFrustumDirection) {
    const fs::path dir = test::scratchDir();
    const fs::path c = cylinderWall(dir, "--profile 3d");
    const WallConfig w = loadWallConfig(c);
    EXPECT_TRUE(checkWarp(w).empty());
    const MpcdiFile f = readMpcdi(w.warp->mpcdi);
    ASSERT_EQ(f.profile, MpcdiProfile::Simulation3d);
    const Float3 eye = w.stereo.viewer;
    const std::vector<WallWarp> warps = wallWarps(w, f);
    ASSERT_EQ(warps.size(), 3u);
    const fs::path a3dir = dir / "a3";
    fs::create_directories(a3dir);
    const WallConfig a3 = loadWallConfig(cylinderWall(a3dir));
    const std::vector<WallWarp> surface = wallWarps(a3, readMpcdi(a3.warp->mpcdi));
    double worstAngle = 0, worstToSurface = 0;
    size_t valid = 0;
    for (size_t k = 0; k < 3; ++k) {
        const MpcdiRegion& r = f.buffers[k].regions.at(0);
        ASSERT_TRUE(r.frustum);
        EXPECT_NE(r.frustum->pitch, 0.0);
        EXPECT_NE(r.frustum->roll, 0.0);
        const PixelWarp& g = *warps[k].regions.at(0).warp;
        EXPECT_EQ(g.kind, PixelWarp::Kind::SurfacePoints);
        for (size_t i = 0; i < g.samples.size(); ++i) {
            const Float3 uv = r.warp.samples[i], p = g.samples[i];
            if (std::isnan(uv.x)) {
                EXPECT_TRUE(std::isnan(p.x));
                continue;
            }
            ++valid;
            const Float3 want = expectedDirection(*r.frustum, uv.x, uv.y);
            const Float3 got = p - eye;
            // 10 m along the axis: the axis is the direction's unit component along it.
            EXPECT_NEAR(length(got) / length(want), 10.0, 1e-3) << i;
            worstAngle = std::max(worstAngle, double(length(cross(normalize(got), normalize(want)))));
            const Float3 toSurface = surface[k].regions.at(0).warp->samples[i] - eye;
            worstToSurface = std::max(worstToSurface, double(length(cross(normalize(got), normalize(toSurface)))));
        }
    }
    EXPECT_GT(valid, 3u * 32 * 24 / 2);
    EXPECT_LT(worstAngle, 2e-6) << "radians";
    EXPECT_LT(worstToSurface, 2e-6) << "radians";
    // The eye point and distance from [warp]: the points move with them.
    const WallConfig moved = loadWallConfig(edited(c, "\\[warp\\]\n", "[warp]\neyepoint = [0.5, 0.25, 3]\nfrustum_distance = 4\n", "m.toml"));
    const MpcdiRegion& r0 = f.buffers[0].regions[0];
    const std::vector<WallWarp> mw = wallWarps(moved, f);
    for (size_t i = 0; i < r0.warp.samples.size(); ++i) {
        if (std::isnan(r0.warp.samples[i].x)) continue;
        const Float3 d = mw[0].regions[0].warp->samples[i] - Float3{0.5f, 0.25f, 3.0f};
        ASSERT_NEAR(length(d) / length(expectedDirection(*r0.frustum, r0.warp.samples[i].x, r0.warp.samples[i].y)), 4.0, 1e-3);
    }
    // An eye point that puts the frusta's rays off the screens: named per buffer.
    const std::vector<std::string> off = checkWarp(loadWallConfig(edited(c, "\\[warp\\]\n", "[warp]\neyepoint = [0, 0, -8]\n", "o.toml")));
    ASSERT_EQ(off.size(), 3u);
    EXPECT_NE(off[0].find("are the eye point and the frustum right?"), std::string::npos) << off[0];
    EXPECT_TRUE(checkWarp(loadWallConfig(cylinderWall(dir, "--profile sl"))).empty());
}

// A region of part of its buffer: its y counts from the buffer's top (default, nDisplay's
// reading) or, with region_y = "bottom", from its bottom (SGCT's); its warp's rectangle and its
// blend map move accordingly, x alike either way.
TEST(WarpConfig, RegionYCountsFromTheTopOrTheBottom) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("identity " + (dir / "id.mpcdi").string() + " --buffer a=40x30");
    MpcdiFile f = readMpcdi(dir / "id.mpcdi");
    MpcdiRegion& r = f.buffers[0].regions.at(0);
    r.x = 0.25;
    r.xSize = 0.5;
    r.y = 0.2;
    r.ySize = 0.4;
    r.xResolution = 20;
    r.yResolution = 12;
    r.alpha = MpcdiMap{.width = 20, .height = 12, .components = 1, .values = std::vector<float>(20 * 12, 0.5f), .gammaEmbedded = 1};
    for (const bool bottom : {false, true}) {
        SCOPED_TRACE(bottom ? "from the bottom" : "from the top");
        const WallConfig w = parseWallConfig(std::string("[wall]\nwidth = 40\nheight = 30\n[[screen]]\nname = \"A\"\nviewport = [0, 0, 40, 30]\n") +
                                                 "[warp]\nmpcdi = \"id.mpcdi\"\nbuffers = { a = \"A\" }\n" + (bottom ? "region_y = \"bottom\"\n" : ""),
                                             dir / "w.toml");
        EXPECT_EQ(w.warp->regionYFromBottom, bottom);
        const std::vector<WallWarp> warps = wallWarps(w, f);
        ASSERT_EQ(warps.size(), 1u);
        // Rows 6..17 from the top (0.2 of 30 pixels down), or 12..23 (0.2 up from the bottom).
        const int top = bottom ? 12 : 6;
        EXPECT_EQ(warps[0].regions.at(0).rect, (TileRect{10, top, 30, top + 12}));
        const ProjectorBlendStage blend(w, f);
        Image white;
        white.width = 40;
        white.height = 30;
        white.rgb.assign(40 * 30 * 3, 255);
        blend.apply(w, 0, 0, white);
        for (int y = 0; y < 30; ++y)
            for (int x = 0; x < 40; ++x) {
                const bool inside = x >= 10 && x < 30 && y >= top && y < top + 12;
                ASSERT_EQ(white.pixel(x, y)[0] != 255, inside) << x << "," << y;
            }
    }
}

// The views' warps from the file: a 2D identity is exactly no offset, a whole-pixel shift
// exactly that shift (in wall pixels, through a screen scaled 2x), 3D points in metres over
// each screen's viewport.
TEST(WarpConfig, WallWarpsFromTheFile) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("identity " + (dir / "id.mpcdi").string() + " --buffer a=40x30 --buffer b=20x15");
    test::mpcdiTestgen("identity " + (dir / "shift.mpcdi").string() + " --buffer a=40x30 --buffer b=20x15 --shift 3,-2");
    auto wall = [&](const std::string& mpcdi) {
        return parseWallConfig("[wall]\nwidth = 80\nheight = 30\n[[screen]]\nname = \"A\"\nviewport = [0, 0, 40, 30]\n"
                               "[[screen]]\nname = \"B\"\nviewport = [40, 0, 40, 30]\nresolution = [20, 15]\n"
                               "[warp]\nmpcdi = \"" + mpcdi + "\"\nbuffers = { a = \"A\", b = \"B\" }\n",
                               dir / "w.toml");
    };
    for (const bool shifted : {false, true}) {
        SCOPED_TRACE(shifted ? "shifted" : "identity");
        const WallConfig w = wall(shifted ? "shift.mpcdi" : "id.mpcdi");
        // Shifted, the edge rows and columns look past the screen's frame: named, one line a buffer.
        EXPECT_EQ(checkWarp(w).size(), shifted ? 2u : 0u);
        const std::vector<WallWarp> warps = wallWarps(w, readMpcdi(w.warp->mpcdi));
        ASSERT_EQ(warps.size(), 2u);
        for (const WallWarp& ww : warps) {
            ASSERT_EQ(ww.regions.size(), 1u);
            const ScreenWarp& sw = ww.regions[0];
            const PixelRect& vp = w.screens[ww.screen].viewport;
            EXPECT_EQ(sw.rect, (TileRect{vp.x, vp.y, vp.x + vp.width, vp.y + vp.height}));
            ASSERT_TRUE(sw.warp);
            EXPECT_EQ(sw.warp->kind, PixelWarp::Kind::ScreenOffsets);
            // Screen B's buffer is 20x15 over 40x30 wall pixels: a buffer pixel is two wall pixels.
            const float scale = ww.screen == 1 ? 2.0f : 1.0f;
            const Float3 want = shifted ? Float3{3 * scale, -2 * scale, 0} : Float3{0, 0, 0};
            for (const Float3& o : sw.warp->samples) ASSERT_EQ(o, want);
        }
    }
    const fs::path c = cylinderWall(dir, "--unit mm");
    const WallConfig w = loadWallConfig(c);
    const std::vector<WallWarp> warps = wallWarps(w, readMpcdi(w.warp->mpcdi));
    ASSERT_EQ(warps.size(), 3u);
    const MpcdiFile f = readMpcdi(w.warp->mpcdi);
    for (size_t k = 0; k < 3; ++k) {
        const ScreenWarp& sw = warps[k].regions.at(0);
        EXPECT_EQ(warps[k].screen, k);
        EXPECT_EQ(sw.rect, (TileRect{int(32 * k), 0, int(32 * k) + 32, 24}));
        EXPECT_EQ(sw.warp->kind, PixelWarp::Kind::SurfacePoints);
        const std::vector<Float3>& mm = f.buffers[k].regions[0].warp.samples;
        ASSERT_EQ(sw.warp->samples.size(), mm.size());
        for (size_t i = 0; i < mm.size(); ++i) {
            if (std::isnan(mm[i].x)) {
                EXPECT_TRUE(std::isnan(sw.warp->samples[i].x));
                continue;
            }
            EXPECT_EQ(sw.warp->samples[i], mm[i] * 0.001f);
        }
    }
}

}  // namespace
}  // namespace rtwall
