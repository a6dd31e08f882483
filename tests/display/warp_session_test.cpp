// A calibrated wall end to end in one process (issue 30; loopback, client threads): the clients
// get the warp grids once and trace every projector pixel's ray through its calibration. An
// identity calibration is today's flat wall bit for bit, a whole-pixel shift shifts the image
// exactly, and the curved three-projector wall is the same bytes on one, two and three clients.
#include "common/files.h"
#include "session_tracker.h"
#include "display_test_util.h"
#include "test_util.h"

#include <rtwall/mpcdi.h>
#include <rtwall/tracking.h>
#include <rtwall/wall.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <chrono>
#include <cstring>
#include <map>
#include <thread>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

const std::string kScene = test::sceneText("tracked_boxes");

// Two screens side by side on one plane (one view), 200x150 wall pixels each, 8 mm a pixel;
// `warp`: the [warp] table, if any.
std::string twoScreens(const std::string& warp) {
    return R"([wall]
width = 400
height = 150
vsync = false
[stereo]
viewer = [0.0, 0.0, 2.0]
lower_left = [-1.6, -0.6, 0.0]
lower_right = [1.6, -0.6, 0.0]
upper_left = [-1.6, 0.6, 0.0]
[[screen]]
name = "A"
viewport = [0, 0, 200, 150]
lower_left = [-1.6, -0.6, 0.0]
lower_right = [0.0, -0.6, 0.0]
upper_left = [-1.6, 0.6, 0.0]
[[screen]]
name = "B"
viewport = [200, 0, 200, 150]
lower_left = [0.0, -0.6, 0.0]
lower_right = [1.6, -0.6, 0.0]
upper_left = [0.0, 0.6, 0.0]
[headless]
write_every = 0
)" + warp;
}


// The first frame of `wallFile` on `clients` client threads.
Image render(const fs::path& dir, const fs::path& wallFile, int clients, std::vector<std::string>* log = nullptr) {
    RunConfig c = steppedRunConfig(dir, clients);
    c.scene = test::writeFile(dir / "scene.toml", kScene).string();
    c.wall = wallFile;
    c.cluster.async = false;
    if (log) c.log = [log](const std::string& line) { log->push_back(line); };
    WallSession s(c);
    EXPECT_TRUE(s.step());
    return s.lastFrame().left;
}

TEST(WarpSession, AnIdentityCalibrationIsTheFlatWallBitForBitOnOneTwoAndThreeClients) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("identity " + (dir / "id.mpcdi").string() + " --buffer a=200x150 --buffer b=200x150");
    const fs::path flat = test::writeFile(dir / "flat.toml", twoScreens(""));
    const fs::path warped =
        test::writeFile(dir / "warped.toml", twoScreens("[warp]\nmpcdi = \"id.mpcdi\"\nbuffers = { a = \"A\", b = \"B\" }\n"));
    const Image want = render(dir, flat, 2);
    ASSERT_EQ(want.width, 400);
    ASSERT_NE(std::count(want.rgb.begin(), want.rgb.end(), want.rgb[0]), std::ptrdiff_t(want.rgb.size())) << "a blank image";
    for (int clients : {1, 2, 3}) {
        std::vector<std::string> log;
        EXPECT_EQ(render(dir, warped, clients, &log).rgb, want.rgb) << clients << " clients";
        EXPECT_TRUE(test::logged(log, "warp: id.mpcdi, 2 projector regions on 2 screens, rays through each projector pixel (2d profile)"));
    }
}

