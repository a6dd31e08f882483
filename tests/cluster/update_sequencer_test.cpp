// Updates reordered, duplicated and lost: the sequencer hands out exactly the consecutive run,
// or says why it cannot.
#include "update_sequencer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace rtwall::cluster {
namespace {

Update update(uint32_t seq, uint32_t base = ~0u) {
    Update u;
    u.seq = seq;
    u.baseSeq = base == ~0u ? seq - 1 : base;
    u.changes.push_back(LightChange{seq, Light{}});  // tags the update with its number
    return u;
}

std::vector<uint32_t> seqs(const std::vector<Update>& ups) {
    std::vector<uint32_t> s;
    for (const Update& u : ups) s.push_back(u.seq);
    return s;
}

TEST(UpdateSequencer, ReorderedUpdatesComeOutInOrder) {
    UpdateSequencer s;
    for (uint32_t seq : {3u, 1u, 4u, 2u}) EXPECT_TRUE(s.add(update(seq)));
    std::vector<Update> out;
    EXPECT_EQ(s.catchUp(3, out), UpdateSequencer::CatchUp::Ready);
    EXPECT_EQ(seqs(out), (std::vector<uint32_t>{1, 2, 3}));
    EXPECT_EQ(s.state(), 3u);
    EXPECT_EQ(s.pending(), 1u);  // 4 waits for its frame
    EXPECT_EQ(s.catchUp(4, out), UpdateSequencer::CatchUp::Ready);
    EXPECT_EQ(seqs(out), (std::vector<uint32_t>{4}));
}

TEST(UpdateSequencer, ALostUpdateIsAGapUntilASnapshot) {
    UpdateSequencer s;
    s.add(update(1));
    s.add(update(3));
    std::vector<Update> out;
    EXPECT_EQ(s.catchUp(3, out), UpdateSequencer::CatchUp::Gap);
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(s.state(), 0u) << "nothing is applied across a gap";
    EXPECT_EQ(s.catchUp(1, out), UpdateSequencer::CatchUp::Ready) << "up to the gap is fine";
    // A snapshot at 2 fills the hole: 3 is still buffered and applies next.
    s.reset(2);
    EXPECT_EQ(s.catchUp(3, out), UpdateSequencer::CatchUp::Ready);
    EXPECT_EQ(seqs(out), (std::vector<uint32_t>{3}));
}

TEST(UpdateSequencer, DuplicatesAndOldUpdatesAreIgnored) {
    UpdateSequencer s;
    s.reset(5);
    s.add(update(4));
    s.add(update(5));
    s.add(update(6));
    s.add(update(6));
    EXPECT_EQ(s.pending(), 1u);
    std::vector<Update> out;
    EXPECT_EQ(s.catchUp(6, out), UpdateSequencer::CatchUp::Ready);
    EXPECT_EQ(seqs(out), (std::vector<uint32_t>{6}));
}

TEST(UpdateSequencer, AFrameOlderThanTheStateCannotBeRendered) {
    UpdateSequencer s;
    s.reset(10);
    std::vector<Update> out;
    EXPECT_EQ(s.catchUp(9, out), UpdateSequencer::CatchUp::Ahead);
    EXPECT_EQ(s.catchUp(10, out), UpdateSequencer::CatchUp::Ready);
    EXPECT_TRUE(out.empty());
}

TEST(UpdateSequencer, OverflowAsksForAResync) {
    UpdateSequencer s;
    for (uint32_t i = 0; i < UpdateSequencer::kMaxPending; ++i) ASSERT_TRUE(s.add(update(i + 2)));
    EXPECT_FALSE(s.add(update(UpdateSequencer::kMaxPending + 2)));
    EXPECT_EQ(s.pending(), 0u);
}

TEST(UpdateSequencer, MergedUpdatesCoverARange) {
    UpdateSequencer s;
    s.add(update(5, 0));   // 0 -> 5 in one message
    s.add(update(7, 5));   // 5 -> 7
    std::vector<Update> out;
    EXPECT_EQ(s.catchUp(3, out), UpdateSequencer::CatchUp::Gap) << "a frame inside a merged update cannot start";
    EXPECT_EQ(s.catchUp(7, out), UpdateSequencer::CatchUp::Ready);
    EXPECT_EQ(seqs(out), (std::vector<uint32_t>{5, 7}));
    s.add(update(9, 9));   // malformed: base not below seq
    EXPECT_EQ(s.pending(), 0u);
}

TEST(UpdateSequencer, RandomOrderAndLossNeverApplyOutOfOrder) {
    // Bounded random trials: whatever arrives, what comes out is consecutive from the state.
    std::mt19937 rng(7);
    for (int trial = 0; trial < 200; ++trial) {
        UpdateSequencer s;
        std::vector<uint32_t> arrive;
        for (uint32_t i = 1; i <= 20; ++i)
            if (rng() % 5 != 0) arrive.push_back(i);  // 20% lost
        std::shuffle(arrive.begin(), arrive.end(), rng);
        for (uint32_t a : arrive) s.add(update(a));
        std::vector<Update> out;
        const auto r = s.catchUp(20, out);
        const bool complete = arrive.size() == 20;
        EXPECT_EQ(r == UpdateSequencer::CatchUp::Ready, complete);
        if (complete) {
            for (size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i].seq, i + 1);
        }
    }
}

}  // namespace
}  // namespace rtwall::cluster
