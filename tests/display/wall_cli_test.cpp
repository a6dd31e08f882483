// `rtwall check` and `rtwall run --wall` as a user meets them: exit codes, one-line errors,
// the headless presenter's per-screen images.
#include "display_test_util.h"

#include <rtwall/wall.h>
#include "cli_util.h"

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <cstdio>

namespace rtwall {
namespace {

// No display: the wall must fall back to headless by itself.
using Result = test::CliResult;

Result run(const std::string& args) { return test::runCli(RTWALL_EXE, args, 300, "env -u DISPLAY -u WAYLAND_DISPLAY"); }

TEST(WallCli, CheckAcceptsEveryShippedWall) {
    for (const char* w : {"desktop", "projectors-2x2", "monitors-3x2-bezels", "projector-pair-blend", "stereo-passive"}) {
        const Result r = run("check " + (test::sourceDir() / "configs/wall" / (std::string(w) + ".toml")).string());
        EXPECT_EQ(r.status, 0) << r.output;
        EXPECT_NE(r.output.find("ok"), std::string::npos) << r.output;
    }
}

TEST(WallCli, CheckNamesTheScreensOfEachDisplayNode) {
    Result r = run("check " + (test::sourceDir() / "configs/wall/two-nodes-2x2.toml").string());
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("4 screens, shaders compile; display nodes: left: c0r0 c0r1; right: c1r0 c1r1\n"), std::string::npos)
        << r.output;
    const auto dir = test::scratchDir();
    const auto bad = test::writeFile(dir / "nodes.toml", "[wall]\nwidth = 100\nheight = 50\n[[screen]]\nviewport = [0, 0, 50, 50]\n"
                                                         "node = \"a\"\n[[screen]]\nviewport = [50, 0, 50, 50]\n");
    r = run("check " + bad.string());
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output, "rtwall: error: " + bad.string() +
                            ":8: screen 'screen2': key 'node': missing; screen 'screen1' is on node 'a', so every screen needs a node\n");
}

// [warp] (issue 30): `rtwall check` reads the calibration and says so; a problem in it is a line
// and exit 1; `rtwall run` refuses the wall in one line while rendering through it is not built.
// The curved example from the command line: checked, run headless (each projector's image
// written), and in post-warp mode (other images), also on quad-buffered screens (each eye's own).
TEST(WallCli, CheckReadsTheProjectorCalibrationAndRunTracesThroughIt) {
    const auto dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 32x24 --wall " + (dir / "c.toml").string());
    Result r = run("check " + (dir / "c.toml").string());
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("3 screens, shaders compile; warp (direct): 3 projectors of c.mpcdi\n"), std::string::npos) << r.output;
    r = run("run " + (test::sourceDir() / "configs/run/demo.toml").string() + " --wall " + (dir / "c.toml").string() +
            " --headless --frames 1 --write-every 1 --out " + (dir / "out").string());
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("warp: c.mpcdi, 3 projector regions on 3 screens, rays through each projector pixel (a3 profile)"),
              std::string::npos) << r.output;
    for (const char* p : {"proj0", "proj1", "proj2"})
        EXPECT_EQ(readPng(dir / "out" / (std::string("frame_000001_") + p + ".png")).width, 32) << p;
    std::ifstream in(dir / "c.toml");
    std::string post((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    post += "mode = \"post\"\n";
    test::writeFile(dir / "post.toml", post);
    r = run("run " + (test::sourceDir() / "configs/run/demo.toml").string() + " --wall " + (dir / "post.toml").string() +
            " --headless --frames 1 --write-every 1 --out " + (dir / "post").string());
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("warp: c.mpcdi, post-warp: flat renders resampled through the calibration on the screens (a3 profile)"),
              std::string::npos) << r.output;
    for (const char* p : {"proj0", "proj1", "proj2"}) {
        const std::string name = std::string("frame_000001_") + p + ".png";
        EXPECT_NE(readPng(dir / "post" / name).rgb, readPng(dir / "out" / name).rgb) << p << ": post-warp and direct alike";
    }
    // A quad-buffered screen shows both eyes, each buffer post-warped from its own eye: both
    // written, and they differ (the eyes are 6.5 cm apart).
    std::string both = post;
    both.replace(both.find("mode = \"none\""), 13, "mode = \"quad_buffer\"");
    test::writeFile(dir / "both.toml", both);
    r = run("run " + (test::sourceDir() / "configs/run/demo.toml").string() + " --wall " + (dir / "both.toml").string() +
            " --headless --frames 1 --write-every 1 --out " + (dir / "both").string());
    EXPECT_EQ(r.status, 0) << r.output;
    for (const char* p : {"proj0", "proj1", "proj2"}) {
        const std::string stem = std::string("frame_000001_") + p;
        EXPECT_NE(readPng(dir / "both" / (stem + "_left.png")).rgb, readPng(dir / "both" / (stem + "_right.png")).rgb) << p;
    }
    std::filesystem::resize_file(dir / "c.mpcdi", 100);
    r = run("check " + (dir / "c.toml").string());
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output.rfind("rtwall: error: " + (dir / "c.toml").string() + ": [warp]: " + (dir / "c.mpcdi").string() +
                                 ": not a readable zip archive (",
                             0),
              0u)
        << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1);
}