// Pixel (x, y) of a calibration shifted by (3, -2) wall pixels looks where the flat wall's
// pixel (x + 3, y - 2) looks: the same bytes there, everywhere.
TEST(WarpSession, AWholePixelShiftShiftsTheImageExactly) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("identity " + (dir / "s.mpcdi").string() + " --buffer a=200x150 --buffer b=200x150 --shift 3,-2");
    const Image flat = render(dir, test::writeFile(dir / "flat.toml", twoScreens("")), 2);
    const Image shifted = render(
        dir, test::writeFile(dir / "s.toml", twoScreens("[warp]\nmpcdi = \"s.mpcdi\"\nbuffers = { a = \"A\", b = \"B\" }\n")), 3);
    ASSERT_EQ(shifted.width, flat.width);
    size_t differ = 0, compared = 0;
    for (int y = 2; y < 150; ++y)
        for (int x = 0; x + 3 < 400; ++x) {
            differ += std::memcmp(shifted.pixel(x, y), flat.pixel(x + 3, y - 2), 3) != 0;
            ++compared;
        }
    EXPECT_EQ(differ, 0u) << "of " << compared;
    EXPECT_NE(shifted.rgb, flat.rgb);
}

// The pixels of two images that differ (any channel).
size_t differing(const Image& a, const Image& b) {
    size_t n = 0;
    for (size_t i = 0; i + 2 < a.rgb.size() && i + 2 < b.rgb.size(); i += 3) n += std::memcmp(&a.rgb[i], &b.rgb[i], 3) != 0;
    return n;
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

// The curved example: every projector pixel's ray through its surface point, the same bytes on
// one, two and three clients, black where the calibration says the pixel lands on no screen
// (the corners of each projector's bent image), and not the flat wall's picture.
TEST(WarpSession, TheCurvedWallIsTheSameOnOneTwoAndThreeClientsAndOffScreenPixelsAreBlack) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
    const Image one = render(dir, dir / "c.toml", 1);
    ASSERT_EQ(one.width, 192);
    EXPECT_EQ(render(dir, dir / "c.toml", 2).rgb, one.rgb);
    EXPECT_EQ(render(dir, dir / "c.toml", 3).rgb, one.rgb);
    const MpcdiFile file = readMpcdi(dir / "c.mpcdi");
    size_t offScreen = 0;
    for (size_t p = 0; p < 3; ++p) {
        const MpcdiWarp& w = file.buffers[p].regions[0].warp;
        ASSERT_EQ(w.width, 64);  // one sample per projector pixel
        for (int y = 0; y < 48; ++y)
            for (int x = 0; x < 64; ++x) {
                const Float3 s = w.samples[size_t(y) * 64 + size_t(x)];
                const uint8_t* px = one.pixel(int(p) * 64 + x, y);
                if (std::isnan(s.x)) {
                    ++offScreen;
                    EXPECT_EQ(px[0] + px[1] + px[2], 0) << "projector " << p << " pixel " << x << "," << y;
                }
            }
    }
    EXPECT_GT(offScreen, 0u);
    // Without its calibration the same wall shows flat projector images.
    std::string text = test::fileBytes(dir / "c.toml");
    text.erase(text.find("\n[warp]\n"));
    EXPECT_NE(render(dir, test::writeFile(dir / "flat.toml", text), 2).rgb, one.rgb);
}

// Stereo through a calibration: each eye's rays go from that eye through the same surface
// points, so each eye's image is the mono wall's seen from a viewer at that eye (the room put
// in the world the same way: the mono camera moved by the eye's offset), to the bit.
TEST(WarpSession, EachEyeOfAStereoWallSeesThroughTheCalibrationFromItself) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
    const std::string mono = test::fileBytes(dir / "c.toml");
    const fs::path stereoFile =
        test::writeFile(dir / "stereo.toml", replaced(mono, "mode = \"none\"", "mode = \"quad_buffer\"\neye_separation = 0.2"));
    RunConfig c = steppedRunConfig(dir, 2);
    c.scene = test::writeFile(dir / "scene.toml", kScene).string();
    c.cluster.async = false;
    c.wall = stereoFile;
    WallFrame stereo;
    CameraDesc camera;
    {
        WallSession s(c);
        ASSERT_TRUE(s.step());
        stereo = s.lastFrame();
        camera = s.camera();
    }
    ASSERT_EQ(stereo.right.width, stereo.left.width);
    EXPECT_GT(differing(stereo.left, stereo.right), stereo.left.rgb.size() / 3 / 50) << "the eyes see alike";
    // The camera's right: the wall's x axis in the world.
    const Float3 right = normalize(cross(camera.lookAt - camera.position, camera.up));
    for (const float eye : {-0.1f, 0.1f}) {
        SCOPED_TRACE(eye < 0 ? "left eye" : "right eye");
        char viewer[64];
        std::snprintf(viewer, sizeof viewer, "viewer = [%g, 0.0, 3]", double(eye));
        c.wall = test::writeFile(dir / "eye.toml", replaced(mono, "viewer = [0.0, 0.0, 3]", viewer));
        WallSession s(c);
        CameraDesc moved = camera;
        moved.position = camera.position + right * eye;
        moved.lookAt = camera.lookAt + right * eye;
        s.setCamera(moved);
        ASSERT_TRUE(s.step());
        const Image& want = eye < 0 ? stereo.left : stereo.right;
        const size_t pixels = want.rgb.size() / 3, off = differing(s.lastFrame().left, want);
        EXPECT_EQ(off, 0u) << off << " of " << pixels << " pixels differ";
    }
}

