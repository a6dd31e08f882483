// `rtwall run` of a wall on two display nodes in one command (issue 19): the session starts one
// `rtwall display` process per node on this PC; each writes its screens, and they are the
// single-PC wall's screens byte for byte. A node killed mid-run is said, and the run finishes
// with the other. Loopback only; every wait is bounded.
#include "display_test_util.h"

#include "child_process.h"
#include "files.h"

#include <rtwall/display.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <map>
#include <regex>
#include <set>

namespace rtwall {
namespace {

using test::fileBytes;

std::vector<std::string> filesIn(const std::filesystem::path& dir) {
    std::vector<std::string> out;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
}

const std::map<std::string, std::set<std::string>> kScreensOf{{"left", {"c0r0", "c0r1"}}, {"right", {"c1r0", "c1r1"}}};

std::filesystem::path nodesWall() { return test::sourceDir() / "configs/wall/two-nodes-2x2.toml"; }

// The same wall without nodes: the master drives the four screens, as on one PC.
std::filesystem::path onePcWall(const std::filesystem::path& dir) {
    WallConfig w = loadWallConfig(nodesWall());
    for (ScreenConfig& s : w.screens) s.node.clear();
    const std::filesystem::path file = dir / "one-pc.toml";
    test::writeFile(file, writeWallConfig(w));
    EXPECT_TRUE(loadWallConfig(file).nodes().empty());
    return file;
}

std::vector<std::string> runArgs(const std::filesystem::path& wall, int frames, const std::filesystem::path& out) {
    return {RTWALL_EXE, "run", (test::sourceDir() / "configs/run/demo.toml").string(), "--wall", wall.string(), "--headless",
            "--frames", std::to_string(frames), "--out", out.string()};
}

TEST(NodeRun, OneCommandRunsTwoLocalNodesBitIdenticalToOnePc) {
    const std::filesystem::path dir = test::scratchDir();
    test::ChildProcess nodes(runArgs(nodesWall(), 4, dir / "nodes"));
    const std::optional<int> status = nodes.wait(240'000);
    ASSERT_TRUE(status.has_value()) << nodes.output();
    ASSERT_EQ(*status, 0) << nodes.output();
    EXPECT_NE(nodes.output().find("display nodes: all 2 joined (left, right)"), std::string::npos) << nodes.output();
    EXPECT_NE(nodes.output().find("display nodes 2/2, "), std::string::npos) << nodes.output();
    // The master wrote no screens of its own.
    for (const std::string& f : filesIn(dir / "nodes")) EXPECT_TRUE(f == "left" || f == "right") << f;

    test::ChildProcess onePc(runArgs(onePcWall(dir), 4, dir / "one"));
    ASSERT_EQ(onePc.wait(240'000), std::optional<int>(0)) << onePc.output();

    for (const auto& [node, screens] : kScreensOf) {
        const std::vector<std::string> files = filesIn(dir / "nodes" / node);
        // Every frame, each as two screens: none is lost to the next frame overtaking it (async),
        // and the last frame's swap is waited for before the run ends.
        for (int frame = 1; frame <= 4; ++frame)
            for (const std::string& screen : screens) {
                char name[64];
                std::snprintf(name, sizeof name, "frame_%06d_%s.png", frame, screen.c_str());
                EXPECT_NE(std::find(files.begin(), files.end(), name), files.end()) << node << " did not show " << name << "\n"
                                                                                    << nodes.output();
            }
        for (const std::string& f : files) {
            SCOPED_TRACE(node + "/" + f);
            ASSERT_EQ(f.size(), std::string("frame_000001_c0r0.png").size());
            EXPECT_TRUE(screens.count(f.substr(13, 4))) << "a screen of the other node";
            ASSERT_TRUE(std::filesystem::exists(dir / "one" / f));
            EXPECT_EQ(fileBytes(dir / "nodes" / node / f), fileBytes(dir / "one" / f));
        }
    }
}

// A calibrated wall (issue 30) on two display nodes: the clients trace through the warps (or,
// post-warping, render flat and each node resamples its screens from the eyes each frame names),
// each node blends its screens with the file's maps, and every screen is the one-PC wall's bytes;
// post-warped also on quad-buffered screens (each eye's buffer from its eye).
TEST(NodeRun, TheCurvedWallOnTwoNodesIsTheOnePcWallsBytes) {
    for (const std::string variant : {"direct", "post", "post-quad"}) {
        SCOPED_TRACE(variant);
        const std::filesystem::path dir = test::scratchDir() / variant;
        std::filesystem::create_directories(dir);
        test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
        std::string text = fileBytes(dir / "c.toml");
        if (variant == "post-quad") text.replace(text.find("mode = \"none\""), 13, "mode = \"quad_buffer\"");
        test::writeFile(dir / "c.toml", text);
        WallConfig w = loadWallConfig(dir / "c.toml");
        w.writeEvery = 1;
        if (variant != "direct") w.warp->mode = WarpMode::Post;
        test::writeFile(dir / "one.toml", writeWallConfig(w));
        for (ScreenConfig& sc : w.screens) sc.node = sc.name == "proj2" ? "right" : "left";
        test::writeFile(dir / "nodes.toml", writeWallConfig(w));
        test::ChildProcess nodes(runArgs(dir / "nodes.toml", 2, dir / "nodes"));
        ASSERT_EQ(nodes.wait(240'000), std::optional<int>(0)) << nodes.output();
        EXPECT_EQ(nodes.output().find("without the calibration's"), std::string::npos) << nodes.output();
        test::ChildProcess onePc(runArgs(dir / "one.toml", 2, dir / "one"));
        ASSERT_EQ(onePc.wait(240'000), std::optional<int>(0)) << onePc.output();
        size_t compared = 0;
        const std::vector<std::string> suffixes = variant == "post-quad" ? std::vector<std::string>{"_left", "_right"} : std::vector<std::string>{""};
        for (const auto& [node, screens] : std::map<std::string, std::vector<std::string>>{{"left", {"proj0", "proj1"}}, {"right", {"proj2"}}})
            for (int frame = 1; frame <= 2; ++frame)
                for (const std::string& screen : screens)
                    for (const std::string& eye : suffixes) {
                        char name[64];
                        std::snprintf(name, sizeof name, "frame_%06d_%s%s.png", frame, screen.c_str(), eye.c_str());
                        SCOPED_TRACE(node + "/" + name);
                        ASSERT_TRUE(std::filesystem::exists(dir / "nodes" / node / name)) << nodes.output();
                        EXPECT_TRUE(fileBytes(dir / "nodes" / node / name) == fileBytes(dir / "one" / name));
                        ++compared;
                    }
        EXPECT_EQ(compared, 6u * suffixes.size());
        if (variant == "post-quad") {  // the eyes' buffers differ: each was warped from its own eye
            EXPECT_NE(fileBytes(dir / "one" / "frame_000002_proj1_left.png"), fileBytes(dir / "one" / "frame_000002_proj1_right.png"));
        }
    }
}

// The node's process among the run's children, by its --node argument.
pid_t nodeProcess(pid_t run, const std::string& name) {
    for (pid_t kid : test::childrenOf(run)) {
        if (fileBytes("/proc/" + std::to_string(kid) + "/cmdline").find(std::string("--node\0", 7) + name + '\0') != std::string::npos) return kid;
    }
    return 0;
}

TEST(NodeRun, AKilledLocalNodeIsSaidAndTheRunFinishesWithTheOther) {
    const std::filesystem::path dir = test::scratchDir();
    test::ChildProcess run(runArgs(nodesWall(), 30, dir));
    ASSERT_TRUE(run.waitFor("display nodes: all 2 joined", 120'000)) << run.output();
    ASSERT_TRUE(run.waitFor("frame 10:", 120'000)) << run.output();
    const pid_t right = nodeProcess(run.pid(), "right");
    ASSERT_GT(right, 0) << "no local node process 'right'";
    ASSERT_EQ(kill(right, SIGKILL), 0);
    const std::optional<int> status = run.wait(240'000);
    ASSERT_TRUE(status.has_value()) << run.output();
    EXPECT_EQ(*status, 0) << run.output();
    const std::string out = run.output();
    EXPECT_TRUE(std::regex_search(out, std::regex("local display node 'right' \\(pid " + std::to_string(right) + "\\) killed by signal 9")))
        << out;
    EXPECT_NE(out.find("display nodes there: left (1 of 2)"), std::string::npos) << out;
    EXPECT_NE(out.find("30 frames"), std::string::npos) << out;
    // The left node went on to the end; the right one stopped where it was killed.
    const std::vector<std::string> left = filesIn(dir / "left"), rightFiles = filesIn(dir / "right");
    EXPECT_NE(std::find(left.begin(), left.end(), "frame_000030_c0r0.png"), left.end()) << out;
    EXPECT_EQ(std::find(rightFiles.begin(), rightFiles.end(), "frame_000030_c1r0.png"), rightFiles.end()) << out;
    EXPECT_FALSE(test::alive(right));
}

// Denoising on display nodes (issue 28): a path-traced room, svgf, the camera orbiting, on the
// two-node wall (mono: one image; stereo side by side: a view per eye). Each node filters its
// screens, each with the ring of pixels around it the single-PC wall filters with, and shows the
// single-PC wall's screens byte for byte; and they are denoised (not the frames as they came).
class NodeRunDenoise : public ::testing::TestWithParam<bool> {};

TEST_P(NodeRunDenoise, EachNodeFiltersItsScreensToTheSinglePcWallsBytes) {
    const bool stereo = GetParam();
    const std::filesystem::path dir = test::scratchDir();
    auto wallFile = [&](const std::filesystem::path& from, const std::string& name) {
        std::string text = fileBytes(from);
        if (stereo) {  // a table of its own: where it goes in the file does not matter
            text.insert(0, "[stereo]\nmode = \"side_by_side\"\neye_separation = 0.065\nviewer = [0.0, 0.0, 2.5]\n"
                              "lower_left = [-1.6, -1.2, 0.0]\nlower_right = [1.6, -1.2, 0.0]\nupper_left = [-1.6, 1.2, 0.0]\n\n");
        }
        return test::writeFile(dir / name, text);
    };
    const std::filesystem::path nodes = wallFile(nodesWall(), "nodes.toml");
    WallConfig single = loadWallConfig(nodes);  // the same wall, its screens on the master
    for (ScreenConfig& sc : single.screens) sc.node.clear();
    const std::filesystem::path one = test::writeFile(dir / "one.toml", writeWallConfig(single));
    // No node may be left out of a swap for being slow (a loaded machine: each node filters its
    // screens on the same two cores): a node left out restarts its history, by design.
    auto runConfig = [&](const std::string& denoise, const std::string& name) {
        return test::writeFile(dir / name, "scene = \"" + (test::sourceDir() / "tests/data/scenes/gi_room.toml").string() +
                                               "\"\n[cluster]\nclients = 2\nthreads = 1\nnode_stall_ms = 120000\n[run]\nframes = 3\nwrite_every = 1\n"
                                               "orbit = 2.0\ndenoise = \"" + denoise + "\"\n");
    };
    auto run = [&](const std::filesystem::path& config, const std::filesystem::path& wall, const std::string& out) {
        test::ChildProcess p({RTWALL_EXE, "run", config.string(), "--wall", wall.string(), "--headless", "--out", (dir / out).string()});
        const std::optional<int> status = p.wait(240'000);
        EXPECT_EQ(status, std::optional<int>(0)) << p.output();
        return p.output();
    };
    const std::string onNodes = run(runConfig("svgf", "svgf.toml"), nodes, "nodes");
    EXPECT_NE(onNodes.find("denoise: svgf (5 levels, history 32), on the frames of a stochastic scene, on the display nodes "
                           "(79-pixel ring around each screen)"),
              std::string::npos) << onNodes;
    run(runConfig("svgf", "svgf.toml"), one, "one");
    run(runConfig("off", "off.toml"), one, "off");
    size_t compared = 0, denoised = 0;
    for (const auto& [node, screens] : kScreensOf)
        for (int frame = 1; frame <= 3; ++frame)
            for (const std::string& screen : screens) {
                char name[64];
                std::snprintf(name, sizeof name, "frame_%06d_%s.png", frame, screen.c_str());
                SCOPED_TRACE(node + "/" + name);
                ASSERT_TRUE(std::filesystem::exists(dir / "nodes" / node / name)) << onNodes;
                const std::string shown = fileBytes(dir / "nodes" / node / name);
                EXPECT_TRUE(shown == fileBytes(dir / "one" / name)) << "not the single-PC wall's screen";
                denoised += shown != fileBytes(dir / "off" / name);
                ++compared;
            }
    EXPECT_EQ(compared, 12u);
    EXPECT_EQ(denoised, compared) << "every screen of every frame filtered";
}

INSTANTIATE_TEST_SUITE_P(MonoAndStereo, NodeRunDenoise, ::testing::Bool(),
                         [](const auto& p) { return p.param ? "StereoSideBySide" : "Mono"; });

}  // namespace
}  // namespace rtwall
