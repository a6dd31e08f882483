// Issue 16, "the master never freezes", and issue 15's stuck render thread: each test replays a
// scenario of the reports (real processes or threads over loopback), bounded in time, and is
// named after what it guards.
#include "child_process.h"
#include "fake_master.h"
#include "local_cluster.h"
#include "protocol.h"
#include "security.h"
#include "test_util.h"
#include "../cli_util.h"

#include <rtwall/cluster.h>
#include <rtwall/cluster_testing.h>

#include <zmq.hpp>

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <chrono>
#include <future>
#include <memory>
#include <thread>

namespace rtwall {
namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

SceneDesc demoScene(int width, int height) { return test::quickDemo(width, height, 8); }

// Every client of `cluster` joined, frame 1 one machine's (`expected`), and frame 2, in which a
// render thread gets stuck, within 10 s and one machine's too. Fatal failures: call it in
// ASSERT_NO_FATAL_FAILURE.
void expectFrame2PassesTheStuckThread(test::StoppableCluster& cluster, const Image& expected) {
    ASSERT_TRUE(cluster.ready());
    ASSERT_EQ(cluster.master->renderFrame().rgb, expected.rgb);
    const auto t0 = Clock::now();
    const auto img = cluster.frameWithin(20);
    ASSERT_TRUE(img) << "frame 2 waited for the stuck thread";
    EXPECT_LT(since(t0), 10.0);
    EXPECT_EQ(img->rgb, expected.rgb);
}

// A client whose first tile of frame 2 or later does not return for 30 s (fault injection).
ClientSettings stuckFromFrame2() {
    ClientSettings c;
    c.faults = std::make_shared<const ClientFaults>(ClientFaults{.stallMs = 30000, .stallFrame = 2});
    return c;
}

// A run config on the demo scene at 160x120: `clients` local clients, `frames` frames.
std::filesystem::path runConfig(const std::filesystem::path& dir, int clients, int frames, const std::string& cluster = {}) {
    return test::writeFile(dir / "run.toml",
                           "scene = \"" + (test::sourceDir() / "configs/demo.toml").string() + "\"\ncamera = \"main\"\n"
                           "[image]\nwidth = 160\nheight = 120\n"
                           "[cluster]\nclients = " + std::to_string(clients) + "\nthreads = 1\n" + cluster +
                           "[run]\nframes = " + std::to_string(frames) + "\nwrite_every = 0\norbit = 1.0\n");
}

// Issue 16, item 1: a peer sends [b'x', b'y'] twenty times, 50 ms apart, to `rtwall run` with one
// local client, then 200 times at once. The loop that threw away the extra frames tested the
// first frame's flag, so it read the socket empty, and the client's results behind it were lost
// for good.
TEST(Issue16, AMultiPartMessageFromAnyPeerDoesNotFreezeTheMaster) {
    const auto dir = test::scratchDir();
    test::ChildProcess run({RTWALL_EXE, "run", runConfig(dir, 1, 150).string(), "--headless"});
    const auto endpoint = run.waitFor("rtwall master at (tcp://[0-9.]+:[0-9]+)", 60000);
    ASSERT_TRUE(endpoint) << run.output();
    ASSERT_TRUE(run.waitFor("frame 10:", 60000)) << run.output();
    zmq::context_t ctx;
    zmq::socket_t peer(ctx, zmq::socket_type::dealer);
    peer.set(zmq::sockopt::linger, 1000);
    peer.connect(*endpoint);
    for (int i = 0; i < 20; ++i) {
        peer.send(zmq::str_buffer("x"), zmq::send_flags::sndmore);
        peer.send(zmq::str_buffer("y"));
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    // And the full attack: 200 more at once, so that the clients' messages queue behind them.
    for (int i = 0; i < 200; ++i) {
        peer.send(zmq::str_buffer("x"), zmq::send_flags::sndmore);
        peer.send(zmq::str_buffer("y"));
    }
    const auto status = run.wait(90000);
    ASSERT_TRUE(status) << "the master froze:\n" << run.output();
    EXPECT_EQ(*status, 0) << run.output();
    EXPECT_NE(run.output().find("150 frames"), std::string::npos) << run.output();
    // Item 5: the run says what it dropped, and the log names the peer. Nothing else was lost:
    // with the old loop the results read behind the attack were gone (and then, with the lost
    // results recovered, handed out again).
    EXPECT_NE(run.output().find("master: dropped 220 messages (220 malformed)\n"), std::string::npos) << run.output();
    EXPECT_NE(run.output().find("dropped a malformed message from 127.0.0.1"), std::string::npos) << run.output();
}

// Item 2: a result lost on its way (here every 5th) with one client: the client's idle report
// releases the hand-outs it no longer holds and they go back to it. Before, an overdue tile went
// only to another client, and with one client the frame waited for ever.
TEST(Issue16, ALostTileResultIsRecoveredWithOneClient) {
    const SceneDesc desc = demoScene(96, 72);
    const Image expected = test::singleMachine(desc, 0);
    test::StoppableCluster cluster(desc, test::inStep());
    ClientSettings c;
    c.faults = std::make_shared<const ClientFaults>(ClientFaults{.dropEveryNthResult = 5});
    cluster.start(c);
    ASSERT_TRUE(cluster.ready());
    for (int f = 0; f < 3; ++f) {
        const auto img = cluster.frameWithin(30);
        ASSERT_TRUE(img) << "frame " << f << " never completed";
        EXPECT_EQ(img->rgb, expected.rgb) << "frame " << f;
    }
    EXPECT_GT(cluster.master->counters().lostHandOuts, 0u) << describeCounters(cluster.master->counters());
    cluster.master.reset();  // its goodbye ends the client
    EXPECT_EQ(cluster.clients[0].get(), 0);
}

// Item 3: `rtwall render MESH --clients 3` with one client frozen (SIGSTOP) and one killed as soon
// as they start. It waited 60 s for three clients, although one lived; now it goes on with the
// one that joined, and writes the single machine's bytes.
TEST(Issue16, AFrameCompletesWhenOneOfThreeClientsSurvives) {
    const auto dir = test::scratchDir();
    const std::string mesh = (test::sourceDir() / "configs/meshes/knot.ply").string();
    const std::string size = " --width 1600 --height 1200";
    const test::CliResult one = test::runCli(RTWALL_EXE, "render " + mesh + " --out " + (dir / "one.png").string() + size);
    ASSERT_EQ(one.status, 0) << one.output;
    const auto t0 = Clock::now();
    test::ChildProcess render({RTWALL_EXE, "render", mesh, "--out", (dir / "three.png").string(), "--width", "1600",
                               "--height", "1200", "--clients", "3"});
    std::vector<pid_t> kids;
    while (kids.size() < 3 && since(t0) < 30) kids = test::childrenOf(render.pid());
    ASSERT_EQ(kids.size(), 3u) << render.output();
    kill(kids[0], SIGSTOP);
    kill(kids[2], SIGKILL);
    const auto status = render.wait(120000);
    kill(kids[0], SIGCONT);
    ASSERT_TRUE(status) << "still waiting after 120 s:\n" << render.output();
    EXPECT_EQ(*status, 0) << render.output();
    EXPECT_LT(since(t0), 45.0) << "it waited for the clients that could not come";
    EXPECT_NE(render.output().find("of 3 local render clients joined"), std::string::npos) << render.output();
    std::ifstream a(dir / "one.png", std::ios::binary), b(dir / "three.png", std::ios::binary);
    const std::string bytesA((std::istreambuf_iterator<char>(a)), {}), bytesB((std::istreambuf_iterator<char>(b)), {});
    EXPECT_FALSE(bytesA.empty());
    EXPECT_EQ(bytesA, bytesB) << "the survivor's frame is one machine's, byte for byte";
}

// Item 3, the other half: a live client whose queue is full for a moment (it reads nothing for
// a while: a busy PC) is not dropped; only a queue full for longer than the timeout is death.
// The peer here completes the handshake, proves the state and asks for every mesh (some 10 MB,
// more than the sockets' buffers hold), then stops reading for 1.5 s (its timeout is 10 s) while
// the application sends updates.
TEST(Issue16, ALiveClientWhoseQueueIsFullForAMomentStays) {
    using namespace cluster;
    SceneDesc desc = builtinScene("knots", 400'000);
    desc.settings.width = 64;
    desc.settings.height = 48;
    desc.settings.tileSize = 16;
    ClusterSettings cs = test::inStep();
    cs.timeoutMs = 10000;
    cs.highWaterMark = 1;
    test::LocalCluster cluster(desc, cs, 1);
    Master& master = *cluster.master;
    ASSERT_TRUE(cluster.ready());

    zmq::context_t ctx;
    zmq::socket_t peer(ctx, zmq::socket_type::dealer);
    peer.set(zmq::sockopt::linger, 0);
    peer.set(zmq::sockopt::rcvhwm, 1);
    peer.set(zmq::sockopt::rcvbuf, 4096);
    peer.connect(master.endpoint());
    Header h;
    peer.send(zmq::buffer(encodeMessage(h, Hello{kProtocolVersion, 1, "busy"})));
    std::optional<SceneSnapshot> snap;
    for (auto end = Clock::now() + std::chrono::seconds(10); !snap && Clock::now() < end;) {
        zmq::message_t msg;
        if (!peer.recv(msg, zmq::recv_flags::dontwait)) {
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            continue;
        }
        const auto* p = static_cast<const uint8_t*>(msg.data());
        const Header in = decodeHeader(p, msg.size());
        h.session = in.session;
        if (in.type == MsgType::SceneSnapshot) snap = decodeMessage<SceneSnapshot>(p, msg.size());
    }
    ASSERT_TRUE(snap);
    peer.send(zmq::buffer(encodeMessage(h, Ready{snap->updateSeq, stateHash(*snap)})));
    ASSERT_TRUE(master.waitForClients(2, 10000)) << "it proved its state";

    const uint64_t failed0 = master.counters().failedSends;
    for (const MeshRef& m : snap->meshes) peer.send(zmq::buffer(encodeMessage(h, MeshRequest{m.hash})));
    const auto quietUntil = Clock::now() + std::chrono::milliseconds(1500);
    for (int i = 0; Clock::now() < quietUntil; ++i) {  // it reads nothing, but says it is there
        peer.send(zmq::buffer(encodeMessage(h, Heartbeat{})), zmq::send_flags::dontwait);
        desc.lights[0].intensity = 10.0f + float(i % 50);
        master.setLight(0, desc.lights[0]);
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_GT(master.counters().failedSends, failed0) << "its queue never filled: the scenario did not happen; "
                                                      << describeCounters(master.counters());
    // It reads again (all of it) and goes on with heartbeats.
    for (auto end = Clock::now() + std::chrono::milliseconds(1500); Clock::now() < end;) {
        zmq::message_t msg;
        while (peer.recv(msg, zmq::recv_flags::dontwait)) {
        }
        peer.send(zmq::buffer(encodeMessage(h, Heartbeat{})), zmq::send_flags::dontwait);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    EXPECT_EQ(master.counters().clientsDropped, 0u) << describeCounters(master.counters());
    EXPECT_EQ(master.connectedClients(), 2);
    EXPECT_EQ(master.renderFrame().rgb, test::singleMachine(desc, 0).rgb);
}

// Item 4: `rtwall run` whose clients are frozen (a frame that cannot finish; their timeout is a
// minute, so they stay connected) must end on SIGINT or SIGTERM within a few seconds, say so, exit
// non-zero and leave no client process behind. Before, the stop flag was read only between frames.
class StuckRun : public ::testing::TestWithParam<int> {};

TEST_P(StuckRun, EndsOnTheSignalWithinSecondsAndLeavesNoClient) {
    const auto dir = test::scratchDir();
    test::ChildProcess run({RTWALL_EXE, "run", runConfig(dir, 2, 100000, "timeout_ms = 60000\n").string(), "--headless"});
    ASSERT_TRUE(run.waitFor("frame 10:", 60000)) << run.output();
    const std::vector<pid_t> kids = test::childrenOf(run.pid());
    ASSERT_EQ(kids.size(), 2u);
    for (pid_t k : kids) kill(k, SIGSTOP);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the frame in flight is stuck now
    const auto t0 = Clock::now();
    run.signal(GetParam());
    const auto status = run.wait(15000);
    for (pid_t k : kids) kill(k, SIGCONT);
    ASSERT_TRUE(status) << "it ignored the signal:\n" << run.output();
    EXPECT_LT(since(t0), 5.0);
    EXPECT_EQ(*status, 130) << run.output();
    EXPECT_NE(run.output().find("interrupted"), std::string::npos) << run.output();
    EXPECT_NE(run.output().find("master: "), std::string::npos) << "the counters, however the run ends";
    for (pid_t k : kids) EXPECT_FALSE(test::alive(k)) << "client " << k << " left behind";
}

INSTANTIATE_TEST_SUITE_P(Issue16, StuckRun, ::testing::Values(SIGINT, SIGTERM),
                         [](const ::testing::TestParamInfo<int>& p) { return std::string(p.param == SIGINT ? "SIGINT" : "SIGTERM"); });

// Item 6: with `key` and `client_keys`, local clients get a key pair of their own, made for the
// session (a private directory, the secret key mode 0600, removed with the master).
TEST(Issue16, LocalClientsOfAMasterWithKeysGetASessionKeyPair) {
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "master");
    writeNewKeyPair(dir / "node01");
    const auto cfg = runConfig(dir, 1, 3, "key = \"master.key\"\nclient_keys = [\"node01.pub\"]\n");
    const test::CliResult r = test::runCli(RTWALL_EXE, "run " + cfg.string() + " --headless", 120);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("3 frames"), std::string::npos) << r.output;

    ClusterSettings cs;
    cs.keyFile = dir / "master.key";
    cs.clientKeys = {dir / "node01.pub"};
    cs.localClients = 1;
    std::filesystem::path keyDir;
    {
        Master master(demoScene(32, 24), cs);
        const std::vector<std::string> args = master.localClientArgs();
        ASSERT_EQ(args.size(), 4u);
        EXPECT_EQ(args[0], "--key");
        EXPECT_EQ(args[2], "--server-key");
        keyDir = std::filesystem::path(args[1]).parent_path();
        using std::filesystem::perms;
        EXPECT_EQ(std::filesystem::status(keyDir).permissions() & perms::all, perms::owner_all);
        EXPECT_EQ(std::filesystem::status(args[1]).permissions() & perms::all, perms::owner_read | perms::owner_write);
        EXPECT_EQ(cluster::readPublicKey(args[3]), cluster::readKeyPair(dir / "master.key").publicKey);
    }
    EXPECT_FALSE(std::filesystem::exists(keyDir)) << "removed with the master";
    cs.keyFile.clear();
    EXPECT_TRUE(Master(demoScene(32, 24), cs).localClientArgs().empty()) << "no keys, no key arguments";
    // A wall on display nodes that the session starts on this PC: the nodes need the session's
    // key pair even when every render client is remote.
    cs.keyFile = dir / "master.key";
    cs.localClients = 0;
    EXPECT_TRUE(Master(demoScene(32, 24), cs).localClientArgs().empty()) << "no local process, no session key pair";
    cs.displayNodes.names = {"left", "right"};
    EXPECT_EQ(Master(demoScene(32, 24), cs).localClientArgs().size(), 4u) << "display nodes get the session key pair";
}

// Item 6: a refused handshake is said on both sides: the client says the master refused its key
// (not "no master"), the master counts and logs the refusal.
TEST(Issue16, ARefusedKeyIsSaidOnBothSides) {
    const auto dir = test::scratchDir();
    for (const char* name : {"master", "good", "stranger"}) writeNewKeyPair(dir / name);
    ClusterSettings cs;
    cs.keyFile = dir / "master.key";
    cs.clientKeys = {dir / "good.pub"};
    Master master(demoScene(32, 24), cs);
    const test::CliResult r = test::runCli(RTWALL_EXE, "client --connect " + master.endpoint() + " --key " +
                                                           (dir / "stranger.key").string() + " --server-key " +
                                                           (dir / "master.pub").string() + " --exit-after-idle 2000", 60);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("the master refused this client's key"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("giving up (the master refused"), std::string::npos) << r.output;
    EXPECT_GE(master.counters().refused, 1u);
    // A client without keys at a master with keys: told that the two disagree on security.
    const test::CliResult plain = test::runCli(RTWALL_EXE, "client --connect " + master.endpoint() + " --exit-after-idle 1500", 60);
    EXPECT_NE(plain.output.find("disagree on security"), std::string::npos) << plain.output;
    EXPECT_GE(master.counters().failedHandshakes, 1u);
}

// Item 7: `rtwall keys keys/master` where keys/ does not exist, as docs/security.md shows it.
TEST(Issue16, KeysMakesItsDirectory) {
    const auto dir = test::scratchDir();
    const auto stem = dir / "new" / "keys" / "master";
    const test::CliResult r = test::runCli(RTWALL_EXE, "keys " + stem.string());
    EXPECT_EQ(r.status, 0) << r.output;
    using std::filesystem::perms;
    EXPECT_EQ(std::filesystem::status(stem.string() + ".key").permissions() & perms::all, perms::owner_read | perms::owner_write);
    EXPECT_EQ(std::filesystem::status(stem.parent_path()).permissions() & perms::all, perms::owner_all);
    EXPECT_NO_THROW(cluster::readKeyPair(stem.string() + ".key"));
    EXPECT_NO_THROW(cluster::readPublicKey(stem.string() + ".pub"));
}

// Item 4, in the library: renderFrame gives up (Cancelled) within 100 ms of the stop flag when its
// frame cannot finish (the only client's only render thread is stuck).
TEST(Issue16, RenderFrameGivesUpWhenTheStopFlagIsSet) {
    const SceneDesc desc = demoScene(64, 48);
    test::StoppableCluster cluster(desc, test::inStep());
    Master& master = *cluster.master;
    ClientSettings c = stuckFromFrame2();
    cluster.start(c);
    ASSERT_TRUE(cluster.ready());
    master.renderFrame();
    auto frame = std::async(std::launch::async, [&] { return master.renderFrame(); });
    EXPECT_EQ(frame.wait_for(std::chrono::milliseconds(1500)), std::future_status::timeout) << "the frame should be stuck";
    const auto t0 = Clock::now();
    cluster.stop = true;
    ASSERT_EQ(frame.wait_for(std::chrono::seconds(5)), std::future_status::ready);
    EXPECT_THROW(frame.get(), Cancelled);
    EXPECT_LT(since(t0), 1.0);
}

// Issue 15: a render thread that never returns. The client reports the tile (frame and tile) far
// past its expected time, the master counts it and hands the tile to the other client; the frame
// completes long before the stall ends, bit-identical.
TEST(Issue15, AStuckRenderThreadIsReportedAndItsTileRenderedByAnotherClient) {
    SceneDesc desc = demoScene(96, 72);
    const Image expected = test::singleMachine(desc, 0);
    ClusterSettings cs = test::inStep();
    cs.timeoutMs = 1000;
    cs.heartbeatMs = 100;
    test::StoppableCluster cluster(desc, cs);
    Master& master = *cluster.master;
    auto counters = std::make_shared<ClientCounters>();
    ClientSettings stuck = stuckFromFrame2();
    stuck.minStallMs = 300;
    stuck.counters = counters;
    ClientSettings healthy;
    healthy.minStallMs = stuck.minStallMs;
    cluster.start(stuck);
    cluster.start(healthy);
    ASSERT_NO_FATAL_FAILURE(expectFrame2PassesTheStuckThread(cluster, expected));
    // Reported once, after 300 ms, whether a straggler re-issue finished the tile first or not.
    for (int i = 0; i < 500 && master.counters().stalledTiles == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_EQ(counters->stalledTiles.load(), 1u);
    EXPECT_EQ(master.counters().stalledTiles, 1u) << describeCounters(master.counters());
    // The stuck client's network thread does not wait for its render thread: a frame with an
    // update (the scene is locked by the stuck thread) waits on that client, which keeps
    // answering and is not dropped, while the other renders the frame.
    desc.lights[0].intensity *= 2.0f;
    master.setLight(0, desc.lights[0]);
    const auto after = cluster.frameWithin(20);
    ASSERT_TRUE(after);
    EXPECT_EQ(after->rgb, test::singleMachine(desc, 0).rgb);
    std::this_thread::sleep_for(std::chrono::milliseconds(2 * cs.timeoutMs));
    EXPECT_EQ(master.connectedClients(), 2) << "a client with a stuck render thread still answers";
}

// Issue 15, the only client: its other render thread takes the stuck tile.
TEST(Issue15, TheOnlyClientRendersItsStuckTileOnItsOtherThread) {
    const SceneDesc desc = demoScene(96, 72);
    const Image expected = test::singleMachine(desc, 0);
    test::StoppableCluster cluster(desc, test::inStep());
    Master& master = *cluster.master;
    ClientSettings c = stuckFromFrame2();
    c.minStallMs = 300;
    cluster.start(c, 2);
    ASSERT_NO_FATAL_FAILURE(expectFrame2PassesTheStuckThread(cluster, expected));
    EXPECT_EQ(master.counters().stalledTiles, 1u);
}

TEST(Issue16, DescribeCountersNamesEveryKind) {
    MasterCounters c;
    EXPECT_EQ(describeCounters(c), "nothing dropped, refused or lost");
    c.malformed = 20;
    c.unknownPeer = 3;
    c.refused = 2;
    c.failedSends = 1;
    c.lostHandOuts = 4;
    EXPECT_EQ(describeCounters(c), "dropped 23 messages (20 malformed, 3 from unknown peers), 2 handshakes refused, 1 sends "
                                   "failed, 4 lost tiles handed out again");
    EXPECT_EQ(c.dropped(), 23u);
}

}  // namespace
}  // namespace rtwall
