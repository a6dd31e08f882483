// The re-projecting wall end to end in one process (loopback, client threads; issue 27): a
// tracked wall re-projects by default, and with a still head it shows the very bytes of the
// same wall without re-projection, on one, two and three clients, on a flat stereo wall and a
// CAVE; while the cluster renders a slow frame the wall keeps presenting, each presentation with
// the head pose read just before it; the wall config's `reproject` and the run's override.
#include "display_test_util.h"
#include "session_tracker.h"
#include "test_util.h"

#include <rtwall/cluster_testing.h>
#include <rtwall/wall.h>

#include <chrono>
#include <map>
#include <set>
#include <cmath>
#include <thread>

namespace rtwall {
namespace {

const std::string kScene = test::sceneText("tracked_boxes");

// The shipped 2x2 stereo wall's geometry at a few pixels per screen, tracked (the room is the
// wall's coordinates in millimetres), the head at `viewer` until a datagram says otherwise.
std::string trackedWall(const std::string& extra = "") {
    return R"([wall]
vsync = false
)" + extra + R"(
[grid]
columns = 2
rows = 2
screen_width = 24
screen_height = 16
[stereo]
mode = "passive"
eye_separation = 0.065
viewer = [0.0, 0.2, 2.5]
lower_left = [-1.6, -1.2, 0.0]
lower_right = [1.6, -1.2, 0.0]
upper_left = [-1.6, 1.2, 0.0]
[headless]
write_every = 0
[tracking]
source = "dtrack://127.0.0.1:0"
room_scale = 0.001
timeout_ms = 60000
)";
}

RunConfig config(const std::filesystem::path& dir, const std::string& wallText, int clients) {
    RunConfig c = steppedRunConfig(dir, clients);
    c.scene = test::writeFile(dir / "scene.toml", kScene).string();
    c.wall = test::writeFile(dir / "wall.toml", wallText);
    c.cluster.async = false;
    return c;
}

// A head at wall position p (metres), facing the wall, as DTrack sends it (millimetres); waits
// until the session's tracker has it.
void sendHead(WallSession& s, Float3 p, uint64_t frame) { test::sendHeadAt(s, p.x * 1e3, p.y * 1e3, p.z * 1e3, frame); }

TEST(ReprojectSession, ATrackedWallReprojectsByDefaultAndTheOverrideWins) {
    const auto dir = test::scratchDir();
    EXPECT_TRUE(parseWallConfig(trackedWall(), "w.toml").reprojects());
    EXPECT_FALSE(parseWallConfig(trackedWall("reproject = \"off\""), "w.toml").reprojects());
    {
        WallSession on(config(dir, trackedWall(), 1));
        EXPECT_TRUE(on.reprojecting());
    }
    RunConfig c = config(dir, trackedWall(), 1);
    c.reproject = false;
    WallSession off(c);
    EXPECT_FALSE(off.reprojecting());
}

// A still head: every frame shown re-projected is the frame as rendered, byte for byte, and
// the same bytes as the wall without re-projection, whichever clients rendered which tiles.
TEST(ReprojectSession, AStillHeadShowsTheUnwarpedImagesOnOneTwoAndThreeClients) {
    const auto dir = test::scratchDir();
    const Float3 head{0.1f, 0.25f, 2.2f};
    std::vector<WallFrame> want;
    {
        RunConfig c = config(dir, trackedWall(), 2);
        c.reproject = false;
        WallSession plain(c);
        sendHead(plain, head, 1);
        for (int i = 0; i < 2; ++i) {
            ASSERT_TRUE(plain.step());
            want.push_back(plain.lastFrame());
        }
    }
    ASSERT_FALSE(want[0].left.rgb.empty());
    ASSERT_FALSE(want[0].right.rgb.empty());
    for (int clients : {1, 2, 3}) {
        WallSession s(config(dir, trackedWall(), clients));
        ASSERT_TRUE(s.reprojecting());
        sendHead(s, head, 1);
        for (int i = 0; i < 2; ++i) {
            ASSERT_TRUE(s.step());
            EXPECT_EQ(s.lastFrame().left.rgb, want[size_t(i)].left.rgb) << clients << " clients, frame " << i;
            EXPECT_EQ(s.lastFrame().right.rgb, want[size_t(i)].right.rgb) << clients << " clients, frame " << i;
        }
        const std::vector<Presentation> shown = s.takePresentations();
        ASSERT_FALSE(shown.empty());
        for (const Presentation& p : shown) EXPECT_EQ(p.head.position.x, head.x);
    }
}

// Tiles that take 60 ms each: while the frame renders the wall presents at its refresh, each
// time with the pose read just before; a head that moves during the frame is shown where it
// is at once, by warping the frame before, not when the frame it moved in is done.
TEST(ReprojectSession, TheWallKeepsPresentingTheNewestHeadWhileTheClusterRenders) {
    const auto dir = test::scratchDir();
    RunConfig c = config(dir, trackedWall("refresh_hz = 100"), 1);
    auto faults = std::make_shared<ClientFaults>();
    faults->extraTileDelayMs = 60;
    c.clientFaults = faults;
    WallSession s(c);
    ASSERT_TRUE(s.reprojecting());
    sendHead(s, {0.0f, 0.2f, 2.5f}, 1);
    ASSERT_TRUE(s.step());  // the first frame: nothing to warp while it renders
    const std::vector<Presentation> first = s.takePresentations();
    ASSERT_EQ(first.size(), 1u);
    const uint32_t firstFrame = first[0].frame;

    const Float3 moved{0.3f, 0.2f, 2.4f};
    std::thread mover([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(40));
        sendHead(s, moved, 2);
    });
    ASSERT_TRUE(s.step());
    mover.join();
    const std::vector<Presentation> shown = s.takePresentations();
    // The frame's tiles take at least 60 ms on the one client: several refreshes of 10 ms.
    ASSERT_GE(shown.size(), 3u);
    size_t movedRefreshes = 0;
    for (size_t i = 0; i + 1 < shown.size(); ++i) {
        EXPECT_EQ(shown[i].frame, firstFrame) << "a refresh shows the newest complete frame";
        EXPECT_TRUE(shown[i].warped);
        EXPECT_LE(shown[i].posed, shown[i].at);
        if (i > 0) {
            EXPECT_GE(shown[i].trackerPackets, shown[i - 1].trackerPackets);
        }
        if (shown[i].trackerPackets == 2) {
            ++movedRefreshes;
            EXPECT_FLOAT_EQ(shown[i].head.position.x, moved.x);
        }
    }
    EXPECT_GT(movedRefreshes, 0u) << "the head moved 40 ms into a frame of 60 ms and more: a refresh before its end shows it";
    EXPECT_GT(shown.back().frame, firstFrame) << "the step ends by showing its new frame";
    EXPECT_EQ(shown.back().trackerPackets, 2u);
    EXPECT_FLOAT_EQ(shown.back().head.position.x, moved.x) << "the new frame, rendered for the old head, is shown for the new one";
}