// Profile 3d (3D simulation): the same projector pixels written as directions in each
// projector's frustum from the viewer. From that eye point the rays are the a3 file's to the
// cylinder's surface up to rounding (the directions are computed two ways), the same bytes on
// one, two and three clients. From another eye the two differ: the 3d file's rays are fixed
// on the frustum distance's plane (10 m), the a3 file's on the screen itself.
TEST(WarpSession, The3dProfileSeesFromItsEyePointWhatTheSurfacePointsShow) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c3.mpcdi").string() + " --res 64x48 --profile 3d --wall " + (dir / "c3.toml").string());
    test::mpcdiTestgen("cylinder " + (dir / "ca.mpcdi").string() + " --res 64x48 --wall " + (dir / "ca.toml").string());
    std::vector<std::string> log;
    const Image sim = render(dir, dir / "c3.toml", 1, &log);
    EXPECT_TRUE(test::logged(log, "warp: c3.mpcdi, 3 projector regions on 3 screens, rays through each projector pixel (3d profile)"));
    EXPECT_EQ(render(dir, dir / "c3.toml", 2).rgb, sim.rgb);
    EXPECT_EQ(render(dir, dir / "c3.toml", 3).rgb, sim.rgb);
    const Image surface = render(dir, dir / "ca.toml", 2);
    const size_t pixels = sim.rgb.size() / 3, off = differing(sim, surface);
    EXPECT_LT(off, pixels / 200) << off << " of " << pixels << " pixels differ";  // edges a rounding apart
    const std::string moved = replaced(test::fileBytes(dir / "c3.toml"), "viewer = [0.0, 0.0, 3]", "viewer = [0.4, 0.0, 3]");
    const std::string movedSurface = replaced(test::fileBytes(dir / "ca.toml"), "viewer = [0.0, 0.0, 3]", "viewer = [0.4, 0.0, 3]");
    // The eye point stays where the calibration was made (the old viewer).
    const Image simMoved = render(dir, test::writeFile(dir / "m3.toml", replaced(moved, "[warp]\n", "[warp]\neyepoint = [0, 0, 3]\n")), 2);
    const Image surfaceMoved = render(dir, test::writeFile(dir / "ma.toml", movedSurface), 2);
    EXPECT_GT(differing(simMoved, surfaceMoved), pixels / 20) << "parallax: the frustum plane is not the screen";
}

