// TileScheduler without a network: every policy (affinity, stealing, straggler re-issue, dead
// and late clients, stale results) driven by hand with an explicit clock.
#include "scheduler.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <set>

namespace rtwall::cluster {
namespace {

using Result = TileScheduler::Result;

std::vector<uint32_t> range(uint32_t first, uint32_t last) {  // [first, last)
    std::vector<uint32_t> v(last - first);
    std::iota(v.begin(), v.end(), first);
    return v;
}

uint64_t sum(const std::map<ClientId, uint64_t>& m) {
    uint64_t s = 0;
    for (const auto& [client, n] : m) s += n;
    return s;
}

// Clients added to s, in this order.
void addClients(TileScheduler& s, std::initializer_list<ClientId> ids) {
    for (ClientId c : ids) s.addClient(c);
}

// Clients 1 and 2 in frame 0 of `tiles` tiles: at time 0, 1 takes tile 0 and 2 takes tile 1.
void oneTileEach(TileScheduler& s, uint32_t tiles) {
    addClients(s, {1, 2});
    s.beginFrame(0, tiles);
    EXPECT_EQ(s.request(1, 1, 0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.request(2, 1, 0), std::vector<uint32_t>{1});
}

// Client 1 alone in frame `frame` of four tiles: it takes all four at time 0.
void oneClientTakesAll(TileScheduler& s, uint32_t frame) {
    s.addClient(1);
    s.beginFrame(frame, 4);
    EXPECT_EQ(s.request(1, 4, 0.0), range(0, 4));
}

// A tile is a straggler once older than max(0.05 s, 4 x the median tile time): the numbers the
// straggler tests work out by hand.
SchedulerOptions stragglerOptions() {
    SchedulerOptions options;
    options.minStragglerSeconds = 0.05;
    options.stragglerFactor = 4;
    return options;
}

// Each client in turn, starting with clients[first], asks for `batch` tiles and returns them
// all before its next turn. Returns who rendered each tile.
std::vector<ClientId> runRoundRobin(TileScheduler& s, const std::vector<ClientId>& clients, size_t first,
                                    uint32_t batch, double& now) {
    std::vector<ClientId> owner(s.tileCount(), TileScheduler::kNobody);
    for (int round = 0; !s.frameComplete(); ++round) {
        if (round > 10000) {
            ADD_FAILURE() << "frame " << s.frame() << " never completes";
            break;
        }
        for (size_t i = 0; i < clients.size(); ++i) {
            const ClientId c = clients[(first + i) % clients.size()];
            for (uint32_t t : s.request(c, batch, now)) {
                now += 0.001;
                EXPECT_EQ(s.complete(c, s.frame(), t, now), Result::Accepted) << "tile " << t;
                owner[t] = c;
            }
        }
    }
    return owner;
}

// One frame in which each (client, n) takes n tiles in that order and returns them, so the
// next frame's affinity queues are known exactly.
void ownFrame(TileScheduler& s, uint32_t frame, const std::vector<std::pair<ClientId, uint32_t>>& takes,
              double now) {
    uint32_t total = 0;
    for (const auto& [c, n] : takes) total += n;
    s.beginFrame(frame, total);
    for (const auto& [c, n] : takes)
        for (uint32_t t : s.request(c, n, now)) ASSERT_EQ(s.complete(c, frame, t, now + 0.001), Result::Accepted);
    ASSERT_TRUE(s.frameComplete());
}

// --- Basics ----------------------------------------------------------------------------------

TEST(Scheduler, SingleClientGetsAllTilesInImageOrderNAtATime) {
    TileScheduler s;
    s.addClient(7);
    s.beginFrame(0, 10);
    EXPECT_EQ(s.remaining(), 10u);
    EXPECT_FALSE(s.frameComplete());

    std::vector<std::vector<uint32_t>> batches;
    for (int i = 0; i < 5; ++i) batches.push_back(s.request(7, 3, 0.0));
    EXPECT_EQ(batches[0], range(0, 3));
    EXPECT_EQ(batches[1], range(3, 6));
    EXPECT_EQ(batches[2], range(6, 9));
    EXPECT_EQ(batches[3], range(9, 10));
    EXPECT_TRUE(batches[4].empty());
    EXPECT_EQ(s.stats().assigned, 10u);

    for (uint32_t t = 0; t < 10; ++t) {
        EXPECT_FALSE(s.frameComplete()) << "before tile " << t;
        EXPECT_EQ(s.complete(7, 0, t, 0.01), Result::Accepted);
        EXPECT_EQ(s.remaining(), 9 - t);
    }
    EXPECT_TRUE(s.frameComplete());
    EXPECT_EQ(s.stats().completed, 10u);
    EXPECT_EQ(s.stats().completedBy.at(7), 10u);
    EXPECT_EQ(s.stats().stolen, 0u);
    EXPECT_EQ(s.stats().reissued, 0u);
}

TEST(Scheduler, ReopenedTileIsHandedOutAgain) {
    // An accepted result whose pixels did not decode: the tile must be rendered again.
    TileScheduler s;
    addClients(s, {1, 2});
    s.beginFrame(1, 2);
    const auto a = s.request(1, 2, 0.0);
    ASSERT_EQ(a.size(), 2u);
    EXPECT_EQ(s.complete(1, 1, a[0], 0.1), Result::Accepted);
    EXPECT_EQ(s.complete(1, 1, a[1], 0.1), Result::Accepted);
    EXPECT_TRUE(s.frameComplete());
    EXPECT_FALSE(s.reopen(2, a[0])) << "another frame";
    EXPECT_TRUE(s.reopen(1, a[0]));
    EXPECT_FALSE(s.reopen(1, a[0])) << "already open";
    EXPECT_FALSE(s.frameComplete());
    EXPECT_EQ(s.remaining(), 1u);
    const auto again = s.request(2, 4, 0.2);
    ASSERT_EQ(again, std::vector<uint32_t>{a[0]});
    EXPECT_EQ(s.complete(2, 1, a[0], 0.3), Result::Accepted);
    EXPECT_TRUE(s.frameComplete());
}

TEST(Scheduler, CountZeroAndEmptyFrameGiveNothing) {
    TileScheduler s;
    s.addClient(1);
    s.beginFrame(0, 0);
    EXPECT_TRUE(s.frameComplete());
    EXPECT_TRUE(s.request(1, 4, 0).empty());
    s.beginFrame(1, 3);
    EXPECT_TRUE(s.request(1, 0, 0).empty());
    EXPECT_EQ(s.stats().assigned, 0u);
    EXPECT_EQ(s.request(1, 4, 0), range(0, 3));
}

// Decision: an unknown client gets nothing rather than being added implicitly, so a late
// request from a client the master declared dead cannot bring it back.
TEST(Scheduler, UnknownOrRemovedClientGetsNothing) {
    TileScheduler s;
    s.addClient(1);
    s.beginFrame(0, 4);
    EXPECT_FALSE(s.hasClient(2));
    EXPECT_TRUE(s.request(2, 4, 0).empty());
    EXPECT_FALSE(s.hasClient(2));
    EXPECT_EQ(s.complete(2, 0, 0, 0), Result::Unexpected);

    s.addClient(2);
    s.addClient(2);  // again: no effect
    EXPECT_EQ(s.request(2, 1, 0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.removeClient(2), 1u);
    EXPECT_EQ(s.removeClient(2), 0u);
    EXPECT_TRUE(s.request(2, 4, 0).empty());
    EXPECT_EQ(s.stats().assigned, 1u);
    EXPECT_EQ(s.request(1, 4, 0), range(0, 4));
}

TEST(Scheduler, ReservedClientIdIsRefused) {
    TileScheduler s;
    EXPECT_THROW(s.addClient(TileScheduler::kNobody), std::invalid_argument);
    EXPECT_FALSE(s.hasClient(TileScheduler::kNobody));
}

TEST(Scheduler, PrefetchingClientsCompletingInVariousOrders) {
    SchedulerOptions options;
    options.minStragglerSeconds = 1e9;  // a tile held back by newest-first is not a straggler here
    TileScheduler s(options);
    const std::vector<ClientId> clients{10, 11, 12};
    for (ClientId c : clients) s.addClient(c);
    s.beginFrame(3, 50);

    std::mt19937 rng(5);
    std::map<ClientId, std::vector<uint32_t>> inFlight;
    std::vector<int> accepted(50, 0);
    double now = 0;
    for (int round = 0; !s.frameComplete() && round < 1000; ++round) {
        for (ClientId c : clients) {
            // Keep 4 in flight, like a client with prefetch 4.
            auto& mine = inFlight[c];
            for (uint32_t t : s.request(c, 4 - uint32_t(mine.size()), now)) mine.push_back(t);
            if (mine.empty()) continue;
            // 10 returns its oldest tile, 11 its newest, 12 a random one.
            size_t pick = c == 10 ? 0 : c == 11 ? mine.size() - 1 : rng() % mine.size();
            now += 0.001;
            const uint32_t t = mine[pick];
            mine.erase(mine.begin() + std::ptrdiff_t(pick));
            ASSERT_EQ(s.complete(c, 3, t, now), Result::Accepted) << "tile " << t;
            ++accepted[t];
        }
    }
    EXPECT_TRUE(s.frameComplete());
    EXPECT_EQ(accepted, std::vector<int>(50, 1));
    EXPECT_EQ(s.stats().completed, 50u);
    EXPECT_EQ(s.stats().assigned, 50u);
    EXPECT_EQ(sum(s.stats().completedBy), 50u);
    EXPECT_EQ(s.stats().duplicates + s.stats().stale + s.stats().unexpected, 0u);
    for (ClientId c : clients) EXPECT_GT(s.stats().completedBy.at(c), 0u) << c;
}

// --- Results that must not be written ----------------------------------------------------------

TEST(Scheduler, ResultForPreviousOrFutureFrameIsStale) {
    TileScheduler s;
    oneClientTakesAll(s, 5);
    EXPECT_EQ(s.complete(1, 5, 0, 0.1), Result::Accepted);

    s.beginFrame(6, 4);
    EXPECT_EQ(s.stats().completed, 0u) << "stats are per frame";
    EXPECT_EQ(s.remaining(), 4u);
    EXPECT_EQ(s.complete(1, 5, 1, 0.2), Result::Stale);
    EXPECT_EQ(s.complete(1, 7, 1, 0.2), Result::Stale);
    EXPECT_EQ(s.stats().stale, 2u);
    // The unfinished frame's hand-outs are forgotten.
    EXPECT_EQ(s.complete(1, 6, 1, 0.2), Result::Unexpected);
    EXPECT_EQ(s.remaining(), 4u);
    EXPECT_EQ(s.request(1, 4, 0.3), range(0, 4));
}

TEST(Scheduler, ResultForTileNeverHandedOutIsUnexpected) {
    TileScheduler s;
    addClients(s, {1, 2});
    s.beginFrame(0, 4);
    EXPECT_EQ(s.request(1, 2, 0), range(0, 2));
    EXPECT_EQ(s.complete(1, 0, 4, 0.1), Result::Unexpected) << "out of range";
    EXPECT_EQ(s.complete(1, 0, 1000000, 0.1), Result::Unexpected) << "out of range";
    EXPECT_EQ(s.complete(1, 0, 2, 0.1), Result::Unexpected) << "still queued";
    EXPECT_EQ(s.complete(2, 0, 0, 0.1), Result::Unexpected) << "handed to client 1";
    EXPECT_EQ(s.stats().unexpected, 4u);
    EXPECT_EQ(s.remaining(), 4u);
    EXPECT_EQ(s.complete(1, 0, 0, 0.1), Result::Accepted);
    EXPECT_EQ(s.complete(2, 0, 0, 0.1), Result::Unexpected) << "done, but never 2's";
    EXPECT_EQ(s.complete(1, 0, 0, 0.1), Result::Duplicate) << "sent twice";
    EXPECT_EQ(s.stats().duplicates, 1u);
    EXPECT_EQ(s.stats().completed, 1u);
}

// --- Affinity ----------------------------------------------------------------------------------

// Who asks first changes from frame to frame, as it does on a network.
SchedulerStats stillCamera(bool affinity, std::vector<double>* hitRates) {
    SchedulerOptions options;
    options.affinity = affinity;
    TileScheduler s(options);
    const std::vector<ClientId> clients{1, 2, 3};
    for (ClientId c : clients) s.addClient(c);
    double now = 0;
    std::vector<ClientId> last;
    for (uint32_t f = 0; f < 6; ++f) {
        s.beginFrame(f, 48);  // 4 batches of 4 each: nobody runs out early and steals
        std::vector<ClientId> owner = runRoundRobin(s, clients, f % clients.size(), 4, now);
        if (f > 0) {
            size_t same = 0;
            for (size_t t = 0; t < owner.size(); ++t) same += owner[t] == last[t];
            EXPECT_EQ(s.stats().affinityHits, same) << "frame " << f;
            hitRates->push_back(double(s.stats().affinityHits) / 48);
        }
        last = owner;
    }
    return s.stats();
}

TEST(SchedulerAffinity, StillCameraSendsEveryTileBackToItsOwner) {
    std::vector<double> rates;
    const SchedulerStats last = stillCamera(true, &rates);
    ASSERT_EQ(rates.size(), 5u);
    for (double r : rates) EXPECT_EQ(r, 1.0);
    EXPECT_EQ(last.stolen, 0u);
    EXPECT_EQ(last.completed, 48u);
}

TEST(SchedulerAffinity, WithoutAffinityTilesGoToWhoeverAsksFirst) {
    std::vector<double> on, off;
    const SchedulerStats withAffinity = stillCamera(true, &on);
    const SchedulerStats without = stillCamera(false, &off);
    EXPECT_LT(without.affinityHits, withAffinity.affinityHits);
    EXPECT_LT(*std::max_element(off.begin(), off.end()), 0.9);
    EXPECT_EQ(without.completed, 48u);
}

TEST(SchedulerAffinity, FirstAskerGetsItsOwnTilesNotTheSharedOrder) {
    TileScheduler s;
    addClients(s, {1, 2});
    ownFrame(s, 0, {{1, 3}, {2, 3}}, 0);  // 1 rendered 0..2, 2 rendered 3..5
    s.beginFrame(1, 6);
    EXPECT_EQ(s.request(2, 2, 1.0), range(3, 5)) << "own queue, front first";
    EXPECT_EQ(s.request(1, 3, 1.0), range(0, 3));
    EXPECT_EQ(s.stats().stolen, 0u);
    for (uint32_t t = 0; t < 3; ++t) EXPECT_EQ(s.complete(1, 1, t, 1.1), Result::Accepted);
    EXPECT_EQ(s.complete(2, 1, 3, 1.1), Result::Accepted);
    EXPECT_EQ(s.stats().affinityHits, 4u);
}

// Both eyes in one pass (issue 18): the frame's tile list is the left eye's tiles, then the
// right eye's (viewTiles), so affinity by tile number keeps each client on the same tiles of the
// same eye: client 1 rendered the left eye's first half and the right eye's second half, and
// gets exactly those again, whoever asks first.
TEST(SchedulerAffinity, EachEyesTilesGoBackToTheirOwnerInOnePass) {
    std::vector<FrameView> views(2);
    const uint32_t perEye = uint32_t(makeTiles(64, 32, 16).size()), count = uint32_t(viewTiles(views, 64, 32, 16).size());
    ASSERT_EQ(count, 2 * perEye);
    TileScheduler s;
    addClients(s, {1, 2});
    // Frame 0: 1 takes left 0..3 and right 4..7, 2 the rest (its own queue order after frame 0).
    s.beginFrame(0, count);
    std::vector<uint32_t> one = s.request(1, 4, 0.0);
    EXPECT_EQ(one, range(0, 4));
    std::vector<uint32_t> two = s.request(2, perEye, 0.0);  // left 4..7 and right 0..3
    EXPECT_EQ(two, range(4, 12));
    std::vector<uint32_t> rest = s.request(1, 4, 0.0);  // right 4..7
    EXPECT_EQ(rest, range(12, 16));
    for (uint32_t t : one) s.complete(1, 0, t, 0.1);
    for (uint32_t t : rest) s.complete(1, 0, t, 0.1);
    for (uint32_t t : two) s.complete(2, 0, t, 0.1);
    // Frame 1: 2 asks first and gets its own tiles of both eyes, not the front of the list.
    s.beginFrame(1, count);
    EXPECT_EQ(s.request(2, perEye, 1.0), range(4, 12));
    std::vector<uint32_t> again = s.request(1, perEye, 1.0);
    std::vector<uint32_t> expected = range(0, 4);
    for (uint32_t t : range(12, 16)) expected.push_back(t);
    EXPECT_EQ(again, expected);
    for (uint32_t t = 0; t < count; ++t) s.complete(t < 4 || t >= 12 ? 1 : 2, 1, t, 1.1);
    EXPECT_EQ(s.stats().affinityHits, count);
    EXPECT_EQ(s.stats().stolen, 0u);
}

TEST(SchedulerAffinity, ChangedTileCountStartsFromTheSharedQueue) {
    TileScheduler s;
    addClients(s, {1, 2});
    ownFrame(s, 0, {{1, 3}, {2, 3}}, 0);
    s.beginFrame(1, 8);  // resized wall: last frame's owners mean nothing
    EXPECT_EQ(s.request(2, 3, 1.0), range(0, 3));
    EXPECT_EQ(s.stats().stolen, 0u);
    for (uint32_t t = 0; t < 3; ++t) EXPECT_EQ(s.complete(2, 1, t, 1.1), Result::Accepted);
    EXPECT_EQ(s.stats().affinityHits, 0u);

    // Back to 6 tiles after an 8-tile frame: still no affinity (the 8-tile frame was last).
    s.beginFrame(2, 6);
    EXPECT_EQ(s.request(2, 6, 2.0), range(0, 6));
}

TEST(SchedulerAffinity, AffinityOffPutsEverythingInTheSharedQueue) {
    SchedulerOptions options;
    options.affinity = false;
    TileScheduler s(options);
    addClients(s, {1, 2});
    ownFrame(s, 0, {{1, 3}, {2, 3}}, 0);
    s.beginFrame(1, 6);
    EXPECT_EQ(s.request(2, 6, 1.0), range(0, 6));
    EXPECT_EQ(s.stats().stolen, 0u) << "shared tiles are not steals";
    for (uint32_t t = 0; t < 6; ++t) EXPECT_EQ(s.complete(2, 1, t, 1.1), Result::Accepted);
    EXPECT_EQ(s.stats().affinityHits, 3u) << "hits are still measured";
}

TEST(SchedulerAffinity, UnfinishedFrameOnlyPassesOnTheTilesThatWereDone) {
    TileScheduler s;
    addClients(s, {1, 2});
    s.beginFrame(0, 4);
    EXPECT_EQ(s.request(1, 4, 0), range(0, 4));
    EXPECT_EQ(s.complete(1, 0, 2, 0.1), Result::Accepted);
    s.beginFrame(1, 4);  // frame 0 abandoned
    EXPECT_EQ(s.request(2, 3, 1.0), (std::vector<uint32_t>{0, 1, 3})) << "only tile 2 has an owner";
    EXPECT_EQ(s.stats().stolen, 0u);
    EXPECT_EQ(s.request(1, 4, 1.0), std::vector<uint32_t>{2});
}

// --- Stealing ----------------------------------------------------------------------------------

TEST(SchedulerStealing, IdleClientsStealFromTheBackOfASlowClientsQueue) {
    TileScheduler s;
    const ClientId a = 1, b = 2, slow = 3;
    addClients(s, {a, b, slow});
    double now = 0;
    s.beginFrame(0, 48);
    const std::vector<ClientId> lastOwner = runRoundRobin(s, {a, b, slow}, 0, 4, now);
    std::vector<uint32_t> slowTiles;
    for (uint32_t t = 0; t < 48; ++t)
        if (lastOwner[t] == slow) slowTiles.push_back(t);
    ASSERT_EQ(slowTiles.size(), 16u);

    s.beginFrame(1, 48);
    // The slow client takes its first tiles and sits on them until the end.
    const std::vector<uint32_t> slowHeld = s.request(slow, 4, now);
    EXPECT_EQ(slowHeld, std::vector<uint32_t>(slowTiles.begin(), slowTiles.begin() + 4));

    std::vector<uint32_t> stolenTiles;
    std::vector<std::vector<uint32_t>> stolenBatches;
    std::vector<int> accepted(48, 0);
    for (int round = 0; round < 100; ++round) {
        bool gotAny = false;
        for (ClientId c : {a, b}) {
            std::vector<uint32_t> batch;
            for (uint32_t t : s.request(c, 2, now)) {
                gotAny = true;
                if (lastOwner[t] != c) batch.push_back(t);
                EXPECT_EQ(s.complete(c, 1, t, now + 0.001), Result::Accepted);
                ++accepted[t];
            }
            now += 0.001;
            if (!batch.empty()) stolenBatches.push_back(batch);
            stolenTiles.insert(stolenTiles.end(), batch.begin(), batch.end());
        }
        if (!gotAny) break;
    }
    EXPECT_FALSE(s.frameComplete());
    for (uint32_t t : s.request(slow, 4, now)) ADD_FAILURE() << "everything left was stolen, got " << t;
    for (uint32_t t : slowHeld) {
        EXPECT_EQ(s.complete(slow, 1, t, now), Result::Accepted);
        ++accepted[t];
    }
    EXPECT_TRUE(s.frameComplete());
    EXPECT_EQ(accepted, std::vector<int>(48, 1));

    // Every stolen tile was the slow client's, taken from the back, never its next ones.
    std::sort(stolenTiles.begin(), stolenTiles.end());
    EXPECT_EQ(stolenTiles, std::vector<uint32_t>(slowTiles.begin() + 4, slowTiles.end()));
    ASSERT_FALSE(stolenBatches.empty());
    EXPECT_EQ(stolenBatches.front(), (std::vector<uint32_t>{slowTiles[14], slowTiles[15]}));
    EXPECT_EQ(s.stats().stolen, 12u);
    EXPECT_EQ(s.stats().stolenBy.count(slow), 0u);
    EXPECT_EQ(s.stats().stolenBy.at(a) + s.stats().stolenBy.at(b), 12u);
    EXPECT_EQ(s.stats().completedBy.at(slow), 4u);
    EXPECT_EQ(s.stats().affinityHits, 36u);
    EXPECT_EQ(s.stats().reissued, 0u);
}

SchedulerOptions seeded(uint64_t seed) {
    SchedulerOptions options;
    options.seed = seed;
    return options;
}

// Clients 1, 2 and 3 rendered tiles 0-9, 10-19 and 20-29 of frame 0: their queues in frame 1 of
// 30 tiles, which is begun.
void threeQueuesOfTen(TileScheduler& s) {
    addClients(s, {1, 2, 3});
    ownFrame(s, 0, {{1, 10}, {2, 10}, {3, 10}}, 0);
    s.beginFrame(1, 30);
}

TEST(SchedulerStealing, VictimIsAPeerWithTilesLeft) {
    for (uint64_t seed = 1; seed <= 20; ++seed) {
        TileScheduler s(seeded(seed));
        threeQueuesOfTen(s);
        EXPECT_EQ(s.request(2, 10, 1), range(10, 20));  // 2 drained its own queue
        EXPECT_EQ(s.request(1, 10, 1), range(0, 10));
        // Only 3 has tiles left: every steal comes from it, from the back.
        for (uint32_t t = 29; t >= 20; --t) ASSERT_EQ(s.request(1, 1, 1), std::vector<uint32_t>{t}) << "seed " << seed;
        EXPECT_TRUE(s.request(1, 1, 1).empty());
        EXPECT_TRUE(s.request(3, 1, 1).empty());
        EXPECT_EQ(s.stats().stolen, 10u);
    }
}

TEST(SchedulerStealing, VictimChoiceIsRandomButReproducible) {
    auto victims = [](uint64_t seed) {
        TileScheduler s(seeded(seed));
        threeQueuesOfTen(s);
        EXPECT_EQ(s.request(1, 10, 1), range(0, 10));
        std::vector<ClientId> from;
        uint32_t nextOf2 = 19, nextOf3 = 29;
        for (int i = 0; i < 8; ++i) {
            const std::vector<uint32_t> got = s.request(1, 1, 1);
            EXPECT_EQ(got.size(), 1u);
            if (got.empty()) break;
            // Each victim loses its back tile first.
            if (got[0] < 20) {
                EXPECT_EQ(got[0], nextOf2--);
                from.push_back(2);
            } else {
                EXPECT_EQ(got[0], nextOf3--);
                from.push_back(3);
            }
        }
        return from;
    };
    std::set<std::vector<ClientId>> distinct;
    for (uint64_t seed = 1; seed <= 10; ++seed) {
        const std::vector<ClientId> v = victims(seed);
        EXPECT_EQ(v, victims(seed)) << "seed " << seed;
        distinct.insert(v);
    }
    EXPECT_GT(distinct.size(), 1u);
}

TEST(SchedulerStealing, StolenRunIsHandedOutInImageOrder) {
    TileScheduler s;
    addClients(s, {1, 2});
    ownFrame(s, 0, {{1, 8}}, 0);
    s.beginFrame(1, 8);
    EXPECT_EQ(s.request(2, 3, 1), range(5, 8));
    EXPECT_EQ(s.request(1, 8, 1), range(0, 5)) << "the victim keeps its next tiles";
    EXPECT_EQ(s.stats().stolenBy.at(2), 3u);
}

// --- Clients coming and going --------------------------------------------------------------------

TEST(SchedulerClients, DeadClientsTilesGoBackAndItsLateResultsAreRejected) {
    TileScheduler s;
    addClients(s, {1, 2, 3});
    ownFrame(s, 0, {{1, 6}, {2, 6}, {3, 6}}, 0);  // 2 owns 6..11
    s.beginFrame(1, 18);
    const std::vector<uint32_t> held = s.request(2, 4, 1.0);
    EXPECT_EQ(held, range(6, 10));
    EXPECT_EQ(s.complete(2, 1, 6, 1.1), Result::Accepted);

    // 7..9 outstanding plus 10..11 queued come back; 6 is done and stays done.
    EXPECT_EQ(s.removeClient(2), 5u);
    EXPECT_FALSE(s.hasClient(2));
    EXPECT_EQ(s.remaining(), 17u);
    // Its tiles are in the shared queue now, in image order, behind 1's own queue.
    EXPECT_EQ(s.request(1, 8, 1.2), (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 7, 8}));
    EXPECT_EQ(s.stats().stolen, 0u);

    std::vector<int> accepted(18, 0);
    accepted[6] = 1;
    for (uint32_t t : {0, 1, 2, 3, 4, 5, 7, 8}) {
        EXPECT_EQ(s.complete(1, 1, t, 1.3), Result::Accepted);
        ++accepted[t];
    }
    double now = 1.3;
    for (ClientId c : {3, 1})
        for (uint32_t t : s.request(c, 10, now)) {
            EXPECT_EQ(s.complete(c, 1, t, now += 0.001), Result::Accepted);
            ++accepted[t];
        }
    EXPECT_TRUE(s.frameComplete());
    EXPECT_EQ(accepted, std::vector<int>(18, 1));

    // The dead client's late results: never accepted, in this frame or the next.
    for (uint32_t t : held) EXPECT_EQ(s.complete(2, 1, t, 2.0), Result::Unexpected) << t;
    s.beginFrame(2, 18);
    EXPECT_EQ(s.complete(2, 1, 7, 3.0), Result::Stale);
    EXPECT_EQ(s.complete(2, 2, 7, 3.0), Result::Unexpected);
    EXPECT_TRUE(s.request(2, 4, 3.0).empty());
}

TEST(SchedulerClients, TileStillRenderedByAReissueIsNotQueuedAgain) {
    TileScheduler s;
    addClients(s, {1, 2, 3});
    s.beginFrame(0, 3);
    EXPECT_EQ(s.request(1, 1, 0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.request(2, 2, 0), range(1, 3));
    EXPECT_EQ(s.complete(2, 0, 1, 0.01), Result::Accepted);
    EXPECT_EQ(s.complete(2, 0, 2, 0.01), Result::Accepted);
    EXPECT_EQ(s.request(2, 1, 1.0), std::vector<uint32_t>{0});  // re-issue of 1's tile
    // 1 dies: tile 0 is still being rendered by 2, so it is not queued again.
    EXPECT_EQ(s.removeClient(1), 0u);
    EXPECT_TRUE(s.request(3, 4, 1.0).empty());
    EXPECT_EQ(s.complete(2, 0, 0, 1.01), Result::Accepted);
    EXPECT_TRUE(s.frameComplete());
    EXPECT_EQ(s.complete(1, 0, 0, 1.02), Result::Unexpected);
}

TEST(SchedulerClients, LateJoinerStealsWhenEveryTileHasAnOwner) {
    TileScheduler s;
    addClients(s, {1, 2});
    ownFrame(s, 0, {{1, 4}, {2, 4}}, 0);
    s.beginFrame(1, 8);
    s.addClient(3);
    const std::vector<uint32_t> got = s.request(3, 2, 1.0);
    ASSERT_EQ(got.size(), 2u);
    EXPECT_TRUE(got == range(2, 4) || got == range(6, 8)) << got[0] << "," << got[1];
    EXPECT_EQ(s.stats().stolenBy.at(3), 2u);
}

TEST(SchedulerClients, DepartedClientsTilesGoToTheSharedQueueNextFrame) {
    TileScheduler s;
    addClients(s, {1, 2});
    ownFrame(s, 0, {{1, 4}, {2, 4}}, 0);
    s.removeClient(2);
    s.addClient(3);
    s.beginFrame(1, 8);
    EXPECT_EQ(s.request(3, 4, 1.0), range(4, 8)) << "2's tiles, shared, in image order";
    EXPECT_EQ(s.stats().stolen, 0u);
    EXPECT_EQ(s.request(1, 8, 1.0), range(0, 4));
}

TEST(SchedulerClients, ReturningIdStartsWithoutAffinity) {
    TileScheduler s;
    addClients(s, {1, 2});
    ownFrame(s, 0, {{1, 4}, {2, 4}}, 0);
    s.removeClient(2);
    s.addClient(2);  // a restarted process: its cache is cold
    s.beginFrame(1, 8);
    EXPECT_EQ(s.request(1, 8, 1.0), range(0, 8)) << "own queue, then 2's old tiles from the shared queue";
    EXPECT_EQ(s.stats().stolen, 0u);
}

// --- Stragglers --------------------------------------------------------------------------------

TEST(SchedulerStragglers, HungTileIsReissuedToAnIdleClient) {
    TileScheduler s(stragglerOptions());
    const ClientId hung = 1, worker = 2;
    addClients(s, {hung, worker});
    s.beginFrame(0, 8);
    EXPECT_EQ(s.request(hung, 1, 0.0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.request(worker, 7, 0.0), range(1, 8));
    for (uint32_t t = 1; t < 8; ++t) EXPECT_EQ(s.complete(worker, 0, t, 0.01), Result::Accepted);
    // Median 0.01 s, so the threshold is max(0.05, 4 * 0.01) = 0.05 s.
    EXPECT_TRUE(s.request(worker, 4, 0.045).empty()) << "older than 4 * median but not than the minimum";
    EXPECT_TRUE(s.request(worker, 4, 0.05).empty()) << "must be older than the threshold";
    EXPECT_TRUE(s.request(hung, 4, 10.0).empty()) << "never re-issued to its holder";
    EXPECT_EQ(s.request(worker, 4, 0.06), std::vector<uint32_t>{0});
    EXPECT_EQ(s.stats().reissued, 1u);
    EXPECT_EQ(s.stats().assigned, 9u);
    EXPECT_TRUE(s.request(worker, 4, 1.0).empty()) << "already handed to this client";
    EXPECT_FALSE(s.frameComplete());

    EXPECT_EQ(s.complete(worker, 0, 0, 0.07), Result::Accepted);
    EXPECT_TRUE(s.frameComplete());
    EXPECT_EQ(s.complete(hung, 0, 0, 2.0), Result::Duplicate);
    EXPECT_EQ(s.stats().duplicates, 1u);
    EXPECT_EQ(s.stats().completedBy.count(hung), 0u);
    EXPECT_EQ(s.stats().completedBy.at(worker), 8u);
}

TEST(SchedulerStragglers, SlowHolderWinsAndTheReissueIsTheDuplicate) {
    TileScheduler s;
    oneTileEach(s, 2);
    EXPECT_EQ(s.complete(2, 0, 1, 0.01), Result::Accepted);
    EXPECT_EQ(s.request(2, 1, 1.0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.complete(1, 0, 0, 1.001), Result::Accepted);
    EXPECT_EQ(s.complete(2, 0, 0, 1.002), Result::Duplicate);
    EXPECT_TRUE(s.request(2, 1, 5.0).empty()) << "done tiles are never re-issued";
}

TEST(SchedulerStragglers, LatencyIsMeasuredFromTheAnsweringHandOut) {
    TileScheduler s;  // min 0.05 s, factor 4
    addClients(s, {1, 2, 3});
    s.beginFrame(0, 3);
    EXPECT_EQ(s.request(1, 1, 0.0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.request(2, 1, 0.0), std::vector<uint32_t>{1});
    EXPECT_EQ(s.request(3, 1, 0.5), std::vector<uint32_t>{2});
    EXPECT_EQ(s.complete(2, 0, 1, 0.01), Result::Accepted);
    EXPECT_EQ(s.request(2, 1, 1.0), std::vector<uint32_t>{0});
    // 0.01 s after the re-issue, not 1.01 s after 1 got it: the median stays 0.01 s...
    EXPECT_EQ(s.complete(2, 0, 0, 1.01), Result::Accepted);
    // ...so tile 2, 0.7 s old, is a straggler (with 1.01 s samples it would not be before 4 s).
    EXPECT_EQ(s.request(2, 1, 1.2), std::vector<uint32_t>{2});
}

TEST(SchedulerStragglers, NothingIsReissuedBeforeTheFirstResult) {
    TileScheduler s;
    oneTileEach(s, 2);
    EXPECT_TRUE(s.request(2, 1, 100.0).empty());
    EXPECT_TRUE(s.request(1, 1, 100.0).empty());
    EXPECT_EQ(s.stats().reissued, 0u);
}

TEST(SchedulerStragglers, ThresholdFollowsTheMedianTileTime) {
    TileScheduler s(stragglerOptions());
    addClients(s, {1, 2});
    s.beginFrame(0, 5);
    EXPECT_EQ(s.request(2, 4, 0), range(0, 4));
    // Latencies 0.5, 1, 1, 9: median 1 (the outlier does not drag it, as a mean would to
    // 2.875), so the threshold is 4 s.
    EXPECT_EQ(s.complete(2, 0, 0, 0.5), Result::Accepted);
    EXPECT_EQ(s.complete(2, 0, 1, 1.0), Result::Accepted);
    EXPECT_EQ(s.complete(2, 0, 2, 1.0), Result::Accepted);
    EXPECT_EQ(s.complete(2, 0, 3, 9.0), Result::Accepted);
    EXPECT_EQ(s.request(1, 1, 9.0), std::vector<uint32_t>{4});
    EXPECT_TRUE(s.request(2, 1, 12.9).empty());
    EXPECT_EQ(s.request(2, 1, 13.1), std::vector<uint32_t>{4});
}

TEST(SchedulerStragglers, OldestFirstAndAgedFromTheLatestHandOut) {
    TileScheduler s;  // min 0.05 s, factor 4
    addClients(s, {1, 2, 3, 4});
    s.beginFrame(0, 4);
    EXPECT_EQ(s.request(1, 1, 0.0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.request(2, 1, 0.1), std::vector<uint32_t>{1});
    EXPECT_EQ(s.request(3, 2, 0.1), range(2, 4));
    EXPECT_EQ(s.complete(3, 0, 2, 0.11), Result::Accepted);
    EXPECT_EQ(s.complete(3, 0, 3, 0.11), Result::Accepted);
    // Tile 0 was handed out first, so it is re-issued first.
    EXPECT_EQ(s.request(3, 1, 1.0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.request(3, 1, 1.0), std::vector<uint32_t>{1});
    // Both were just re-issued: 4 waits until the re-issues themselves look stuck.
    EXPECT_TRUE(s.request(4, 2, 1.01).empty());
    EXPECT_EQ(s.request(4, 2, 2.0), range(0, 2));
    EXPECT_EQ(s.stats().reissued, 4u);
    EXPECT_EQ(s.complete(4, 0, 1, 2.01), Result::Accepted);
    EXPECT_EQ(s.complete(2, 0, 1, 2.02), Result::Duplicate);
    EXPECT_EQ(s.complete(3, 0, 1, 2.03), Result::Duplicate);
}

TEST(SchedulerStragglers, QueuedTilesComeBeforeReissues) {
    TileScheduler s;
    oneTileEach(s, 4);
    EXPECT_EQ(s.complete(2, 0, 1, 0.01), Result::Accepted);
    // Tile 0 is a straggler by now, but 2 and 3 are still queued: they come first, and the
    // rest of the request is filled with the re-issue.
    EXPECT_EQ(s.request(2, 3, 10.0), (std::vector<uint32_t>{2, 3, 0}));
    EXPECT_EQ(s.stats().reissued, 1u);
}

// --- Properties over random sequences ------------------------------------------------------------

// Issue 16: a lost result when one client is left. The scheduler re-issues an overdue tile only
// to another client; the client's idle report (Heartbeat) releases its hand-outs instead, and
// they go back to it.
TEST(SchedulerLostHandOuts, ReleasedTilesGoBackToTheOnlyClient) {
    TileScheduler s;
    oneClientTakesAll(s, 1);
    EXPECT_EQ(s.complete(1, 1, 0, 0.01), Result::Accepted);
    EXPECT_EQ(s.complete(1, 1, 1, 0.02), Result::Accepted);
    // Tiles 2 and 3: their results were lost. Without a release nothing ever gives them out again.
    EXPECT_TRUE(s.request(1, 4, 100.0).empty()) << "never re-issued to the client holding them";
    EXPECT_EQ(s.outstanding(1), 2u);
    EXPECT_EQ(s.release(1), 2u);
    EXPECT_EQ(s.outstanding(1), 0u);
    EXPECT_EQ(s.stats().released, 2u);
    EXPECT_EQ(s.request(1, 4, 100.0), range(2, 4));
    EXPECT_EQ(s.complete(1, 1, 2, 100.1), Result::Accepted);
    EXPECT_EQ(s.complete(1, 1, 3, 100.1), Result::Accepted);
    EXPECT_TRUE(s.frameComplete());
}

TEST(SchedulerLostHandOuts, AReleasedHandOutsLateResultStillCountsOnce) {
    TileScheduler s;
    s.addClient(1);
    s.beginFrame(1, 2);
    EXPECT_EQ(s.request(1, 2, 0.0), range(0, 2));
    EXPECT_EQ(s.release(1), 2u);
    // Only late, not lost: the first result wins and the tile leaves the queue.
    EXPECT_EQ(s.complete(1, 1, 0, 1.0), Result::Accepted);
    EXPECT_EQ(s.request(1, 4, 1.0), std::vector<uint32_t>{1}) << "the done tile is not handed out again";
    EXPECT_EQ(s.complete(1, 1, 0, 1.1), Result::Duplicate);
    EXPECT_EQ(s.complete(1, 1, 1, 1.2), Result::Accepted);
    EXPECT_TRUE(s.frameComplete());
    EXPECT_EQ(s.stats().completed, 2u);
}

TEST(SchedulerLostHandOuts, ATileStillRenderedElsewhereIsNotQueuedAgain) {
    TileScheduler s(SchedulerOptions{false, 2.0, 0.05, 1});
    addClients(s, {1, 2});
    s.beginFrame(1, 2);
    EXPECT_EQ(s.request(1, 1, 0.0), std::vector<uint32_t>{0});
    EXPECT_EQ(s.request(2, 1, 0.0), std::vector<uint32_t>{1});
    EXPECT_EQ(s.complete(2, 1, 1, 0.1), Result::Accepted);
    EXPECT_EQ(s.request(2, 1, 1.0), std::vector<uint32_t>{0}) << "a straggler re-issue";
    EXPECT_EQ(s.release(1), 1u);
    EXPECT_TRUE(s.request(1, 1, 1.0).empty()) << "client 2 still renders it: not queued a third time";
    EXPECT_EQ(s.complete(2, 1, 0, 1.1), Result::Accepted);
    EXPECT_TRUE(s.frameComplete());
}

// Issue 15: a render thread stuck on a tile. The tile goes to another client while there is one,
// and to the same client (its other threads) when it is the only one left.
TEST(SchedulerLostHandOuts, AStuckTileAvoidsItsClientWhileAnotherIsPresent) {
    TileScheduler s(SchedulerOptions{false, 4.0, 0.05, 1});
    addClients(s, {1, 2});
    s.beginFrame(1, 4);
    EXPECT_EQ(s.request(1, 2, 0.0), range(0, 2));
    EXPECT_FALSE(s.release(1, 1, 3, true)) << "not its tile";
    EXPECT_FALSE(s.release(1, 2, 0, true)) << "another frame";
    EXPECT_TRUE(s.release(1, 1, 0, true));
    EXPECT_FALSE(s.release(1, 1, 0, true)) << "released already";
    EXPECT_EQ(s.request(1, 4, 0.1), range(2, 4)) << "client 1 gets the other tiles, not the stuck one";
    EXPECT_EQ(s.request(2, 4, 0.1), std::vector<uint32_t>{0});
    EXPECT_EQ(s.complete(2, 1, 0, 0.2), Result::Accepted);

    s.beginFrame(2, 4);
    EXPECT_EQ(s.request(1, 1, 0.0), std::vector<uint32_t>{0});
    EXPECT_TRUE(s.release(1, 2, 0, true));
    s.removeClient(2);
    EXPECT_EQ(s.request(1, 1, 0.1), std::vector<uint32_t>{0}) << "the only client left: its other threads take it";
}

// A model of what a TileScheduler driven by random calls must answer: which clients are live,
// who holds which tile of the frame, what was handed out and released, what is done. Each call
// checks the scheduler against it.
class SchedulerModel {
public:
    explicit SchedulerModel(uint64_t seed) : rng_(seed * 7919), s_(optionsFor(seed)) {
        for (uint64_t i = 0, n = 1 + rng_() % 4; i < n; ++i) addClient();
    }

    // Frame `frame` (sometimes with a new tile count): 300 random calls, the tile counts checked
    // after each. Fatal failures: call it in ASSERT_NO_FATAL_FAILURE.
    void randomCalls(uint32_t frame) {
        frame_ = frame;
        if (frame == 0 || rng_() % 4 == 0) tiles_ = 1 + uint32_t(rng_() % 40);
        s_.beginFrame(frame, tiles_);
        accepted_.assign(tiles_, 0);
        handed_.clear();
        holders_.assign(tiles_, {});
        released_.clear();
        assigned_ = acceptedCount_ = 0;
        for (int step = 0; step < 300; ++step) {
            now_ += rng_() % 50 == 0 ? 1.0 : double(rng_() % 10) * 0.001;
            randomCall();
            ASSERT_EQ(s_.remaining(), tiles_ - acceptedCount_);
            ASSERT_EQ(s_.frameComplete(), acceptedCount_ == tiles_);
        }
    }

    // Drain with whoever is left: every tile must be accepted exactly once, and the statistics
    // add up. Fatal failures: call it in ASSERT_NO_FATAL_FAILURE.
    void drainAndCheck() {
        if (live_.empty()) addClient();
        for (int round = 0; !s_.frameComplete() && round < 1000; ++round) {
            for (ClientId c : std::vector<ClientId>(live_.begin(), live_.end())) request(c, 4);
            now_ += 0.001;
            for (size_t i = 0; i < held_.size();) {
                if (held_[i].frame == frame_ && live_.count(held_[i].client)) {
                    const Held h = held_[i];
                    held_.erase(held_.begin() + std::ptrdiff_t(i));
                    report(h);
                } else {
                    ++i;
                }
            }
        }
        ASSERT_TRUE(s_.frameComplete());
        EXPECT_EQ(s_.remaining(), 0u);
        EXPECT_EQ(accepted_, std::vector<int>(tiles_, 1));
        EXPECT_EQ(s_.stats().completed, tiles_);
        EXPECT_EQ(sum(s_.stats().completedBy), tiles_);
        EXPECT_EQ(s_.stats().assigned, assigned_);
        EXPECT_EQ(sum(s_.stats().stolenBy), s_.stats().stolen);
        EXPECT_LE(s_.stats().affinityHits, s_.stats().completed);
        EXPECT_LE(s_.stats().stolen + s_.stats().reissued, s_.stats().assigned);
    }

private:
    struct Held {
        ClientId client;
        uint32_t frame, tile;
    };

    static SchedulerOptions optionsFor(uint64_t seed) {
        SchedulerOptions options;
        options.affinity = seed % 2 == 1;
        options.seed = seed;
        options.stragglerFactor = 2;
        return options;
    }

    void addClient() {
        s_.addClient(nextId_);
        live_.insert(nextId_++);
    }

    ClientId pick(const std::set<ClientId>& from) {
        auto it = from.begin();
        std::advance(it, std::ptrdiff_t(rng_() % from.size()));
        return *it;
    }

    // One call of the scheduler's, drawn at random: a request, a result (held, garbage), a client
    // never seen, one removed or added, lost hand-outs.
    void randomCall() {
        const uint64_t op = rng_() % 21;
        if (op < 8 && !live_.empty()) {
            request(pick(live_), 1 + uint32_t(rng_() % 4));
        } else if (op < 15 && !held_.empty()) {
            const size_t i = rng_() % held_.size();
            const Held h = held_[i];
            held_.erase(held_.begin() + std::ptrdiff_t(i));
            report(h);
        } else if (op == 15) {
            report({ClientId(rng_() % (nextId_ + 2)), frame_, uint32_t(rng_() % (tiles_ + 3))});  // garbage
        } else if (op == 16) {
            request(nextId_ + 5, 4);  // a client never seen
        } else if (op == 17 && !live_.empty()) {
            removeClient(pick(live_));
        } else if (op == 18) {
            addClient();
        } else if (op == 19 && !live_.empty()) {
            loseHandOuts(pick(live_));
        }
    }

    void request(ClientId c, uint32_t n) {
        const uint64_t reissuedBefore = s_.stats().reissued;
        const std::vector<uint32_t> got = s_.request(c, n, now_);
        EXPECT_LE(got.size(), n);
        if (!live_.count(c)) {
            EXPECT_TRUE(got.empty());
        }
        std::set<uint32_t> unique;
        uint64_t heldElsewhere = 0;
        for (uint32_t t : got) {
            ASSERT_LT(t, tiles_);
            EXPECT_TRUE(unique.insert(t).second) << "tile " << t << " twice in one request";
            EXPECT_EQ(accepted_[t], 0) << "done tile " << t << " handed out";
            if (handed_.count({t, c})) {  // only after its hand-out was released
                EXPECT_EQ(released_.erase({t, c}), 1u) << "tile " << t << " handed to " << c << " twice";
            }
            heldElsewhere += !holders_[t].empty();
            holders_[t].insert(c);
            handed_.insert({t, c});
            held_.push_back({c, frame_, t});
        }
        // A tile somebody is still rendering goes out again only as a re-issue.
        EXPECT_EQ(heldElsewhere, s_.stats().reissued - reissuedBefore);
        assigned_ += got.size();
    }

    void report(const Held& h) {
        Result expected;
        if (h.frame != frame_)
            expected = Result::Stale;
        else if (h.tile >= tiles_ || !live_.count(h.client) || !handed_.count({h.tile, h.client}))
            expected = Result::Unexpected;
        else if (accepted_[h.tile])
            expected = Result::Duplicate;
        else
            expected = Result::Accepted;
        EXPECT_EQ(s_.complete(h.client, h.frame, h.tile, now_), expected);
        if (expected == Result::Accepted) {
            ++accepted_[h.tile];
            ++acceptedCount_;
            holders_[h.tile].clear();
        }
    }

    void removeClient(ClientId c) {
        live_.erase(c);
        // At least the tiles only it held and that are not done come back.
        size_t onlyHeldByIt = 0;
        for (uint32_t t = 0; t < tiles_; ++t) {
            onlyHeldByIt += !accepted_[t] && holders_[t] == std::set<ClientId>{c};
            holders_[t].erase(c);
        }
        for (auto it = handed_.begin(); it != handed_.end();) it = it->second == c ? handed_.erase(it) : std::next(it);
        for (auto it = released_.begin(); it != released_.end();) it = it->second == c ? released_.erase(it) : std::next(it);
        EXPECT_GE(s_.removeClient(c), onlyHeldByIt);
    }

    // Lost hand-outs: all of client c's (idle report), or one stuck tile.
    void loseHandOuts(ClientId c) {
        size_t holding = 0;
        for (uint32_t t = 0; t < tiles_; ++t) holding += holders_[t].count(c);
        if (rng_() % 2 == 0) {
            EXPECT_EQ(s_.release(c), holding);
            for (uint32_t t = 0; t < tiles_; ++t)
                if (holders_[t].erase(c)) released_.insert({t, c});
        } else {
            const uint32_t t = uint32_t(rng_() % (tiles_ + 1));
            const bool holds = t < tiles_ && holders_[t].count(c);
            EXPECT_EQ(s_.release(c, frame_, t, rng_() % 2 == 0), holds);
            if (holds) {
                holders_[t].erase(c);
                released_.insert({t, c});
            }
        }
    }

    std::mt19937_64 rng_;
    TileScheduler s_;
    std::set<ClientId> live_;
    ClientId nextId_ = 0;
    std::vector<Held> held_;  // hand-outs not reported yet, of any frame and any client
    double now_ = 0;
    uint32_t frame_ = 0, tiles_ = 0;
    // Of the current frame:
    std::vector<int> accepted_;
    std::set<std::pair<uint32_t, ClientId>> handed_;    // present clients
    std::vector<std::set<ClientId>> holders_;           // awaiting a result, present clients
    std::set<std::pair<uint32_t, ClientId>> released_;  // hand-outs released: may be handed to it again
    uint64_t assigned_ = 0, acceptedCount_ = 0;
};

TEST(SchedulerProperty, RandomSequencesKeepTheInvariants) {
    for (uint64_t seed = 1; seed <= 150; ++seed) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        SchedulerModel model(seed);
        for (uint32_t frame = 0; frame < 6; ++frame) {
            ASSERT_NO_FATAL_FAILURE(model.randomCalls(frame));
            ASSERT_NO_FATAL_FAILURE(model.drainAndCheck());
        }
    }
}

TEST(SchedulerProperty, SameSeedSameSchedule) {
    auto trace = [](uint64_t seed) {
        TileScheduler s(seeded(seed));
        std::mt19937 ops(99);  // the same calls every time; only the scheduler's seed varies
        for (ClientId c = 0; c < 4; ++c) s.addClient(c);
        std::vector<uint32_t> out;
        double now = 0;
        for (uint32_t frame = 0; frame < 4; ++frame) {
            s.beginFrame(frame, 40);
            std::vector<std::pair<ClientId, uint32_t>> held;
            for (int step = 0; step < 400 && !s.frameComplete(); ++step) {
                now += 0.001;
                const ClientId c = ClientId(ops() % 4);
                if (ops() % 2 && c != 0) {  // client 0 is slow: others steal from it
                    for (uint32_t t : s.request(c, 1 + ops() % 3, now)) {
                        out.push_back(t);
                        held.emplace_back(c, t);
                    }
                } else if (!held.empty()) {
                    const size_t i = ops() % held.size();
                    s.complete(held[i].first, frame, held[i].second, now);
                    held.erase(held.begin() + std::ptrdiff_t(i));
                }
            }
            out.push_back(uint32_t(s.stats().stolen));
        }
        return out;
    };
    EXPECT_EQ(trace(3), trace(3));
    EXPECT_NE(trace(3), trace(4));
}

}  // namespace
}  // namespace rtwall::cluster
