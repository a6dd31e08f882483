// Issue 16's chaos test: four render-client processes frozen (SIGSTOP/SIGCONT), killed and
// started again, restarted, and (with namespaces) cut off and reconnected at random with a fixed
// seed, while the master renders a scene whose state changes every frame. Every frame that
// completes must be one machine's image of its state, bit for bit, no frame may be lost for
// good, and once the faults stop (every client alive again) the next frame must complete within
// the bound stated here. `rtwall bench chaos` runs the same for longer.
#include "adversary.h"
#include "local_cluster.h"
#include "test_util.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

namespace rtwall {
namespace {

// After the last fault is undone: a client's timeout (0.4 s), its reconnection back-off (at most
// 0.4 s), joining (the scene is rebuilt: well under a second) and a frame of about 0.1 s. On a
// loaded 2-core machine that is seconds; the bound allows ten.
constexpr double kBoundAfterLastFault = 10.0;

// Four client processes of this build for 12 s, faults drawn from `seed`.
testing::ChaosOptions chaosOptions(uint64_t seed) {
    testing::ChaosOptions o;
    o.exe = RTWALL_EXE;
    o.clients = 4;
    o.seconds = 12;
    o.seed = seed;
    return o;
}

testing::ChaosReport chaosOnTheDemo(const testing::ChaosOptions& o) { return testing::runChaos(test::quickDemo(96, 72, 8), o); }

void check(const testing::ChaosReport& r, const char* what) {
    std::printf("chaos (%s): %llu faults (%llu frozen, %llu killed, %llu restarted, %llu links cut); %llu frames, %llu "
                "bit-identical, %llu failed; worst frame %.2f s; after the last fault: first frame %.2f s, worst %.2f s; "
                "master: %s\n",
                what, (unsigned long long)r.faults, (unsigned long long)r.stops, (unsigned long long)r.kills,
                (unsigned long long)r.restarts, (unsigned long long)r.linkCuts, (unsigned long long)r.frames,
                (unsigned long long)r.framesIdentical, (unsigned long long)r.framesFailed, r.worstFrameSeconds,
                r.firstFrameAfterLastFault, r.worstAfterLastFault, describeCounters(r.counters).c_str());
    EXPECT_GE(r.faults, 10u);
    EXPECT_GT(r.frames, 10u);
    EXPECT_EQ(r.framesIdentical, r.frames) << "a frame that completed differs from one machine's";
    EXPECT_EQ(r.framesFailed, 0u) << "a frame never completed";
    EXPECT_LT(r.firstFrameAfterLastFault, kBoundAfterLastFault);
    EXPECT_LT(r.worstAfterLastFault, kBoundAfterLastFault);
}

TEST(Chaos, ClientsFrozenKilledAndRestartedAtRandom) {
    const testing::ChaosReport r = chaosOnTheDemo(chaosOptions(16));
    ASSERT_TRUE(r.error.empty()) << r.error;
    check(r, "processes");
    EXPECT_GT(r.stops, 0u);
    EXPECT_GT(r.kills + r.restarts, 0u);
}

// The same with the clients' links cut too (each client in a network namespace of its own on a
// bridge in another; root needed, skipped otherwise).
TEST(Chaos, LinksCutAndRestoredToo) {
    testing::ChaosOptions o = chaosOptions(17);
    o.linkCuts = true;
    const testing::ChaosReport r = chaosOnTheDemo(o);
    if (!r.error.empty()) GTEST_SKIP() << r.error;
    check(r, "processes and links");
    EXPECT_GT(r.linkCuts, 0u);
}

}  // namespace
}  // namespace rtwall