// Head tracking through a calibration, from DTrack datagrams on loopback: the head's datagram
// moves the eye the rays leave from (datagram, parser, room transform, eye), so a head 0.25 m
// right of the viewer gives the bytes of the static wall whose viewer stands there (the room put
// in the world as for the stereo eyes above), and back at the viewer the untracked bytes.
TEST(WarpSession, ATrackedHeadMovesTheEyeOfTheCurvedWallsRays) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
    const std::string mono = test::fileBytes(dir / "c.toml");
    RunConfig c = steppedRunConfig(dir, 2);
    c.scene = test::writeFile(dir / "scene.toml", kScene).string();
    c.cluster.async = false;
    c.wall = dir / "c.toml";
    Image atViewer;
    CameraDesc camera;
    {
        WallSession s(c);
        ASSERT_TRUE(s.step());
        atViewer = s.lastFrame().left;
        camera = s.camera();
    }
    const Float3 right = normalize(cross(camera.lookAt - camera.position, camera.up));
    Image moved;
    {
        RunConfig m = c;
        m.wall = test::writeFile(dir / "moved.toml", replaced(mono, "viewer = [0.0, 0.0, 3]", "viewer = [0.25, 0.0, 3]"));
        WallSession s(m);
        CameraDesc shifted = camera;
        shifted.position = camera.position + right * 0.25f;
        shifted.lookAt = camera.lookAt + right * 0.25f;
        s.setCamera(shifted);
        ASSERT_TRUE(s.step());
        moved = s.lastFrame().left;
    }
    ASSERT_GT(differing(moved, atViewer), atViewer.rgb.size() / 3 / 50) << "the moved viewer sees alike";

    c.wall = test::writeFile(dir / "tracked.toml", mono + "[tracking]\nsource = \"dtrack://127.0.0.1:0\"\ntimeout_ms = 60000\n");
    WallSession tracked(c);
    ASSERT_GT(tracked.trackerPort(), 0);
    // Millimetres; the room is the wall's frame.
    auto sendHead = [&](double x, uint64_t frame) { test::sendHeadAt(tracked, x * 1e3, 0.0, 3e3, frame); };
    ASSERT_TRUE(tracked.step());
    EXPECT_EQ(differing(tracked.lastFrame().left, atViewer), 0u) << "before any datagram: the config's viewer";
    sendHead(0.25, 1);
    ASSERT_TRUE(tracked.step());
    EXPECT_EQ(tracked.lastHead().position.x, 0.25f);
    EXPECT_EQ(differing(tracked.lastFrame().left, moved), 0u) << "the head 0.25 m right";
    sendHead(0.0, 2);
    ASSERT_TRUE(tracked.step());
    EXPECT_EQ(differing(tracked.lastFrame().left, atViewer), 0u) << "the head back at the viewer";
}

// The post-warp on display nodes follows the tracked head: each frame tells the nodes the eyes
// its flat views were rendered from, and each node resamples its screens from them. A head
// 0.25 m right of the viewer (DTrack, before the first frame): the nodes' screens are the
// one-PC wall's at that head, to the bit, and not what the config's viewer would make of the
// same flat images.
TEST(WarpSession, PostWarpingDisplayNodesResampleFromTheTrackedEyes) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
    const std::string tracking = "[tracking]\nsource = \"dtrack://127.0.0.1:0\"\ntimeout_ms = 60000\n";
    WallConfig w = loadWallConfig(dir / "c.toml");
    w.warp->mode = WarpMode::Post;
    const std::string one = writeWallConfig(w) + tracking;
    for (ScreenConfig& sc : w.screens) sc.node = sc.name == "proj2" ? "b" : "a";
    const std::string nodes = writeWallConfig(w) + tracking;
    // Each run's screens of its last frame, once every screen was written twice (still head, still scene).
    auto run = [&](const std::string& name, const std::string& wallText, bool moved) {
        const fs::path out = dir / name;
        RunConfig c = steppedRunConfig(out, 2);
        c.scene = test::writeFile(dir / "scene.toml", kScene).string();
        c.wall = test::writeFile(dir / (name + ".toml"), wallText);
        c.cluster.async = false;
        c.writeEvery = 1;
        c.cluster.displayNodes.stallSeconds = 60;  // no node left out on a loaded machine
        WallSession s(c);
        if (moved) test::sendHeadAt(s, 250.0, 0.0, 3000.0, 1);
        std::map<std::string, fs::path> newest;  // screen -> its newest file
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        for (int i = 0; i < 3 || (newest.size() < 3 && std::chrono::steady_clock::now() < until); ++i) {
            EXPECT_TRUE(s.step());
            newest.clear();
            std::error_code ec;
            fs::create_directories(out, ec);
            for (const auto& e : fs::recursive_directory_iterator(out)) {
                const std::string file = e.path().filename().string();  // frame_NNNNNN_projK.png
                if (!e.is_regular_file() || file.size() != 22 || file.compare(0, 6, "frame_") != 0) continue;
                fs::path& n = newest[file.substr(13, 5)];
                if (n.empty() || file > n.filename().string()) n = e.path();
            }
        }
        std::map<std::string, std::vector<uint8_t>> last;
        for (const auto& [screen, file] : newest) last[screen] = readPng(file).rgb;
        return last;
    };
    const auto atHead = run("one", one, true), onNodes = run("nodes", nodes, true), fixed = run("fixed", one, false);
    ASSERT_EQ(atHead.size(), 3u);
    ASSERT_EQ(onNodes.size(), 3u);
    for (const auto& [screen, rgb] : atHead) {
        EXPECT_TRUE(onNodes.at(screen) == rgb) << screen << ": the node's post-warp is not the one-PC wall's";
        EXPECT_FALSE(fixed.at(screen) == rgb) << screen << ": the head did not move the picture";
    }
}