// Display nodes re-project their own screens (issue 27): the master sends each refresh's pose
// and every node warps the newest released frame to it. With a still head every screen a node
// shows at any refresh is that screen of the same wall without re-projection, byte for byte, and
// both nodes answer the refreshes.
size_t countFiles(const std::filesystem::path& dir) {
    std::error_code ec;
    size_t n = 0;
    for (auto it = std::filesystem::directory_iterator(dir, ec); !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) ++n;
    return n;
}

TEST(ReprojectSession, AStillHeadShowsTheUnwarpedImagesOnDisplayNodes) {
    const auto dir = test::scratchDir();
    const Float3 head{0.1f, 0.25f, 2.2f};
    std::string wall = trackedWall("refresh_hz = 200") + "[[node]]\nname = \"a\"\ncolumns = [0, 0]\n[[node]]\nname = \"b\"\ncolumns = [1, 1]\n";
    wall.replace(wall.find("write_every = 0"), 15, "write_every = 1");
    for (bool on : {false, true}) {
        SCOPED_TRACE(on ? "re-projecting" : "not re-projecting");
        const auto run = dir / (on ? "on" : "off");
        std::filesystem::create_directories(run);
        RunConfig c = config(run, wall, 2);
        c.out = run / "out";
        c.reproject = on;
        // No node is left out of a frame on a loaded machine (the left-out overlay would differ).
        c.cluster.displayNodes.stallSeconds = 60;
        WallSession s(c);
        ASSERT_EQ(s.reprojecting(), on);
        sendHead(s, head, 1);
        // Steps (bounded) until each node wrote two frames' screens and, re-projecting, answered
        // a pose (poses go out only with the refreshes of steps, after the first release).
        std::set<std::string> answered;
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        for (int i = 0; i < 4 || (std::chrono::steady_clock::now() < until &&
                                  (countFiles(run / "out" / "a") < 8 || countFiles(run / "out" / "b") < 8 || (on && answered.size() < 2)));
             ++i) {
            ASSERT_TRUE(s.step());
            for (const NodeRefreshDelay& d : s.takeNodeRefreshes()) answered.insert(d.node);
        }
        if (on) {
            EXPECT_EQ(answered, (std::set<std::string>{"a", "b"})) << "both nodes answer the refreshes";
        } else {
            EXPECT_TRUE(answered.empty());
        }
        EXPECT_TRUE(s.lastFrame().left.rgb.empty()) << "the master holds no pixels";
    }
    // The scene is still and renders deterministically: every frame of a screen is the same
    // image, in the plain run (checked) and, warped to the still head, re-projecting. (Which
    // frames a node shows under load differs from run to run: a frame can be released without it.)
    for (const char* node : {"a", "b"}) {
        std::map<std::string, std::vector<uint8_t>> plain;  // screen (file name after frame_NNNNNN_) -> pixels
        for (const auto& e : std::filesystem::directory_iterator(dir / "off" / "out" / node)) {
            const std::string screen = e.path().filename().string().substr(13);
            std::vector<uint8_t> rgb = readPng(e.path()).rgb;
            const auto [it, fresh] = plain.emplace(screen, rgb);
            if (!fresh) {
                EXPECT_EQ(it->second, rgb) << e.path() << ": a still head's frames are alike";
            }
        }
        EXPECT_EQ(plain.size(), 4u) << node << ": two cells, two eyes";
        size_t files = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir / "on" / "out" / node)) {
            const auto it = plain.find(e.path().filename().string().substr(13));
            ASSERT_NE(it, plain.end()) << e.path();
            EXPECT_EQ(readPng(e.path()).rgb, it->second) << e.path();
            ++files;
        }
        EXPECT_GE(files, 8u) << node << ": its four screens of two frames";
    }
}

TEST(ReprojectSession, TheConfigKeysLoadBackAndRefuseWhatTheyCannotBe) {
    WallConfig w = parseWallConfig(trackedWall("reproject = \"off\"\nreproject_debug = true\nrefresh_hz = 90"), "w.toml");
    EXPECT_EQ(w.reproject, std::optional<bool>(false));
    EXPECT_TRUE(w.reprojectDebug);
    EXPECT_EQ(w.refreshHz, 90.0);
    EXPECT_EQ(parseWallConfig(writeWallConfig(w), "again.toml"), w);
    w.reproject.reset();
    EXPECT_EQ(parseWallConfig(writeWallConfig(w), "again.toml"), w);
    EXPECT_NE(test::wallError(trackedWall("reproject = \"maybe\"")).find("reproject"), std::string::npos);
    EXPECT_NE(test::wallError(trackedWall("reproject = true")).find("reproject"), std::string::npos);
    EXPECT_NE(test::wallError(trackedWall("refresh_hz = 0")).find("refresh_hz"), std::string::npos);
    EXPECT_NE(test::wallError(trackedWall("refresh_hz = nan")).find("refresh_hz"), std::string::npos);
}

}  // namespace
}  // namespace rtwall
