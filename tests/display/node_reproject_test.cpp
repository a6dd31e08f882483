// Re-projection on display nodes (issue 27), in one process on loopback: two nodes (threads
// running the cluster's runDisplayNode) each warp their screens of the newest released frame to
// the pose the master sends, and what they show there is the single-PC wall's re-projection of
// the same frame to the same pose, byte for byte; a pose before any release shows nothing; a
// pose with the wrong number of cameras is skipped and counted, never shown. (Without the ring of
// tiles around each node's screens, 145 of the left node's 153,600 screen pixels differ for this
// move: pixels that warp across the seam from tiles the node did not get.)
#include "display_test_util.h"

#include "files.h"
#include "node_kit.h"
#include "test_util.h"

#include <rtwall/cluster.h>
#include <rtwall/display.h>
#include <rtwall/frame.h>
#include <rtwall/wall.h>

#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <chrono>
#include <map>
#include <mutex>
#include <thread>

namespace rtwall {
namespace {

using test::fileBytes;

const char* const kNodes[] = {"left", "right"};

// A display node on a thread of the test: each refresh it warps on the CPU and keeps the eyes.
class NodeThread {
public:
    // `warpMs`: each refresh takes at least this long (a node slower than the refresh rate).
    NodeThread(const std::string& endpoint, const std::string& name, int warpMs = 0) {
        run_.connect = endpoint;
        run_.name = name;
        run_.exitAfterIdleMs = 5000;
        run_.stop = &stop_;
        run_.counters = counters_;
        run_.onWall = [](const std::string&) {};
        run_.present = [this](uint32_t, const Image*, const Image*, const std::vector<std::string>&) { ++swapsPresented_; };
        run_.refresh = [this, warpMs](const NodeRefresh& r) {
            const EyeImages& eyes = r.compositor->reproject(r.targets, {}, r.debug);
            if (warpMs > 0) std::this_thread::sleep_for(std::chrono::milliseconds(warpMs));
            std::lock_guard lock(m_);
            shown_ = eyes.left;
            frame_ = r.frame;
            refresh_ = r.refresh;
        };
        thread_ = std::thread([this] { runDisplayNode(run_); });
    }
    ~NodeThread() {
        stop_ = true;
        thread_.join();
    }
    // Waits (bounded) until the node showed refresh `refresh` or a later one; its left image.
    std::optional<Image> shownAfter(uint32_t refresh, int timeoutMs = 10000) {
        for (int waited = 0; waited < timeoutMs; waited += 5) {
            {
                std::lock_guard lock(m_);
                if (refresh_ >= refresh) return shown_;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        return std::nullopt;
    }
    uint32_t shownFrame() {
        std::lock_guard lock(m_);
        return frame_;
    }
    const DisplayNodeCounters& counters() const { return *counters_; }
    int swapsPresented() const { return swapsPresented_; }

private:
    DisplayNodeRun run_;
    std::atomic<bool> stop_{false};
    std::shared_ptr<DisplayNodeCounters> counters_ = std::make_shared<DisplayNodeCounters>();
    std::atomic<int> swapsPresented_{0};
    std::mutex m_;
    Image shown_;
    uint32_t frame_ = 0, refresh_ = 0;
    std::thread thread_;
};

// The pose's answers the master got, waited for (bounded): every node answered `refresh`.
bool nodesAnswered(Master& master, uint32_t refresh, std::vector<NodeRefreshDelay>& seen) {
    for (int i = 0; i < 2000; ++i) {
        for (NodeRefreshDelay& d : master.takeNodeRefreshes()) seen.push_back(d);
        size_t n = 0;
        for (const NodeRefreshDelay& d : seen) n += d.refresh == refresh;
        if (n == std::size(kNodes)) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
}

TEST(NodeReprojection, EachNodeShowsItsScreensOfTheSinglePcWarpForTheMastersPose) {
    const std::string text = fileBytes(test::sourceDir() / "configs/wall/two-nodes-2x2.toml");
    const WallConfig wall = parseWallConfig(text, "two-node wall");
    SceneDesc scene = test::demoScene(wall.width, wall.height);
    scene.settings.tileSize = 32;
    // One view over the whole wall: the rendered camera, and the pose the head moved to since
    // (4 cm to the side and 2 cm up, looking at the same point).
    FrameView view;
    view.camera = scene.cameras.front();
    CameraDesc target = view.camera;
    target.position.x += 0.04f;
    target.position.y += 0.02f;

    // The single-PC wall: its frame with depth (decoded from the same tiles' codes), composed and
    // re-projected by the one Compositor.
    Image unwarped, want;
    {
        test::ClientThreads clients;
        ClusterSettings cs;
        cs.async = false;
        cs.depth = true;
        Master one(scene, cs);
        for (int i = 0; i < 2; ++i) clients.start(test::localClient(one.endpoint()));
        ASSERT_TRUE(one.waitForClients(2, 20000));
        one.setViews({view});
        FrameReport report;
        std::vector<std::vector<float>> depth;
        std::vector<Image> images = one.renderViews(&report, nullptr, &depth);
        ASSERT_EQ(images.size(), 1u);
        ASSERT_EQ(depth.size(), 1u);
        Compositor c;
        ComposeFrame f;
        f.views = {view};
        f.eyes = {-1};
        f.depth = depth;
        unwarped = c.compose(f, images).left;
        const std::vector<CameraDesc> targets{target};
        want = c.reproject(targets).left;
    }
    ASSERT_NE(unwarped.rgb, want.rgb) << "the pose moved: the warp must change the picture";

    test::ClientThreads clients;
    ClusterSettings cs;
    cs.async = false;
    cs.depth = true;
    cs.displayNodes = displayNodeSettings(wall, text, {-1}, true);
    ASSERT_TRUE(cs.displayNodes.reproject);
    auto master = std::make_unique<Master>(scene, cs);
    std::map<std::string, std::unique_ptr<NodeThread>> nodes;
    for (const char* n : kNodes) nodes[n] = std::make_unique<NodeThread>(master->endpoint(), n);
    ASSERT_TRUE(master->waitForDisplayNodes(20000));
    for (int i = 0; i < 2; ++i) clients.start(test::localClient(master->endpoint()));
    ASSERT_TRUE(master->waitForClients(2, 20000));

    // Before any frame was released there is nothing to warp: the pose is not sent.
    master->presentPose(std::vector<CameraDesc>{target});
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    EXPECT_TRUE(master->takeNodeRefreshes().empty());
    for (const auto& [name, node] : nodes) EXPECT_EQ(node->counters().refreshes.load(), 0u) << name;

    master->setViews({view});
    FrameReport report;
    master->renderViews(&report);
    ASSERT_TRUE(master->waitForSwap(report.frame, 10000));
    for (const auto& [name, node] : nodes) EXPECT_EQ(node->swapsPresented(), 0) << name << ": a re-projecting node shows frames at poses, not at swaps";

    // Refresh 1: the rendered pose gives the unwarped frame; refresh 2: the moved pose.
    std::vector<NodeRefreshDelay> answers;
    const TileRouting routing(wall, wall.width, wall.height);
    for (uint32_t refresh : {1u, 2u}) {
        SCOPED_TRACE("refresh " + std::to_string(refresh));
        master->presentPose(std::vector<CameraDesc>{refresh == 1 ? view.camera : target});
        const Image& expected = refresh == 1 ? unwarped : want;
        for (size_t n = 0; n < std::size(kNodes); ++n) {
            NodeThread& node = *nodes[kNodes[n]];
            const std::optional<Image> shown = node.shownAfter(refresh);
            ASSERT_TRUE(shown.has_value()) << kNodes[n] << " showed no refresh " << refresh;
            EXPECT_EQ(node.shownFrame(), report.frame);
            ASSERT_EQ(shown->width, expected.width);
            ASSERT_EQ(shown->height, expected.height);
            // Its screens' pixels; the rest of its image holds only the tiles routed to it.
            size_t compared = 0, differing = 0;
            for (const auto& screen : routing.needs(n)) {
                const PixelRect& r = screen[0];
                for (int y = r.y; y < r.y + r.height; ++y)
                    for (int x = r.x; x < r.x + r.width; ++x) {
                        const size_t i = (size_t(y) * size_t(expected.width) + size_t(x)) * 3;
                        ++compared;
                        differing += shown->rgb[i] != expected.rgb[i] || shown->rgb[i + 1] != expected.rgb[i + 1] ||
                                     shown->rgb[i + 2] != expected.rgb[i + 2];
                    }
            }
            EXPECT_GT(compared, size_t(wall.width * wall.height / 3));
            EXPECT_EQ(differing, 0u) << kNodes[n] << ": " << differing << " of " << compared << " screen pixels differ";
        }
        ASSERT_TRUE(nodesAnswered(*master, refresh, answers)) << "both nodes answer every refresh";
    }
    for (const NodeRefreshDelay& d : answers) {
        EXPECT_GE(d.milliseconds, 0.0);
        EXPECT_LT(d.milliseconds, 10000.0);
    }

    // A pose for two views of a one-view frame: skipped and counted on every node, not shown.
    master->presentPose(std::vector<CameraDesc>{target, target});
    for (const auto& [name, node] : nodes) {
        for (int i = 0; i < 2000 && node->counters().skippedPoses.load() == 0; ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        EXPECT_EQ(node->counters().skippedPoses.load(), 1u) << name;
        EXPECT_EQ(node->counters().refreshes.load(), 2u) << name;
    }
    master.reset();  // its goodbye ends the nodes and the clients
}

// A node whose warp takes longer than the refreshes come: the poses that queued behind it are
// superseded by the newest, which it shows next; it never works through a queue of old ones.
TEST(NodeReprojection, ASlowNodeShowsTheNewestPoseNotAQueueOfOldOnes) {
    const std::string text = fileBytes(test::sourceDir() / "configs/wall/two-nodes-2x2.toml");
    const WallConfig wall = parseWallConfig(text, "two-node wall");
    SceneDesc scene = test::demoScene(wall.width / 4, wall.height / 4);
    test::ClientThreads clients;
    ClusterSettings cs;
    cs.async = false;
    cs.depth = true;
    cs.displayNodes = displayNodeSettings(wall, text, {-1}, true);
    auto master = std::make_unique<Master>(scene, cs);
    NodeThread slow(master->endpoint(), "left", 400), quick(master->endpoint(), "right");
    ASSERT_TRUE(master->waitForDisplayNodes(20000));
    clients.start(test::localClient(master->endpoint()));
    ASSERT_TRUE(master->waitForClients(1, 20000));
    FrameView view;
    view.camera = scene.cameras.front();
    master->setViews({view});
    FrameReport report;
    master->renderViews(&report);
    ASSERT_TRUE(master->waitForSwap(report.frame, 10000));

    for (uint32_t i = 1; i <= 6; ++i) {
        CameraDesc moved = view.camera;
        moved.position.x += 0.001f * float(i);
        master->presentPose(std::vector<CameraDesc>{moved});
        std::this_thread::sleep_for(std::chrono::milliseconds(25));  // each is sent before the next (else the newest wins there already)
    }
    // The refreshes sent: the quick node answers every one; the newest is the last it answered.
    uint32_t sent = 0;
    for (int i = 0; i < 400; ++i) {
        for (const NodeRefreshDelay& d : master->takeNodeRefreshes())
            if (d.node == "right") sent = std::max(sent, d.refresh);
        if (sent > 0 && quick.counters().refreshes.load() == sent) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_GE(sent, 3u) << "poses 25 ms apart are sent one by one";
    ASSERT_TRUE(slow.shownAfter(sent).has_value()) << "the slow node shows the newest pose";
    const uint64_t shown = slow.counters().refreshes.load(), superseded = slow.counters().supersededPoses.load();
    EXPECT_LT(shown, sent) << "it did not warp every queued pose";
    EXPECT_GE(superseded, 1u);
    EXPECT_EQ(shown + superseded, sent) << "every pose shown or superseded, none lost otherwise";
    EXPECT_EQ(slow.counters().skippedPoses.load(), 0u);
    master.reset();
}

TEST(NodeReprojection, APoseNeedsAReprojectingWallAndOneCameraPerView) {
    const std::string text = fileBytes(test::sourceDir() / "configs/wall/two-nodes-2x2.toml");
    const WallConfig wall = parseWallConfig(text, "two-node wall");
    const SceneDesc scene = test::demoScene(wall.width, wall.height);
    ClusterSettings cs;
    cs.localClients = 0;
    cs.displayNodes = displayNodeSettings(wall, text, {-1});
    {
        Master plain(scene, cs);
        EXPECT_THROW(plain.presentPose(std::vector<CameraDesc>{scene.cameras.front()}), std::logic_error);
    }
    cs.displayNodes = displayNodeSettings(wall, text, {-1}, true);
    Master m(scene, cs);
    EXPECT_THROW(m.presentPose(std::vector<CameraDesc>{}), std::invalid_argument);
    EXPECT_THROW(m.presentPose(std::vector<CameraDesc>(65, scene.cameras.front())), std::invalid_argument);
}

// The ring of tiles around a node's screens: a re-projecting wall routes each node the tiles
// within one tile of what its screens show, a plain one only those it shows.
TEST(NodeReprojection, AReprojectingNodeAlsoGetsTheRingOfTilesAroundItsScreens) {
    const std::string text = fileBytes(test::sourceDir() / "configs/wall/two-nodes-2x2.toml");
    const WallConfig wall = parseWallConfig(text, "two-node wall");
    const int tile = 32;
    FrameView whole;
    const std::vector<uint64_t> plain = displayNodeSettings(wall, text, {-1}).routes(wall.width, wall.height, tile, {whole});
    const std::vector<uint64_t> ringed = displayNodeSettings(wall, text, {-1}, true).routes(wall.width, wall.height, tile, {whole});
    ASSERT_EQ(plain.size(), ringed.size());
    const TileRouting routing(wall, wall.width, wall.height);
    const std::vector<TileRect> tiles = makeTiles(wall.width, wall.height, tile);
    size_t added = 0;
    for (size_t t = 0; t < tiles.size(); ++t) {
        const TileRect& r = tiles[t];
        EXPECT_EQ(plain[t] & ~ringed[t], 0u) << "the ring only adds";
        EXPECT_EQ(ringed[t], routing.route(r.x0 - tile, r.y0 - tile, r.x1 + tile, r.y1 + tile, 0)) << "tile " << t;
        added += size_t(std::popcount(ringed[t]) - std::popcount(plain[t]));
    }
    // The left column's ring reaches one tile into the right column and back: a few tile columns more.
    EXPECT_GT(added, 0u);
    EXPECT_LE(added, size_t(4 * ((wall.height + tile - 1) / tile)));
}

}  // namespace
}  // namespace rtwall
