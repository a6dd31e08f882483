// `rtwall display` processes (issue 19): two display nodes of configs/wall/two-nodes-2x2.toml,
// each writing its two screens headless, against a master in this process and render-client
// threads. Each node's screens are byte-identical to the single-PC wall's screens of the same
// frame. Loopback only; every wait is bounded.
#include "display_test_util.h"

#include "../cluster/child_process.h"

#include <rtwall/cluster.h>
#include <rtwall/wall.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <thread>

namespace rtwall {
namespace {

std::string fileBytes(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// The frame to compare: the newest that both nodes presented ("frame_NNNNNN_"). Each node stops
// after presenting its frames, and a frame released while one node was not in yet (or already
// gone) carries the left-out overlay on the other, so a node's own newest frame can name the
// other as left out; a frame both presented was released with both holding it.
std::string newestFrameOfBoth(const std::filesystem::path& dir) {
    std::set<std::string> left, right;
    for (const auto& e : std::filesystem::directory_iterator(dir / "left")) left.insert(e.path().filename().string().substr(0, 13));
    for (const auto& e : std::filesystem::directory_iterator(dir / "right")) right.insert(e.path().filename().string().substr(0, 13));
    std::vector<std::string> both;
    std::set_intersection(left.begin(), left.end(), right.begin(), right.end(), std::back_inserter(both));
    return both.empty() ? std::string() : both.back();
}

TEST(DisplayNodeProcesses, EachShowsItsHalfOfTheWallBitIdentical) {
    const std::filesystem::path configFile = test::sourceDir() / "configs/wall/two-nodes-2x2.toml";
    const std::string text = fileBytes(configFile);
    const WallConfig wall = loadWallConfig(configFile);
    SceneDesc scene = loadSceneFile(test::sourceDir() / "configs/demo.toml");
    scene.settings.width = wall.width;
    scene.settings.height = wall.height;
    scene.settings.supersample = 1;
    const std::filesystem::path dir = test::displayScratchDir();

    struct Joined {
        std::vector<std::thread> threads;
        ~Joined() {
            for (auto& t : threads) t.join();
        }
    } clients;
    ClusterSettings cs;
    cs.async = false;
    cs.displayNodes = displayNodeSettings(wall, text);
    auto master = std::make_unique<Master>(scene, cs);
    std::vector<std::unique_ptr<test::ChildProcess>> nodes;
    for (const std::string name : {"left", "right"})
        nodes.push_back(std::make_unique<test::ChildProcess>(std::vector<std::string>{
            RTWALL_EXE, "display", "--connect", master->endpoint(), "--node", name, "--headless", "--out",
            (dir / name).string(), "--frames", "3", "--exit-after-idle", "20000"}));
    for (int i = 0; i < 2; ++i) {
        ClientSettings c;
        c.connect = master->endpoint();
        c.threads = 1;
        c.exitAfterIdleMs = 5000;
        clients.threads.emplace_back([c] { runClient(c); });
    }
    ASSERT_TRUE(master->waitForClients(2, 20000));
    // Both nodes in before the first frame (a frame released without one names it on the other);
    // then frames until both have presented three they held (the last one is compared), bounded.
    for (auto& n : nodes) ASSERT_TRUE(n->waitFor("joined", 20000)) << n->output();
    for (int i = 0; i < 30; ++i) {
        master->renderFrame();
        if (nodes[0]->wait(0) && nodes[1]->wait(0)) break;
    }
    for (auto& n : nodes) {
        const std::optional<int> status = n->wait(10000);
        ASSERT_TRUE(status.has_value()) << n->output();
        EXPECT_EQ(*status, 0) << n->output();
    }

    // The same frame on one PC: the whole wall's screens from the single-machine image.
    const Scene reference(scene);
    WallFrame one;
    one.left = renderFrame(reference, Camera(scene.cameras.front(), wall.width, wall.height), scene.settings);
    const std::map<std::string, std::vector<std::string>> screensOf{{"left", {"c0r0", "c0r1"}}, {"right", {"c1r0", "c1r1"}}};
    for (const auto& [name, screens] : screensOf) {
        std::vector<std::filesystem::path> written;
        for (const auto& e : std::filesystem::directory_iterator(dir / name)) written.push_back(e.path());
        ASSERT_EQ(written.size(), 3 * 2u) << name;
        const std::string stem = newestFrameOfBoth(dir);
        ASSERT_FALSE(stem.empty()) << "no frame presented by both nodes";
        one.number = uint32_t(std::stoul(stem.substr(6, 6)));
        HeadlessPresenter whole(wall, dir / ("one-" + name));
        whole.present(one);
        for (const std::string& screen : screens) {
            const std::filesystem::path mine = dir / name / (stem + screen + ".png");
            ASSERT_TRUE(std::filesystem::exists(mine)) << mine;
            EXPECT_EQ(fileBytes(mine), fileBytes(dir / ("one-" + name) / (stem + screen + ".png"))) << name << " " << screen;
        }
    }
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
    SceneDesc scene = loadSceneFile(test::sourceDir() / "configs/demo.toml");
    scene.settings.width = wall.width;
    scene.settings.height = wall.height;
    scene.settings.supersample = 1;
    const std::filesystem::path dir = test::displayScratchDir();

    struct Joined {
        std::vector<std::thread> threads;
        ~Joined() {
            for (auto& t : threads) t.join();
        }
    } clients;
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
    std::vector<std::unique_ptr<test::ChildProcess>> nodes;
    for (const std::string name : {"left", "right"})
        nodes.push_back(std::make_unique<test::ChildProcess>(std::vector<std::string>{
            RTWALL_EXE, "display", "--connect", master->endpoint(), "--node", name, "--headless", "--out",
            (dir / name).string(), "--frames", "3", "--exit-after-idle", "20000"}));
    for (int i = 0; i < 2; ++i) {
        ClientSettings c;
        c.connect = master->endpoint();
        c.threads = 1;
        c.exitAfterIdleMs = 5000;
        clients.threads.emplace_back([c] { runClient(c); });
    }
    ASSERT_TRUE(master->waitForClients(2, 20000));
    // Both nodes in before the first frame (a frame released without one names it on the other).
    for (auto& n : nodes) ASSERT_TRUE(n->waitFor("joined", 20000)) << n->output();
    for (int i = 0; i < 30; ++i) {
        master->renderViews();
        if (nodes[0]->wait(0) && nodes[1]->wait(0)) break;
    }
    for (auto& n : nodes) {
        const std::optional<int> status = n->wait(10000);
        ASSERT_TRUE(status.has_value()) << n->output();
        EXPECT_EQ(*status, 0) << n->output();
    }

    const Scene reference(scene);
    WallFrame one;
    one.left = renderFrame(reference, Camera(views[0].camera, wall.width, wall.height), scene.settings);
    one.right = renderFrame(reference, Camera(views[1].camera, wall.width, wall.height), scene.settings);
    ASSERT_NE(one.left.rgb, one.right.rgb);
    const std::map<std::string, std::vector<std::string>> screensOf{
        {"left", {"c0r0L", "c0r0R", "c0r1L", "c0r1R"}}, {"right", {"c1r0L", "c1r0R", "c1r1L", "c1r1R"}}};
    for (const auto& [name, screens] : screensOf) {
        std::vector<std::filesystem::path> written;
        for (const auto& e : std::filesystem::directory_iterator(dir / name)) written.push_back(e.path());
        ASSERT_EQ(written.size(), 3 * 4u) << name;
        const std::string stem = newestFrameOfBoth(dir);
        ASSERT_FALSE(stem.empty()) << "no frame presented by both nodes";
        one.number = uint32_t(std::stoul(stem.substr(6, 6)));
        HeadlessPresenter whole(wall, dir / ("one-" + name));
        whole.present(one);
        for (const std::string& screen : screens) {
            const std::filesystem::path mine = dir / name / (stem + screen + ".png");
            ASSERT_TRUE(std::filesystem::exists(mine)) << mine;
            EXPECT_EQ(fileBytes(mine), fileBytes(dir / ("one-" + name) / (stem + screen + ".png"))) << name << " " << screen;
        }
    }
    master.reset();
}

// CURVE on the node links, as `rtwall run` will start local nodes: with exactly the arguments
// the master gives its PC's processes (localClientArgs: --key, --server-key), two node processes
// join a keyed master and show their screens bit-identical; a node without keys is refused and
// says why in one line, and gives up after its idle time.
TEST(DisplayNodeProcesses, KeyedNodesWithTheLocalArgumentsWorkAndAKeylessOneIsRefused) {
    const std::filesystem::path configFile = test::sourceDir() / "configs/wall/two-nodes-2x2.toml";
    const std::string text = fileBytes(configFile);
    const WallConfig wall = loadWallConfig(configFile);
    SceneDesc scene = loadSceneFile(test::sourceDir() / "configs/demo.toml");
    scene.settings.width = wall.width;
    scene.settings.height = wall.height;
    scene.settings.supersample = 1;
    const std::filesystem::path dir = test::displayScratchDir();
    writeNewKeyPair(dir / "master");

    struct Joined {
        std::vector<std::thread> threads;
        ~Joined() {
            for (auto& t : threads) t.join();
        }
    } clients;
    ClusterSettings cs;
    cs.async = false;
    cs.keyFile = dir / "master.key";
    cs.localClients = 2;
    cs.displayNodes = displayNodeSettings(wall, text);
    auto master = std::make_unique<Master>(scene, cs);
    const std::vector<std::string> keyArgs = master->localClientArgs();
    ASSERT_EQ(keyArgs.size(), 4u);
    std::vector<std::unique_ptr<test::ChildProcess>> nodes;
    for (const std::string name : {"left", "right"}) {
        std::vector<std::string> argv{RTWALL_EXE, "display", "--connect", master->endpoint(), "--node", name, "--headless",
                                      "--out", (dir / name).string(), "--frames", "3", "--exit-after-idle", "20000"};
        argv.insert(argv.end(), keyArgs.begin(), keyArgs.end());
        nodes.push_back(std::make_unique<test::ChildProcess>(argv));
    }
    test::ChildProcess keyless({RTWALL_EXE, "display", "--connect", master->endpoint(), "--node", "left", "--headless", "--out",
                                (dir / "keyless").string(), "--exit-after-idle", "2000"});
    for (int i = 0; i < 2; ++i) {
        ClientSettings c;
        c.connect = master->endpoint();
        c.threads = 1;
        c.exitAfterIdleMs = 5000;
        c.keyFile = keyArgs[1];
        c.serverKeyFile = keyArgs[3];
        clients.threads.emplace_back([c] { runClient(c); });
    }
    ASSERT_TRUE(master->waitForClients(2, 20000));
    // Both nodes in before the first frame (a frame released without one names it on the other).
    for (auto& n : nodes) ASSERT_TRUE(n->waitFor("joined", 20000)) << n->output();
    for (int i = 0; i < 30; ++i) {
        master->renderFrame();
        if (nodes[0]->wait(0) && nodes[1]->wait(0)) break;
    }
    for (auto& n : nodes) {
        const std::optional<int> status = n->wait(10000);
        ASSERT_TRUE(status.has_value()) << n->output();
        EXPECT_EQ(*status, 0) << n->output();
    }
    const std::optional<int> refused = keyless.wait(20000);
    ASSERT_TRUE(refused.has_value()) << keyless.output();
    EXPECT_EQ(*refused, 1) << keyless.output();
    EXPECT_NE(keyless.output().find("disagree on security"), std::string::npos) << keyless.output();
    EXPECT_FALSE(std::filesystem::exists(dir / "keyless")) << "a refused node presented something";

    const Scene reference(scene);
    WallFrame one;
    one.left = renderFrame(reference, Camera(scene.cameras.front(), wall.width, wall.height), scene.settings);
    const std::map<std::string, std::vector<std::string>> screensOf{{"left", {"c0r0", "c0r1"}}, {"right", {"c1r0", "c1r1"}}};
    for (const auto& [name, screens] : screensOf) {
        std::vector<std::filesystem::path> written;
        for (const auto& e : std::filesystem::directory_iterator(dir / name)) written.push_back(e.path());
        ASSERT_EQ(written.size(), 3 * 2u) << name;
        const std::string stem = newestFrameOfBoth(dir);
        ASSERT_FALSE(stem.empty()) << "no frame presented by both nodes";
        one.number = uint32_t(std::stoul(stem.substr(6, 6)));
        HeadlessPresenter whole(wall, dir / ("one-" + name));
        whole.present(one);
        for (const std::string& screen : screens)
            EXPECT_EQ(fileBytes(dir / name / (stem + screen + ".png")), fileBytes(dir / ("one-" + name) / (stem + screen + ".png")))
                << name << " " << screen;
    }
    master.reset();
}

}  // namespace
}  // namespace rtwall
