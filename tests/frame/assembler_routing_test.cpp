// A display node's share of a frame (issue 19) without a network: an assembler with routes
// holds the frame exactly when every tile routed to it is in, refuses everything else, and
// writes each tile once, also with decode threads racing.
#include <rtwall/frame.h>

#include <gtest/gtest.h>

#include <random>
#include <thread>

namespace rtwall {
namespace {

using Claim = FrameAssembler::Claim;

// A one-view frame of makeTiles(width, height, tileSize), routed by `routes` to node `node`.
void begin(FrameAssembler& a, uint32_t frame, int width, int height, int tileSize, const std::vector<uint64_t>& routes,
           unsigned node) {
    std::vector<ViewTile> tiles;
    for (const TileRect& t : makeTiles(width, height, tileSize)) tiles.push_back({0, t});
    FrameHolding o;
    o.routes = &routes;
    o.node = node;
    a.beginFrame(frame, width, height, tiles, 1, o);
}

bool write(FrameAssembler& a, uint32_t frame, uint32_t tile, uint8_t value) {
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

TEST(AssemblerRouting, HoldsTheFrameWhenEveryRoutedTileIsIn) {
    FrameAssembler a;
    begin(a, 5, 40, 20, 10, routes(), 0);
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
    begin(a, 6, 40, 20, 10, routes(), 1);
    EXPECT_EQ(a.expected(), 5u);
    EXPECT_EQ(a.claim(5, 1, rect, view), Claim::Stale);
    EXPECT_EQ(a.claim(6, 0, rect, view), Claim::NotRouted);
}

TEST(AssemblerRouting, ANodeWithNothingRoutedHoldsEveryFrameAtOnce) {
    FrameAssembler a;
    begin(a, 1, 40, 20, 10, std::vector<uint64_t>(8, 1), 2);
    EXPECT_EQ(a.expected(), 0u);
    EXPECT_TRUE(a.complete());
}

TEST(AssemblerRouting, MasksThatDoNotFitTheTilingAreRefused) {
    FrameAssembler a;
    EXPECT_THROW(begin(a, 1, 40, 20, 10, std::vector<uint64_t>(7, 1), 0), std::invalid_argument);
    EXPECT_THROW(begin(a, 1, 40, 20, 10, routes(), 64), std::invalid_argument);
}

TEST(AssemblerRouting, RacingDecodersWriteEachTileOnce) {
    const int width = 160, height = 96, tile = 8;
    const size_t count = makeTiles(width, height, tile).size();
    std::mt19937 rng(3);
    std::vector<uint64_t> r(count);
    for (uint64_t& m : r) m = rng() % 4;
    for (int run = 0; run < 20; ++run) {
        FrameAssembler a;
        begin(a, uint32_t(run), width, height, tile, r, 1);
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

// A tile of a view the frame does not have is a caller's mistake, said at once.
TEST(AssemblerRouting, ATileOfAViewBeyondTheFramesIsRefused) {
    FrameAssembler a;
    const std::vector<ViewTile> tiles{{0, {0, 0, 8, 8}}, {2, {0, 0, 8, 8}}};
    EXPECT_THROW(a.beginFrame(1, 8, 8, tiles, 2), std::invalid_argument);
}

// A linear frame has a linear buffer per view, which a granted tile is written to at its place
// (what the compositor sums); the buffers keep their size from frame to frame.
TEST(AssemblerRouting, ALinearFrameHasALinearBufferPerView) {
    FrameAssembler a;
    const std::vector<ViewTile> tiles{{0, {0, 0, 4, 4}}, {1, {4, 0, 8, 4}}};
    FrameHolding o;
    o.linear = true;
    a.beginFrame(2, 8, 4, tiles, 2, o);
    ASSERT_TRUE(a.linear());
    ASSERT_EQ(a.linearImages().size(), 2u);
    TileRect rect;
    TileView view;
    ASSERT_EQ(a.claim(2, 1, rect, view), Claim::Granted);
    float* l = a.linearAt(a.viewOf(1), rect.x0, rect.y0);
    EXPECT_EQ(l, a.linearImages()[1].data() + 4 * 3);
    l[0] = 0.5f;
    a.commit(1);
    EXPECT_EQ(a.linearImages()[1][12], 0.5f);
    EXPECT_EQ(a.linearImages()[0][12], 0.0f);
    EXPECT_EQ(a.missing(), 1u);
}

}  // namespace
}  // namespace rtwall
