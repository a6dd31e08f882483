// Two windowed `rtwall display` nodes of configs/wall/two-nodes-2x2.toml under this binary's Xvfb
// (gl_presenter_test.cpp starts it; Mesa's llvmpipe), against `rtwall run --no-local-nodes`
// (the nodes started on their own, as on a real installation; the master opens its console
// window). What each node's windows show, read back from OpenGL (--capture), is its half of the
// single-PC wall exactly. The wall asks for GLX_NV_swap_group, which Mesa does not have: each
// node says so in one line and runs on. Loopback only; every wait is bounded.
#include "display_test_util.h"

#include "child_process.h"
#include "files.h"
#include "test_util.h"

#include <rtwall/engine.h>

#include <map>

namespace rtwall {
namespace {

using test::fileBytes;

TEST(NodeWindows, TwoWindowedNodesEachShowTheirHalfOfTheWall) {
    const std::filesystem::path dir = test::scratchDir();
    WallConfig wall = loadWallConfig(test::sourceDir() / "configs/wall/two-nodes-2x2.toml");
    wall.swapGroup = 1;
    wall.swapBarrier = 1;
    const std::filesystem::path wallFile = test::writeFile(dir / "wall.toml", writeWallConfig(wall));
    // A still camera: every frame is the same image (a windowed master does not orbit anyway).
    const std::filesystem::path runFile = test::writeFile(
        dir / "run.toml", "scene = \"" + (test::sourceDir() / "configs/demo.toml").string() + "\"\ncamera = \"main\"\n[run]\norbit = 0.0\n");

    test::ChildProcess master({RTWALL_EXE, "run", runFile.string(), "--wall", wallFile.string(), "--no-local-nodes", "--frames", "3",
                               "--out", (dir / "master").string()});
    const std::optional<std::string> endpoint = master.waitFor("rtwall master at (tcp://127\\.0\\.0\\.1:[0-9]+)", 60'000);
    ASSERT_TRUE(endpoint) << master.output();
    ASSERT_TRUE(master.waitFor("waiting for display node 'right'", 10'000)) << master.output();
    std::map<std::string, std::unique_ptr<test::ChildProcess>> nodes;
    for (const std::string name : {"left", "right"})
        nodes[name] = std::make_unique<test::ChildProcess>(std::vector<std::string>{
            RTWALL_EXE, "display", "--connect", *endpoint, "--node", name, "--capture", (dir / name).string(), "--out",
            (dir / ("headless-" + name)).string(), "--exit-after-idle", "20000"});
    const std::optional<int> status = master.wait(240'000);
    ASSERT_TRUE(status.has_value()) << master.output();
    ASSERT_EQ(*status, 0) << master.output();
    EXPECT_NE(master.output().find("this PC shows a console window"), std::string::npos) << master.output();
    for (auto& [name, node] : nodes) {
        ASSERT_EQ(node->wait(30'000), std::optional<int>(0)) << node->output();
        EXPECT_NE(node->output().find("GLX_NV_swap_group is absent"), std::string::npos) << node->output();
        EXPECT_FALSE(std::filesystem::exists(dir / ("headless-" + name))) << "the node fell back to writing files:\n" << node->output();
    }

    // The single-PC wall: the whole frame on this machine, cut into the four screens.
    const SceneDesc scene = test::demoScene(wall.width, wall.height);
    const Scene reference(scene);
    WallFrame one;
    one.left = renderFrame(reference, Camera(*scene.findCamera("main"), wall.width, wall.height), scene.settings);
    one.number = 1;
    HeadlessPresenter(wall, dir / "one").present(one);

    const std::map<std::string, std::vector<std::string>> screensOf{{"left", {"c0r0", "c0r1"}}, {"right", {"c1r0", "c1r1"}}};
    for (const auto& [name, screens] : screensOf) {
        size_t frames = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir / name)) {
            const std::string f = e.path().filename().string();  // frame_NNNNNN_SCREEN.png
            SCOPED_TRACE(name + "/" + f);
            ASSERT_EQ(f.size(), std::string("frame_000001_c0r0.png").size());
            const std::string screen = f.substr(13, 4);
            ASSERT_NE(std::find(screens.begin(), screens.end(), screen), screens.end()) << "a screen of the other node";
            EXPECT_EQ(fileBytes(e.path()), fileBytes(dir / "one" / ("frame_000001_" + screen + ".png")));
            frames += screen == screens.front();
        }
        EXPECT_GE(frames, 2u) << name << ": " << nodes[name]->output();
    }
}

// The one command with a display: the local nodes open their windows (and write nothing), the
// master its console window.
TEST(NodeWindows, OneCommandOpensTheNodesWindowsAndTheMastersConsole) {
    const std::filesystem::path dir = test::scratchDir();
    test::ChildProcess run({RTWALL_EXE, "run", (test::sourceDir() / "configs/run/demo.toml").string(), "--wall",
                            (test::sourceDir() / "configs/wall/two-nodes-2x2.toml").string(), "--frames", "3", "--out", dir.string()});
    const std::optional<int> status = run.wait(240'000);
    ASSERT_TRUE(status.has_value()) << run.output();
    ASSERT_EQ(*status, 0) << run.output();
    const std::string out = run.output();
    EXPECT_NE(out.find("display nodes: all 2 joined (left, right)"), std::string::npos) << out;
    EXPECT_NE(out.find("this PC shows a console window"), std::string::npos) << out;
    EXPECT_NE(out.find("display nodes 2/2, "), std::string::npos) << out;
    EXPECT_EQ(out.find("no window"), std::string::npos) << "a node fell back to files:\n" << out;
    EXPECT_FALSE(std::filesystem::exists(dir / "left")) << out;
    EXPECT_FALSE(std::filesystem::exists(dir / "right")) << out;
}

}  // namespace
}  // namespace rtwall
