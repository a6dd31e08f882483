// Faults with real client processes (this build's rtwall executable) on loopback: a client
// killed (SIGKILL) or frozen (SIGSTOP) in the middle of a frame. The frame completes,
// bit-identical to a fault-free run; the master notices within its timeout; a frozen client
// that wakes up has its late results dropped, and it rejoins. Every wait is bounded.
#include "test_util.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <future>
#include <thread>

extern char** environ;

namespace rtwall {
namespace {

using Clock = std::chrono::steady_clock;

struct Process {
    pid_t pid = -1;
    // A client process; with a namespace, inside it (`ip netns exec NS rtwall client ...`).
    explicit Process(const std::string& endpoint, const std::string& netns = {}, int exitAfterIdleMs = 8000) {
        std::vector<std::string> args = {RTWALL_EXE, "client", "--connect", endpoint, "--threads", "1",
                                         "--exit-after-idle", std::to_string(exitAfterIdleMs)};
        if (!netns.empty()) args.insert(args.begin(), {"ip", "netns", "exec", netns});
        std::vector<char*> argv;
        for (auto& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        const char* program = netns.empty() ? RTWALL_EXE : "/usr/sbin/ip";
        EXPECT_EQ(posix_spawn(&pid, program, nullptr, nullptr, argv.data(), environ), 0);
    }
    ~Process() {
        if (pid <= 0) return;
        kill(pid, SIGCONT);
        kill(pid, SIGKILL);
        waitpid(pid, nullptr, 0);
    }
};

SceneDesc slowScene() {
    SceneDesc desc = loadSceneFile(test::sourceDir() / "configs/demo.toml");
    desc.settings.width = 160;
    desc.settings.height = 120;
    desc.settings.tileSize = 8;
    desc.settings.supersample = 3;  // a frame takes long enough to be interrupted
    return desc;
}

Image singleMachine(const SceneDesc& desc) {
    const Scene scene(desc);
    return renderFrame(scene, Camera(desc.cameras.front(), desc.settings.width, desc.settings.height), desc.settings);
}

template <class F> bool waitUntil(F&& f, int ms) {
    const auto end = Clock::now() + std::chrono::milliseconds(ms);
    while (Clock::now() < end) {
        if (f()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return f();
}

ClusterSettings faultSettings() {
    ClusterSettings cs;
    cs.async = false;
    cs.heartbeatMs = 50;
    cs.timeoutMs = 400;
    return cs;
}

TEST(Faults, KilledClientMidFrame) {
    const SceneDesc desc = slowScene();
    const Image expected = singleMachine(desc);
    Master master(desc, faultSettings());
    Process a(master.endpoint()), b(master.endpoint());
    ASSERT_TRUE(master.waitForClients(2, 30000));
    master.renderFrame();

    auto frame = std::async(std::launch::async, [&] { return master.renderFrame(); });
    std::this_thread::sleep_for(std::chrono::milliseconds(60));
    const auto killedAt = Clock::now();
    kill(b.pid, SIGKILL);
    ASSERT_TRUE(waitUntil([&] { return master.connectedClients() == 1; }, 5000));
    const double detection = std::chrono::duration<double>(Clock::now() - killedAt).count();
    EXPECT_EQ(frame.get().rgb, expected.rgb) << "the frame completes, bit-identical";
    EXPECT_LT(detection, 0.4 * 3) << "noticed within the heartbeat timeout (plus scheduling slack)";
    EXPECT_EQ(master.renderFrame().rgb, expected.rgb);
}

TEST(Faults, FrozenClientMidFrameThenWakesUp) {
    const SceneDesc desc = slowScene();
    const Image expected = singleMachine(desc);
    Master master(desc, faultSettings());
    Process a(master.endpoint()), b(master.endpoint());
    ASSERT_TRUE(master.waitForClients(2, 30000));
    master.renderFrame();

    auto frame = std::async(std::launch::async, [&] { return master.renderFrame(); });
    std::this_thread::sleep_for(std::chrono::milliseconds(60));
    kill(b.pid, SIGSTOP);
    EXPECT_EQ(frame.get().rgb, expected.rgb) << "its tiles were re-issued or re-queued";
    ASSERT_TRUE(waitUntil([&] { return master.connectedClients() == 1; }, 5000)) << "timed out by heartbeat";
    const uint64_t droppedBefore = master.droppedMessages();
    kill(b.pid, SIGCONT);
    // It wakes up with results of a frame that is gone: dropped and counted, never used.
    EXPECT_TRUE(waitUntil([&] { return master.droppedMessages() > droppedBefore; }, 5000));
    // Then it notices the master ignores it, reconnects and proves its state: back in.
    EXPECT_TRUE(waitUntil([&] { return master.connectedClients() == 2; }, 10000)) << "rejoined";
    FrameReport r;
    EXPECT_EQ(master.renderFrame(&r).rgb, expected.rgb);
    EXPECT_EQ(r.clients.size(), 2u);
}

// A client process dies and is started again (as systemd would): it joins, proves it holds the
// current state (updates made while it was gone included) and renders again within 5 s.
TEST(Faults, RestartedClientContributesAgainWithinFiveSeconds) {
    SceneDesc desc = slowScene();
    Master master(desc, faultSettings());
    Process a(master.endpoint());
    auto b = std::make_unique<Process>(master.endpoint());
    ASSERT_TRUE(master.waitForClients(2, 30000));
    master.renderFrame();
    kill(b->pid, SIGKILL);
    ASSERT_TRUE(waitUntil([&] { return master.connectedClients() == 1; }, 5000));
    b.reset();
    desc.lights[0].intensity = 42.0f;  // changed while it is away
    master.setLight(0, desc.lights[0]);
    master.renderFrame();
    const auto restartedAt = Clock::now();
    b = std::make_unique<Process>(master.endpoint());
    ASSERT_TRUE(waitUntil([&] { return master.connectedClients() == 2; }, 10000));
    FrameReport r;
    const Image img = master.renderFrame(&r);
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - restartedAt).count(), 5.0);
    EXPECT_EQ(img.rgb, singleMachine(desc).rgb);
    ASSERT_EQ(r.clients.size(), 2u);
    EXPECT_GT(std::min(r.clients[0].tiles, r.clients[1].tiles), 0u) << "both contribute";
}

// A client that stops reading (frozen) while the application floods the master with 60,000
// updates: the master must never block on it, the updates are merged instead of queued one by
// one, the frozen client is dropped (heartbeat timeout or full queue) and the healthy one keeps
// rendering the final state.
TEST(Faults, AFloodOfUpdatesWithAFrozenPeerBlocksNothing) {
    SceneDesc desc = slowScene();
    desc.settings.supersample = 1;
    Master master(desc, faultSettings());
    Process a(master.endpoint()), b(master.endpoint());
    ASSERT_TRUE(master.waitForClients(2, 30000));
    master.renderFrame();
    kill(b.pid, SIGSTOP);
    const auto t0 = Clock::now();
    for (int i = 0; i < 60000; ++i) {
        desc.lights[0].intensity = float(10 + i % 100);
        master.setLight(0, desc.lights[0]);
    }
    const double flood = std::chrono::duration<double>(Clock::now() - t0).count();
    EXPECT_LT(flood, 30.0) << "the application was never blocked";
    EXPECT_TRUE(waitUntil([&] { return master.connectedClients() == 1; }, 20000)) << "the frozen client is gone";
    FrameReport r;
    EXPECT_EQ(master.renderFrame(&r).rgb, singleMachine(desc).rgb);
    EXPECT_EQ(r.clients.size(), 1u);
}

// The master goes away (goodbye) and a new one starts on the same port: a client that waits
// for a master forever reconnects with back-off and jitter and renders for the new one.
TEST(Faults, MasterRestart) {
    const SceneDesc desc = slowScene();
    const Image expected = singleMachine(desc);
    auto first = std::make_unique<Master>(desc, faultSettings());
    const std::string endpoint = first->endpoint();
    Process client(endpoint, {}, 0);
    ASSERT_TRUE(first->waitForClients(1, 30000));
    EXPECT_EQ(first->renderFrame().rgb, expected.rgb);
    first.reset();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ClusterSettings cs = faultSettings();
    cs.bind = endpoint;
    Master second(desc, cs);
    const auto t0 = Clock::now();
    ASSERT_TRUE(second.waitForClients(1, 15000)) << "the client came back";
    EXPECT_LT(Clock::now() - t0, std::chrono::seconds(10));
    EXPECT_EQ(second.renderFrame().rgb, expected.rgb);
}

// A namespace with one end of a veth pair: taking the link down cuts the client off without a
// FIN or RST, the case only heartbeats can detect. Needs root (CI runs as root); skipped
// otherwise. Addresses are this test's own, inside its own namespace.
class CutLink : public ::testing::Test {
protected:
    static constexpr const char* kNs = "rtwt-cut";
    void SetUp() override {
        std::system("ip netns del rtwt-cut 2>/dev/null");
        if (std::system("ip netns add rtwt-cut 2>/dev/null") != 0) GTEST_SKIP() << "cannot create network namespaces here";
        ready_ = std::system("ip link add rtwt-h type veth peer name rtwt-n netns rtwt-cut && "
                             "ip addr add 10.198.7.1/24 dev rtwt-h && ip link set rtwt-h up && "
                             "ip -n rtwt-cut addr add 10.198.7.2/24 dev rtwt-n && ip -n rtwt-cut link set rtwt-n up && "
                             "ip -n rtwt-cut link set lo up") == 0;
        if (!ready_) GTEST_SKIP() << "cannot create a veth pair here";
    }
    void TearDown() override {
        std::system("ip link del rtwt-h 2>/dev/null");
        std::system("ip netns del rtwt-cut 2>/dev/null");
    }
    bool ready_ = false;
};

TEST_F(CutLink, ClientBehindACutCableMidFrame) {
    const SceneDesc desc = slowScene();
    const Image expected = singleMachine(desc);
    ClusterSettings cs = faultSettings();
    cs.bind = "tcp://10.198.7.1:0";
    cs.insecure = true;  // the test's own namespace and veth; nothing else is reachable
    Master master(desc, cs);
    Process local(master.endpoint()), remote(master.endpoint(), kNs);
    ASSERT_TRUE(master.waitForClients(2, 30000));
    master.renderFrame();

    auto frame = std::async(std::launch::async, [&] { return master.renderFrame(); });
    std::this_thread::sleep_for(std::chrono::milliseconds(60));
    const auto cutAt = Clock::now();
    ASSERT_EQ(std::system("ip -n rtwt-cut link set rtwt-n down"), 0);
    ASSERT_TRUE(waitUntil([&] { return master.connectedClients() == 1; }, 5000));
    const double detection = std::chrono::duration<double>(Clock::now() - cutAt).count();
    EXPECT_EQ(frame.get().rgb, expected.rgb) << "the frame completes, bit-identical";
    EXPECT_GE(detection, 0.2) << "no FIN: only the heartbeat timeout can have noticed";
    EXPECT_LT(detection, 0.4 * 3) << "within the heartbeat timeout (plus scheduling slack)";
}

}  // namespace
}  // namespace rtwall
