// A display node's share of a frame (issue 19) without a network: it holds the frame exactly when
// every tile routed to it is in, refuses everything else, and writes each tile once, also with
// decode threads racing.
#include "node_assembly.h"

#include <gtest/gtest.h>

#include <random>
#include <thread>

namespace rtwall::cluster {
namespace {

using Claim = NodeAssembly::Claim;

bool write(NodeAssembly& a, uint32_t frame, uint32_t tile, uint8_t value) {
    TileRect rect;
    TileView view;
    if (a.claim(frame, tile, rect, view) != Claim::Granted) return false;
    for (int y = 0; y < rect.height(); ++y)
        for (int x = 0; x < 3 * rect.width(); ++x) view.data[size_t(y) * view.stride + size_t(x)] = value;
    a.commit(tile);
    return true;
}

// 40x20 in 10-pixel tiles: 4x2 tiles. Left half on node 0, right half on node 1, the middle
// column of tiles (x 10..29) under a bezel both show: a tile may belong to both, or to none.
std::vector<uint64_t> routes() { return {1, 3, 2, 0, 1, 3, 2, 2}; }

TEST(NodeAssembly, HoldsTheFrameWhenEveryRoutedTileIsIn) {
    NodeAssembly a;
    a.beginFrame(5, 40, 20, 10, routes(), 0);
    EXPECT_EQ(a.expected(), 4u);
    EXPECT_FALSE(a.complete());
    TileRect rect;
    TileView view;
    EXPECT_EQ(a.claim(5, 2, rect, view), Claim::NotRouted);
    EXPECT_EQ(a.claim(5, 3, rect, view), Claim::NotRouted);
    EXPECT_EQ(a.claim(4, 0, rect, view), Claim::Stale);
    EXPECT_EQ(a.claim(5, 8, rect, view), Claim::Invalid);
    EXPECT_TRUE(write(a, 5, 0, 10));
    EXPECT_FALSE(write(a, 5, 0, 11));  // a repeat
    EXPECT_TRUE(write(a, 5, 1, 20));
    EXPECT_TRUE(write(a, 5, 4, 30));
    EXPECT_EQ(a.missing(), 1u);
    EXPECT_FALSE(a.complete());
    // A tile whose decoding failed is free again.
    ASSERT_EQ(a.claim(5, 5, rect, view), Claim::Granted);
    a.release(5);
    EXPECT_FALSE(a.complete());
    EXPECT_TRUE(write(a, 5, 5, 40));
    EXPECT_TRUE(a.complete());
    EXPECT_EQ(a.image().pixel(0, 0)[0], 10);
    EXPECT_EQ(a.image().pixel(19, 19)[2], 40);
    EXPECT_EQ(a.image().pixel(25, 5)[0], 0);  // never routed here: not written
    // The next frame starts afresh.
    a.beginFrame(6, 40, 20, 10, routes(), 1);
    EXPECT_EQ(a.expected(), 5u);
    EXPECT_EQ(a.claim(5, 1, rect, view), Claim::Stale);
    EXPECT_EQ(a.claim(6, 0, rect, view), Claim::NotRouted);
}

TEST(NodeAssembly, ANodeWithNothingRoutedHoldsEveryFrameAtOnce) {
    NodeAssembly a;
    a.beginFrame(1, 40, 20, 10, std::vector<uint64_t>(8, 1), 2);
    EXPECT_EQ(a.expected(), 0u);
    EXPECT_TRUE(a.complete());
}

TEST(NodeAssembly, MasksThatDoNotFitTheTilingAreRefused) {
    NodeAssembly a;
    EXPECT_THROW(a.beginFrame(1, 40, 20, 10, std::vector<uint64_t>(7, 1), 0), std::invalid_argument);
    EXPECT_THROW(a.beginFrame(1, 40, 20, 10, routes(), 64), std::invalid_argument);
}

TEST(NodeAssembly, RacingDecodersWriteEachTileOnce) {
    const int width = 160, height = 96, tile = 8;
    const size_t count = makeTiles(width, height, tile).size();
    std::mt19937 rng(3);
    std::vector<uint64_t> r(count);
    for (uint64_t& m : r) m = rng() % 4;
    for (int run = 0; run < 20; ++run) {
        NodeAssembly a;
        a.beginFrame(uint32_t(run), width, height, tile, r, 1);
        std::atomic<size_t> granted{0};
        std::vector<std::thread> threads;
        for (int t = 0; t < 4; ++t)
            threads.emplace_back([&, t] {
                for (size_t i = 0; i < count; ++i) {
                    const uint32_t k = uint32_t((i * 7 + size_t(t) * 13) % count);
                    if (write(a, uint32_t(run), k, uint8_t(k))) ++granted;
                }
            });
        for (auto& th : threads) th.join();
        EXPECT_EQ(granted.load(), a.expected());
        EXPECT_TRUE(a.complete());
    }
}

}  // namespace
}  // namespace rtwall::cluster
