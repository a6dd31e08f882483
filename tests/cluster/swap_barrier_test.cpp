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

// Random interleavings of nodes that behave as display nodes do: each reports the frames it
// holds in increasing order, the next only once the barrier released the one before (it waits
// for that swap), and some lose a frame now and then (a newer one overtook it). A frame is
// released only when every node holds it or went on to a newer one; with no frame lost, every
// node holds every released frame; and the wall never waits on itself (every node can always
// go on: no deadlock without the stall time).
TEST(SwapBarrier, NoFrameIsReleasedBeforeAllHoldItUnderAnyInterleaving) {
    std::mt19937 rng(11);
    for (int run = 0; run < 400; ++run) {
        const int nodes = 1 + int(rng() % 4), frames = 1 + int(rng() % 6);
        const bool losing = run % 2 == 1;
        SwapBarrier b(1e9);  // no stalls here
        for (int n = 0; n < nodes; ++n) b.join(NodeId(n));
        // Each node's frames, in order; a losing node misses some (never the last).
        std::vector<std::vector<uint32_t>> toReport{size_t(nodes)};
        for (auto& list : toReport)
            for (int f = 1; f <= frames; ++f)
                if (!losing || f == frames || rng() % 4 != 0) list.push_back(uint32_t(f));
        std::vector<size_t> next(size_t(nodes), 0);
        std::vector<uint32_t> newest(size_t(nodes), 0);
        std::map<uint32_t, std::set<NodeId>> held;
        uint32_t last = 0;
        double t = 0;
        for (;;) {
            std::vector<int> ready;  // nodes whose previous frame is released (or passed over): they may report
            for (int n = 0; n < nodes; ++n)
                if (next[size_t(n)] < toReport[size_t(n)].size() && newest[size_t(n)] <= b.lastReleased()) ready.push_back(n);
            if (ready.empty()) break;
            const int n = ready[rng() % ready.size()];
            const uint32_t f = toReport[size_t(n)][next[size_t(n)]++];
            newest[size_t(n)] = f;
            held[f].insert(NodeId(n));
            const auto released = b.have(NodeId(n), f, t += 0.001);
            if (!released) continue;
            ASSERT_GT(*released, last);
            for (int m = 0; m < nodes; ++m)
                ASSERT_TRUE(held[*released].count(NodeId(m)) || newest[size_t(m)] > *released)
                    << "frame " << *released << " released while node " << m << " might still hold it";
            if (!losing) ASSERT_EQ(held[*released].size(), size_t(nodes)) << "frame " << *released << " released before every node held it";
            last = *released;
        }
        for (int n = 0; n < nodes; ++n)
            ASSERT_EQ(next[size_t(n)], toReport[size_t(n)].size()) << "node " << n << " waits forever (run " << run << ")";
        EXPECT_EQ(last, uint32_t(frames));  // the newest frame always comes out
        if (!losing) EXPECT_EQ(b.stats().passedOver, 0u);
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

// A node that joins while frames 3 and 4 are under way (3 complete on node 1, 4 begun) may never
// hold them whole (their tiles left before the clients knew it): they do not wait for it, not
// even with a stall time that would hold the wall for a minute; frame 5 does.
TEST(SwapBarrier, ANodeThatJoinsMidFrameTakesPartFromTheNextFrame) {
    SwapBarrier b(60);
    joinAll(b, {1});
    EXPECT_EQ(b.have(1, 1, 0), 1u);
    EXPECT_EQ(b.have(1, 2, 0.01), 2u);
    b.join(2, 5);
    EXPECT_EQ(b.have(1, 3, 0.02), 3u);
    EXPECT_EQ(b.have(1, 4, 0.03), 4u);
    EXPECT_FALSE(b.poll(0.04));
    EXPECT_TRUE(b.leftOut().empty());
    EXPECT_FALSE(b.have(1, 5, 0.05)) << "frame 5 waits for node 2";
    EXPECT_EQ(b.have(2, 5, 0.06), 5u);
    // Past the stall time, a node late for a frame it takes part in is still left out.
    EXPECT_FALSE(b.have(2, 6, 0.07));
    EXPECT_EQ(b.poll(61), 6u);
    EXPECT_EQ(b.leftOut(), (std::vector<NodeId>{1}));
}

// Node 1 holds frame 2 and waits for its swap before it reports 3; node 2 lost frame 2 (frame 4
// overtook it) and holds 3. Node 2's report of 3 says it will never hold 2: frame 2 goes at once
// (not after the stall time, which would hold the wall for a minute here), then 3.
TEST(SwapBarrier, ANodeThatWentOnToANewerFrameDoesNotHoldAnOlderOneBack) {
    SwapBarrier b(60);
    joinAll(b, {1, 2});
    EXPECT_FALSE(b.have(1, 2, 0));
    EXPECT_EQ(b.have(2, 3, 0.01), 2u);
    EXPECT_EQ(b.stats().passedOver, 1u);
    EXPECT_TRUE(b.leftOut().empty()) << "passed over, not stalled";
    EXPECT_EQ(b.have(1, 3, 0.02), 3u);
    EXPECT_EQ(b.stats().superseded, 0u);
    EXPECT_EQ(b.stats().leftOut, 0u);
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