// A click picks what the calibrated pixel shows: its ray through the projector pixel's surface
// point, as the frame rendered it. The room is put in the world by a rotation and a scale, so
// the angle between the rays of two clicked pixels is the angle between the eye's rays through
// their surface points; the wall's plain camera (a flat screen's) gives other angles.
TEST(WarpSession, AClickPicksAlongTheCalibratedPixelsRay) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
    RunConfig c = steppedRunConfig(dir, 1);
    c.scene = test::writeFile(dir / "scene.toml", kScene).string();
    c.wall = dir / "c.toml";
    c.cluster.async = false;
    WallSession s(c);
    ASSERT_TRUE(s.step());
    const WallConfig wall = loadWallConfig(dir / "c.toml");
    const MpcdiFile file = readMpcdi(dir / "c.mpcdi");
    const Float3 viewer = wall.stereo.viewer;
    const Camera flat(s.camera(), wall.width, wall.height);
    struct Hit {
        Float3 ray, room, flat;  // the pick's ray (world), the surface point's (room), the plain camera's
    };
    std::vector<Hit> hits;
    for (int k = 0; k < 3; ++k)
        for (int y = 4; y < 48; y += 8)
            for (int x = 4; x < 64; x += 8) {
                const Float3 p = file.buffers[size_t(k)].regions[0].warp.samples[size_t(y) * 64 + size_t(x)];
                if (std::isnan(p.x)) continue;
                const double wx = 64 * k + x + 0.5, wy = y + 0.5;
                const std::optional<PickResult> r = s.pick(wx, wy);
                if (!r) continue;
                hits.push_back({normalize(r->point - s.camera().position), normalize(p - viewer),
                                normalize(flat.direction(float(wx), float(wy)))});
            }
    ASSERT_GT(hits.size(), 20u) << "the scene is not under the pixels";
    double worst = 0, flatWorst = 0;
    for (size_t i = 0; i < hits.size(); ++i)
        for (size_t j = i + 1; j < hits.size(); ++j) {
            const double want = std::acos(std::clamp(double(dot(hits[i].room, hits[j].room)), -1.0, 1.0));
            worst = std::max(worst, std::abs(std::acos(std::clamp(double(dot(hits[i].ray, hits[j].ray)), -1.0, 1.0)) - want));
            flatWorst = std::max(flatWorst, std::abs(std::acos(std::clamp(double(dot(hits[i].flat, hits[j].flat)), -1.0, 1.0)) - want));
        }
    EXPECT_LT(worst, 1e-3) << "radians";
    EXPECT_GT(flatWorst, 0.05) << "the plain camera would pick the same: the test shows nothing";
}

}  // namespace
}  // namespace rtwall
