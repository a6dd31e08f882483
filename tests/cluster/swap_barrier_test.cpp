// The display nodes' swap barrier (issue 19) without a network: no frame is released before
// every taking-part node holds it, under any order and delay of the reports; a stalled node is
// left out after the stall time and rejoins when it holds a frame again; skew is measured.
#include "swap_barrier.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace rtwall::cluster {
namespace {

// Nodes joined to b, in this order.
void joinAll(SwapBarrier& b, std::initializer_list<NodeId> nodes) {
    for (NodeId n : nodes) b.join(n);
}

TEST(SwapBarrier, ReleasesAFrameOnlyWhenEveryNodeHoldsIt) {
    SwapBarrier b(0.5);
    joinAll(b, {1, 2, 3});
    EXPECT_FALSE(b.have(1, 1, 0.0));
    EXPECT_FALSE(b.have(3, 1, 0.01));
    EXPECT_FALSE(b.have(1, 1, 0.02));  // a repeat changes nothing
    EXPECT_EQ(b.have(2, 1, 0.03), 1u);
    EXPECT_EQ(b.lastReleased(), 1u);
    EXPECT_FALSE(b.have(2, 1, 0.04));  // released frames are done
    EXPECT_EQ(b.stats().released, 1u);
}

// Random interleavings of several frames' reports, with random delays: a frame is released
// exactly when its last node reports it (or a newer frame all hold supersedes it), never before.
TEST(SwapBarrier, NoFrameIsReleasedBeforeAllHoldItUnderAnyDelay) {
    std::mt19937 rng(11);
    for (int run = 0; run < 200; ++run) {
        const int nodes = 1 + int(rng() % 4), frames = 1 + int(rng() % 5);
        SwapBarrier b(1e9);  // no stalls here
        for (int n = 0; n < nodes; ++n) b.join(NodeId(n));
        struct Report {
            NodeId node;
            uint32_t frame;
            double at;
        };
        std::vector<Report> reports;
        for (int f = 1; f <= frames; ++f)
            for (int n = 0; n < nodes; ++n) reports.push_back({NodeId(n), uint32_t(f), f * 0.016 + (rng() % 1000) * 1e-4});  // up to 100 ms late
        std::sort(reports.begin(), reports.end(), [](const Report& a, const Report& c) { return a.at < c.at; });
        std::map<uint32_t, std::set<NodeId>> held;
        uint32_t last = 0;
        for (const Report& r : reports) {
            held[r.frame].insert(r.node);
            const auto released = b.have(r.node, r.frame, r.at);
            if (!released) continue;
            ASSERT_GT(*released, last);
            ASSERT_EQ(held[*released].size(), size_t(nodes)) << "frame " << *released << " released before every node held it";
            last = *released;
        }
        EXPECT_EQ(last, uint32_t(frames));  // the newest frame always comes out
    }
}

TEST(SwapBarrier, AStalledNodeIsLeftOutAndRejoins) {
    SwapBarrier b(0.1);
    joinAll(b, {1, 2});
    EXPECT_FALSE(b.have(1, 1, 1.0));
    EXPECT_FALSE(b.poll(1.05));  // node 2 is late, not yet stalled
    EXPECT_EQ(b.poll(1.2), 1u);  // stalled: frame 1 goes to swap without it
    EXPECT_EQ(b.leftOut(), (std::vector<NodeId>{2}));
    EXPECT_EQ(b.stats().leftOut, 1u);
    // The rest of the wall goes on at its own pace.
    EXPECT_EQ(b.have(1, 2, 1.3), 2u);
    EXPECT_EQ(b.have(1, 3, 1.4), 3u);
    // Node 2 holds a current frame again: it takes part, and frame 4 waits for it.
    EXPECT_FALSE(b.have(2, 4, 1.5));
    EXPECT_TRUE(b.leftOut().empty());
    EXPECT_EQ(b.stats().rejoined, 1u);
    EXPECT_EQ(b.have(1, 4, 1.51), 4u);
    // A stale report of an old frame does not bring anything back.
    EXPECT_FALSE(b.have(2, 2, 1.6));
}

TEST(SwapBarrier, ANodeThatLeavesNoLongerHoldsFramesBack) {
    SwapBarrier b(10);
    joinAll(b, {1, 2});
    EXPECT_FALSE(b.have(1, 1, 0));
    b.leave(2);
    EXPECT_EQ(b.poll(0.01), 1u);
    EXPECT_EQ(b.nodes(), (std::vector<NodeId>{1}));
    b.join(2);  // reconnected: frames wait for it again
    EXPECT_FALSE(b.have(1, 2, 0.02));
    EXPECT_EQ(b.have(2, 2, 0.03), 2u);
    // Reports of nodes that never joined are ignored.
    EXPECT_FALSE(b.have(9, 3, 0.04));
}

TEST(SwapBarrier, ANewerFrameAllHoldSupersedesOlderOnes) {
    SwapBarrier b(10);
    joinAll(b, {1, 2});
    EXPECT_FALSE(b.have(1, 1, 0));  // node 2 never gets frame 1 (a lost tile)
    EXPECT_FALSE(b.have(1, 2, 0.01));
    EXPECT_EQ(b.have(2, 2, 0.02), 2u);
    EXPECT_EQ(b.stats().superseded, 1u);
    EXPECT_FALSE(b.have(2, 1, 0.03));  // too late
}

TEST(SwapBarrier, SkewIsTheSpreadOfTheSwapReports) {
    SwapBarrier b(10);
    joinAll(b, {1, 2});
    b.have(1, 1, 0);
    ASSERT_EQ(b.have(2, 1, 0), 1u);
    b.swapped(2, 1, 5.0004);
    b.swapped(1, 1, 5.0001);
    EXPECT_NEAR(b.stats().lastSkew, 0.0003, 1e-12);
    b.swapped(1, 7, 9.0);  // not released: ignored
    EXPECT_NEAR(b.stats().maxSkew, 0.0003, 1e-12);
}

}  // namespace
}  // namespace rtwall::cluster