// `rtwall display` stops in one line, before listening or connecting, when the clients could not
// be told where it is, or when its keys are half given (as `rtwall client`).
TEST(WallCli, DisplayNeedsAnAdvertisedHostForAWildcardBindAndTheMastersKeyWithItsOwn) {
    Result r = run("display --connect tcp://127.0.0.1:9 --node left --headless --bind tcp://0.0.0.0:0");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output, "rtwall: error: display node: --bind tcp://0.0.0.0:0 listens on every address: say which one the "
                        "render clients reach this node at (--advertise HOST)\n");
    r = run("display --connect tcp://127.0.0.1:9 --node left --headless --bind tcp://*:0");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("(--advertise HOST)"), std::string::npos) << r.output;
    r = run("display --connect tcp://127.0.0.1:9 --node left --headless --advertise 'wall pc'");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("--advertise 'wall pc' is not a host name"), std::string::npos) << r.output;
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "node");
    r = run("display --connect tcp://127.0.0.1:9 --node left --headless --key " + (dir / "node.key").string());
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output, "rtwall: error: --key needs --server-key (the master's public key)\n");
}

TEST(WallCli, CheckReportsABadConfigAndABadShaderOnOneLine) {
    const auto dir = test::scratchDir();
    const auto bad = test::writeFile(dir / "bad.toml", "[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\ngama = 2\n");
    Result r = run("check " + bad.string());
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output, "rtwall: error: " + bad.string() + ":6: [[screen]] #1: unknown key 'gama'\n");
    test::writeFile(dir / "bad.frag", "#version 330 core\nout vec4 colour;\nvoid main() {\n  colour = 1;\n}\n");
    const auto shader = test::writeFile(dir / "shader.toml", "[wall]\nwidth = 100\nheight = 100\n[[screen]]\nviewport = [0, 0, 100, 100]\nshader = \"bad.frag\"\n");
    r = run("check " + shader.string());
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("bad.frag:4: "), std::string::npos) << r.output;
    r = run("check");
    EXPECT_EQ(r.status, 2) << r.output;
    r = run("check " + (dir / "missing.toml").string());
    EXPECT_EQ(r.status, 1) << r.output;
    // run refuses the wall before starting anything.
    r = run("run --wall " + shader.string() + " --frames 1");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("bad.frag:4: "), std::string::npos) << r.output;
}

TEST(WallCli, WebAndSessionOptionsRefuseBadInputOnOneLine) {
    const auto dir = test::scratchDir();
    const std::string minimal = (test::sourceDir() / "tests/data/scenes/minimal.toml").string();
    const std::string scene = test::writeFile(dir / "base.toml", "scene = \"" + minimal + "\"\n[cluster]\nclients = 1\n").string();
    Result r = run("run " + scene + " --web 99999 --frames 1");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output, "rtwall: error: --web 99999: expected [ADDR:]PORT with PORT in 0..65535\n");
    r = run("run " + scene + " --web :80 --frames 1");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output, "rtwall: error: --web :80: the address before ':' is empty\n");
    r = run("run " + scene + " --web 0.0.0.0:0 --frames 1 --headless");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output, "rtwall: error: web: 0.0.0.0 is not loopback: give [web] certificate and key (TLS), or --web-insecure\n");
    const auto cfg = test::writeFile(dir / "run.toml", "scene = \"" + minimal + "\"\n[web]\ntoken = \"short\"\n");
    r = run("run " + cfg.string() + " --frames 1");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.output, "rtwall: error: " + cfg.string() + ":3: [web]: key 'token': 16 to 200 characters of A-Z, a-z, 0-9, '-', '_', '.', '~'\n");
    const auto session = test::writeFile(dir / "s.toml", "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[moved]]\ninstance = 99\n"
                                                        "transform = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]\n");
    r = run("run " + scene + " --session " + session.string() + " --frames 1 --headless");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("rtwall: error: " + session.string() + ":5: [[moved]] #1: key 'instance': 99 does not exist"), std::string::npos)
        << r.output;
    r = run("run " + scene + " --session " + (dir / "none.toml").string() + " --frames 1 --headless");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.output.find("none.toml: no such file"), std::string::npos) << r.output;
}

