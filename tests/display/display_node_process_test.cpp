// `rtwall display` processes (issue 19): two display nodes of configs/wall/two-nodes-2x2.toml,
// each writing its two screens headless, against a master in this process and render-client
// threads. Each node's screens are byte-identical to the single-PC wall's screens of the same
// frame. Loopback only; every wait is bounded.
#include "display_test_util.h"

#include "files.h"
#include "node_kit.h"
#include "test_util.h"

#include <rtwall/cluster.h>
#include <rtwall/wall.h>

#include <gtest/gtest.h>

namespace rtwall {
namespace {

using test::fileBytes;

// The shipped two-node wall (its text and its config) and the demo scene at the wall's size.
struct TwoNodeWall {
    std::string text;
    WallConfig wall;
    SceneDesc scene;
};
TwoNodeWall twoNodeWall() {
    const std::filesystem::path configFile = test::sourceDir() / "configs/wall/two-nodes-2x2.toml";
    const WallConfig wall = loadWallConfig(configFile);
    return {fileBytes(configFile), wall, test::demoScene(wall.width, wall.height, 1)};
}

// The wall's "left" and "right" node processes and two client threads join `master`; `render`
// makes frames until both nodes have presented three they held (the last one is compared), bounded.
void runLeftAndRight(Master& master, test::ClientThreads& clients, const std::filesystem::path& dir,
                     const std::function<void()>& render) {
    test::NodeProcesses nodes = test::startDisplayNodes(RTWALL_EXE, master.endpoint(), {"left", "right"}, dir);
    for (int i = 0; i < 2; ++i) clients.start(test::localClient(master.endpoint()));
    ASSERT_TRUE(master.waitForClients(2, 20000));
    ASSERT_NO_FATAL_FAILURE(test::runUntilNodesEnd(nodes, render));
}

// The same frame on one PC: the "left" and "right" nodes' newest screens are the whole wall's
// screens of the single-machine image of `scene`, byte for byte.
void expectLeftAndRightShowOnePc(const WallConfig& wall, const SceneDesc& scene, const std::filesystem::path& dir) {
    const Scene reference(scene);
    WallFrame one;
    one.left = renderFrame(reference, Camera(scene.cameras.front(), wall.width, wall.height), scene.settings);
    const std::map<std::string, std::vector<std::string>> screensOf{{"left", {"c0r0", "c0r1"}}, {"right", {"c1r0", "c1r1"}}};
    test::expectNodeScreensMatchOnePc(wall, one, dir, screensOf, 3 * 2u);
}

TEST(DisplayNodeProcesses, EachShowsItsHalfOfTheWallBitIdentical) {
    auto [text, wall, scene] = twoNodeWall();
    const std::filesystem::path dir = test::scratchDir();

    test::ClientThreads clients;
    ClusterSettings cs;
    cs.async = false;
    cs.displayNodes = displayNodeSettings(wall, text);
    auto master = std::make_unique<Master>(scene, cs);
    ASSERT_NO_FATAL_FAILURE(runLeftAndRight(*master, clients, dir, [&] { master->renderFrame(); }));

    expectLeftAndRightShowOnePc(wall, scene, dir);
    master.reset();
}

// A passive-stereo 2x2 wall on two nodes (protocol 12): both eyes render in one frame (two
// views), and each node writes the left- and right-eye screens of its column, byte-identical
// to the single-PC wall's screens of the same eye images.
TEST(DisplayNodeProcesses, StereoWallShowsBothEyesOfEachNodesScreensBitIdentical) {
    const std::string text = fileBytes(test::sourceDir() / "configs/wall/two-nodes-2x2.toml") +
                             "\n[stereo]\nmode = \"passive\"\neye_separation = 0.065\n";
    const WallConfig wall = parseWallConfig(text, "stereo two-node wall");
    ASSERT_EQ(wall.screens.size(), 8u);
    SceneDesc scene = test::demoScene(wall.width, wall.height, 1);
    const std::filesystem::path dir = test::scratchDir();

    test::ClientThreads clients;
    ClusterSettings cs;
    cs.async = false;
    cs.displayNodes = displayNodeSettings(wall, text, {0, 1});
    auto master = std::make_unique<Master>(scene, cs);
    // Two eyes a little apart: any two cameras do, the point is that each eye's screens show its own.
    std::vector<FrameView> views(2);
    for (int e = 0; e < 2; ++e) {
        views[size_t(e)].camera = scene.cameras.front();
        views[size_t(e)].camera.position.x += e == 0 ? -0.3f : 0.3f;
    }
    master->setViews(views);
    ASSERT_NO_FATAL_FAILURE(runLeftAndRight(*master, clients, dir, [&] { master->renderViews(); }));

    const Scene reference(scene);
    WallFrame one;
    one.left = renderFrame(reference, Camera(views[0].camera, wall.width, wall.height), scene.settings);
    one.right = renderFrame(reference, Camera(views[1].camera, wall.width, wall.height), scene.settings);
    ASSERT_NE(one.left.rgb, one.right.rgb);
    const std::map<std::string, std::vector<std::string>> screensOf{
        {"left", {"c0r0L", "c0r0R", "c0r1L", "c0r1R"}}, {"right", {"c1r0L", "c1r0R", "c1r1L", "c1r1R"}}};
    test::expectNodeScreensMatchOnePc(wall, one, dir, screensOf, 3 * 4u);
    master.reset();
}

// CURVE on the node links, as `rtwall run` will start local nodes: with exactly the arguments
// the master gives its PC's processes (localClientArgs: --key, --server-key), two node processes
// join a keyed master and show their screens bit-identical; a node without keys is refused and
// says why in one line, and gives up after its idle time.
TEST(DisplayNodeProcesses, KeyedNodesWithTheLocalArgumentsWorkAndAKeylessOneIsRefused) {
    auto [text, wall, scene] = twoNodeWall();
    const std::filesystem::path dir = test::scratchDir();
    writeNewKeyPair(dir / "master");

    test::ClientThreads clients;
    ClusterSettings cs;
    cs.async = false;
    cs.keyFile = dir / "master.key";
    cs.localClients = 2;
    cs.displayNodes = displayNodeSettings(wall, text);
    auto master = std::make_unique<Master>(scene, cs);
    const std::vector<std::string> keyArgs = master->localClientArgs();
    ASSERT_EQ(keyArgs.size(), 4u);
    test::NodeProcesses nodes = test::startDisplayNodes(RTWALL_EXE, master->endpoint(), {"left", "right"}, dir, keyArgs);
    test::ChildProcess keyless({RTWALL_EXE, "display", "--connect", master->endpoint(), "--node", "left", "--headless", "--out",
                                (dir / "keyless").string(), "--exit-after-idle", "2000"});
    for (int i = 0; i < 2; ++i) {
        ClientSettings c = test::localClient(master->endpoint());
        c.keyFile = keyArgs[1];
        c.serverKeyFile = keyArgs[3];
        clients.start(c);
    }
    ASSERT_TRUE(master->waitForClients(2, 20000));
    // Frames until both nodes have presented three they held (the last one is compared), bounded.
    ASSERT_NO_FATAL_FAILURE(test::runUntilNodesEnd(nodes, [&] { master->renderFrame(); }));
    const std::optional<int> refused = keyless.wait(20000);
    ASSERT_TRUE(refused.has_value()) << keyless.output();
    EXPECT_EQ(*refused, 1) << keyless.output();
    EXPECT_NE(keyless.output().find("disagree on security"), std::string::npos) << keyless.output();
    EXPECT_FALSE(std::filesystem::exists(dir / "keyless")) << "a refused node presented something";

    expectLeftAndRightShowOnePc(wall, scene, dir);
    master.reset();
}

}  // namespace
}  // namespace rtwall
