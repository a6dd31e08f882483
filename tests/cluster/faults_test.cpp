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
#include <future>
#include <thread>

extern char** environ;

namespace rtwall {
namespace {

using Clock = std::chrono::steady_clock;

struct Process {
    pid_t pid = -1;
    explicit Process(const std::string& endpoint) {
        const char* argv[] = {RTWALL_EXE, "client", "--connect", endpoint.c_str(), "--threads", "1",
                              "--exit-after-idle", "8000", nullptr};
        EXPECT_EQ(posix_spawn(&pid, RTWALL_EXE, nullptr, nullptr, const_cast<char**>(argv), environ), 0);
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

}  // namespace
}  // namespace rtwall