TEST(WallCli, RunWithoutADisplayWritesWhatEachProjectorGets) {
    const auto dir = test::scratchDir();
    const auto wall = test::writeFile(dir / "wall.toml", "[wall]\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = 64\nscreen_height = 48\n"
                                                         "[headless]\nwrite_every = 2\n");
    const Result r = run("run " + (test::sourceDir() / "configs/run/demo.toml").string() + " --wall " + wall.string() +
                         " --frames 2 --write-every 2 --out " + dir.string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("headless (no DISPLAY)"), std::string::npos) << r.output;
    const Image whole = readPng(dir / "frame_000002.png");
    EXPECT_EQ(whole.width, 128);
    EXPECT_EQ(whole.height, 96);
    const WallConfig w = loadWallConfig(wall);
    WallFrame f;
    f.left = whole;
    for (size_t s = 0; s < 4; ++s) {
        const Image screen = readPng(dir / ("frame_000002_" + w.screens[s].name + ".png"));
        EXPECT_EQ(screen.rgb, presentScreen(w, s, f).rgb) << w.screens[s].name;
    }
}

// The shipped stereo wall: each eye gets its own off-axis view of the wall (from the wall's
// physical corners, the viewer and the eye separation), so the two eyes' images differ.
TEST(WallCli, TheStereoWallWritesDifferentEyes) {
    const auto dir = test::scratchDir();
    const Result r = run("run --wall " + (test::sourceDir() / "configs/wall/stereo-passive.toml").string() +
                         " --headless --frames 1 --write-every 1 --target-fps 0 --out " + dir.string());
    ASSERT_EQ(r.status, 0) << r.output;
    // Both eyes are one rendered frame (one scheduler pass); each eye has its own file.
    std::filesystem::path leftFile, rightFile;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
        const std::string n = e.path().filename().string();
        if (n.ends_with("_left-eye.png")) leftFile = e.path();
        if (n.ends_with("_right-eye.png")) rightFile = e.path();
    }
    ASSERT_FALSE(leftFile.empty()) << r.output;
    ASSERT_FALSE(rightFile.empty()) << r.output;
    const Image left = readPng(leftFile), right = readPng(rightFile);
    ASSERT_EQ(left.width, 1600);
    ASSERT_EQ(right.width, 1600);
    ASSERT_EQ(left.rgb.size(), right.rgb.size());
    size_t differ = 0;
    for (size_t i = 0; i < left.rgb.size(); ++i) differ += left.rgb[i] != right.rgb[i];
    EXPECT_GT(differ, left.rgb.size() / 1000) << "the eyes see the scene from different places";
}

TEST(WallCli, TheShippedWallRunConfigRunsHeadless) {
    const auto dir = test::scratchDir();
    const Result r = run("run " + (test::sourceDir() / "configs/run/wall-2x2.toml").string() + " --frames 1 --write-every 1 --out " +
                         dir.string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(readPng(dir / "frame_000001.png").width, 1600);
    for (const char* s : {"c0r0", "c1r0", "c0r1", "c1r1"})
        EXPECT_EQ(readPng(dir / ("frame_000001_" + std::string(s) + ".png")).width, 800) << s;
}

TEST(WallCli, ARecordedCameraPathReplays) {
    const auto dir = test::scratchDir();
    CameraKey a, b, c;
    a.camera.position = {0, 2, 8};
    b.frame = 1;
    b.camera.position = {3, 2, 8};
    c.frame = 2;
    c.camera.position = {3, 2, 8};
    const auto path = test::writeFile(dir / "recorded.toml", writeCameraPath({a, b, c}, {0, 0, 0}));
    const Result r = run("run " + (test::sourceDir() / "configs/run/demo.toml").string() + " --camera-path " + path.string() +
                         " --frames 3 --write-every 0 --out " + dir.string());
    EXPECT_EQ(r.status, 0) << r.output;
}

}  // namespace
}  // namespace rtwall
