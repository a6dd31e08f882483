// FrameAssembler without a network: each tile of the current frame is written exactly once,
// at the right place, also with several decode threads racing for the same tiles.
#include <rtwall/frame.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <thread>

namespace rtwall {
namespace {

using Claim = FrameAssembler::Claim;

std::array<uint8_t, 3> colourOf(uint32_t tile) {
    return {uint8_t(tile * 37 + 1), uint8_t(255 - tile), uint8_t(tile * 11 + 7)};
}

// Fills a granted tile through its view, as a decoder does.
void fill(const TileRect& rect, const TileView& view, std::array<uint8_t, 3> c) {
    for (int j = 0; j < rect.height(); ++j)
        for (int i = 0; i < rect.width(); ++i) {
            uint8_t* p = view.data + size_t(j) * view.stride + 3 * size_t(i);
            p[0] = c[0];
            p[1] = c[1];
            p[2] = c[2];
        }
}

std::array<uint8_t, 3> at(const Image& img, int x, int y) {
    const uint8_t* p = img.pixel(x, y);
    return {p[0], p[1], p[2]};
}

bool writeTile(FrameAssembler& a, uint32_t frame, uint32_t tile, std::array<uint8_t, 3> c) {
    TileRect rect;
    TileView view;
    if (a.claim(frame, tile, rect, view) != Claim::Granted) return false;
    fill(rect, view, c);
    a.commit(tile);
    return true;
}

TEST(Assembler, BeginFrameSizesImageAndTiles) {
    FrameAssembler a;
    a.beginFrame(4, 37, 23, 8);
    EXPECT_EQ(a.frame(), 4u);
    EXPECT_EQ(a.image().width, 37);
    EXPECT_EQ(a.image().height, 23);
    EXPECT_EQ(a.image().rgb.size(), size_t(37) * 23 * 3);
    ASSERT_EQ(a.tiles().size(), 15u);  // 5 x 3
    const std::vector<TileRect> expected = makeTiles(37, 23, 8);
    for (size_t t = 0; t < expected.size(); ++t) {
        EXPECT_EQ(a.tiles()[t].x0, expected[t].x0);
        EXPECT_EQ(a.tiles()[t].y1, expected[t].y1);
    }
    EXPECT_EQ(a.missing(), 15u);
    EXPECT_FALSE(a.complete());

    a.beginFrame(5, 64, 16, 16);
    EXPECT_EQ(a.image().rgb.size(), size_t(64) * 16 * 3);
    EXPECT_EQ(a.tiles().size(), 4u);
    EXPECT_EQ(a.missing(), 4u);
}

TEST(Assembler, TileIsGrantedOnceUntilReleased) {
    FrameAssembler a;
    a.beginFrame(1, 16, 16, 8);
    TileRect rect;
    TileView view;
    EXPECT_EQ(a.claim(1, 2, rect, view), Claim::Granted);
    EXPECT_EQ(rect.x0, 0);
    EXPECT_EQ(rect.y0, 8);
    EXPECT_EQ(rect.width(), 8);
    EXPECT_EQ(view.data, a.image().pixel(0, 8));
    EXPECT_EQ(view.stride, size_t(16) * 3);
    EXPECT_EQ(a.claim(1, 2, rect, view), Claim::Duplicate) << "being written";

    a.release(2);  // decoding failed
    EXPECT_EQ(a.missing(), 4u);
    EXPECT_EQ(a.claim(1, 2, rect, view), Claim::Granted);
    a.commit(2);
    EXPECT_EQ(a.missing(), 3u);
    EXPECT_EQ(a.claim(1, 2, rect, view), Claim::Duplicate) << "done";
    a.release(2);  // too late: a committed tile stays done
    EXPECT_EQ(a.claim(1, 2, rect, view), Claim::Duplicate);
    EXPECT_EQ(a.missing(), 3u);
}

TEST(Assembler, OtherFrameIsStaleAndOutOfRangeIsInvalid) {
    FrameAssembler a;
    a.beginFrame(7, 16, 16, 8);
    TileRect rect;
    TileView view;
    EXPECT_EQ(a.claim(6, 0, rect, view), Claim::Stale);
    EXPECT_EQ(a.claim(8, 0, rect, view), Claim::Stale);
    EXPECT_EQ(a.claim(6, 100, rect, view), Claim::Stale) << "another frame may have another tiling";
    EXPECT_EQ(a.claim(7, 4, rect, view), Claim::Invalid);
    EXPECT_EQ(a.claim(7, UINT32_MAX, rect, view), Claim::Invalid);
    EXPECT_EQ(a.missing(), 4u);

    EXPECT_EQ(a.claim(7, 0, rect, view), Claim::Granted);
    a.beginFrame(8, 16, 16, 8);  // frame 7's tiles are stale now, and every tile is missing again
    EXPECT_EQ(a.claim(7, 1, rect, view), Claim::Stale);
    EXPECT_EQ(a.claim(8, 0, rect, view), Claim::Granted);
}

TEST(Assembler, CompleteOnlyAfterEveryTileIsCommitted) {
    FrameAssembler a;
    a.beginFrame(0, 20, 10, 8);  // 3 x 2
    ASSERT_EQ(a.tiles().size(), 6u);
    for (uint32_t t = 0; t < 6; ++t) {
        EXPECT_FALSE(a.complete());
        TileRect rect;
        TileView view;
        ASSERT_EQ(a.claim(0, t, rect, view), Claim::Granted);
        EXPECT_FALSE(a.complete()) << "claimed is not done";
        a.commit(t);
        a.commit(t);  // a stray second commit must not count twice
        EXPECT_EQ(a.missing(), 5 - t);
    }
    EXPECT_TRUE(a.complete());
}

TEST(Assembler, CommitWithoutClaimIsIgnored) {
    FrameAssembler a;
    a.beginFrame(0, 16, 8, 8);
    a.commit(0);
    a.commit(99);
    a.release(99);
    EXPECT_EQ(a.missing(), 2u);
    TileRect rect;
    TileView view;
    EXPECT_EQ(a.claim(0, 0, rect, view), Claim::Granted);
}

TEST(Assembler, PixelsLandInTheirTileIncludingEdgeTiles) {
    FrameAssembler a;
    a.beginFrame(3, 37, 23, 8);
    const uint32_t columns = 5;  // ceil(37 / 8)
    // Write every other tile, edges included, so neighbours show any spill.
    std::vector<uint32_t> written;
    for (uint32_t t = 0; t < a.tiles().size(); t += 2) written.push_back(t);
    ASSERT_EQ(written.back(), 14u) << "the bottom-right corner tile";
    for (uint32_t t : written) ASSERT_TRUE(writeTile(a, 3, t, colourOf(t)));

    const TileRect& corner = a.tiles()[14];
    EXPECT_EQ(corner.width(), 5);
    EXPECT_EQ(corner.height(), 7);
    for (int y = 0; y < 23; ++y)
        for (int x = 0; x < 37; ++x) {
            const uint32_t t = uint32_t(y / 8) * columns + uint32_t(x / 8);
            const std::array<uint8_t, 3> expected = t % 2 == 0 ? colourOf(t) : std::array<uint8_t, 3>{0, 0, 0};
            ASSERT_EQ(at(a.image(), x, y), expected) << "pixel " << x << "," << y << " of tile " << t;
        }
    EXPECT_EQ(a.missing(), 7u);
}

TEST(Assembler, SameSizeKeepsLastFramesPixelsNewSizeClears) {
    FrameAssembler a;
    a.beginFrame(0, 16, 8, 8);
    ASSERT_TRUE(writeTile(a, 0, 1, colourOf(1)));
    a.beginFrame(1, 16, 8, 8);
    // A tile that never arrives shows last frame's pixels rather than black.
    EXPECT_EQ(at(a.image(), 15, 7), colourOf(1));
    EXPECT_EQ(a.missing(), 2u);

    a.beginFrame(2, 8, 16, 8);
    EXPECT_EQ(a.image().width, 8);
    for (uint8_t v : a.image().rgb) ASSERT_EQ(v, 0);
    a.beginFrame(3, 0, 0, 8);
    EXPECT_EQ(a.tiles().size(), 0u);
    EXPECT_TRUE(a.complete());
}

TEST(Assembler, ConcurrentClaimsGrantEachTileExactlyOnce) {
    constexpr int kThreads = 4;
    FrameAssembler a;
    for (uint32_t frame = 0; frame < 30; ++frame) {
        a.beginFrame(frame, 37, 23, 4);  // 10 x 6 tiles
        const uint32_t tiles = uint32_t(a.tiles().size());
        std::vector<std::atomic<int>> granted(tiles);
        std::vector<std::thread> threads;
        for (int id = 0; id < kThreads; ++id) {
            threads.emplace_back([&, id] {
                std::mt19937 rng(frame * 131 + uint32_t(id));
                // Every thread walks all tiles in its own order, twice; some decodes fail.
                for (int pass = 0; pass < 2; ++pass)
                    for (uint32_t k = 0; k < tiles; ++k) {
                        const uint32_t t = (k * 7 + uint32_t(id) * 31 + uint32_t(rng() % 3)) % tiles;
                        TileRect rect;
                        TileView view;
                        if (a.claim(frame, t, rect, view) != Claim::Granted) continue;
                        if (rng() % 5 == 0) {
                            a.release(t);
                            continue;
                        }
                        fill(rect, view, {uint8_t(id + 1), uint8_t(t), uint8_t(frame)});
                        granted[t].fetch_add(1);
                        a.commit(t);
                    }
                // Sweep up what failed or was skipped.
                for (uint32_t t = 0; t < tiles; ++t) {
                    TileRect rect;
                    TileView view;
                    if (a.claim(frame, t, rect, view) != Claim::Granted) continue;
                    fill(rect, view, {uint8_t(id + 1), uint8_t(t), uint8_t(frame)});
                    granted[t].fetch_add(1);
                    a.commit(t);
                }
            });
        }
        for (std::thread& th : threads) th.join();
        ASSERT_TRUE(a.complete()) << "frame " << frame;
        for (uint32_t t = 0; t < tiles; ++t) {
            ASSERT_EQ(granted[t].load(), 1) << "frame " << frame << " tile " << t;
            // One writer per tile: the whole tile carries one thread's colour.
            const TileRect& r = a.tiles()[t];
            const std::array<uint8_t, 3> first = at(a.image(), r.x0, r.y0);
            EXPECT_GE(first[0], 1);
            EXPECT_LE(first[0], kThreads);
            EXPECT_EQ(first[1], uint8_t(t));
            EXPECT_EQ(first[2], uint8_t(frame));
            for (int y = r.y0; y < r.y1; ++y)
                for (int x = r.x0; x < r.x1; ++x) ASSERT_EQ(at(a.image(), x, y), first);
        }
    }
}

// A multi-view frame (issue 18): each tile goes into its own view's image, at its place, and
// the frame completes when every view's tiles are in; the images are separate buffers.
TEST(Assembler, MultiViewFrameWritesEachTileIntoItsView) {
    std::vector<FrameView> views(2);
    views[1].regions = {{20, 0, 12, 8}};  // the right half of a 40x16 reference at 32x16: x 16..32
    views[1].refWidth = 40;
    views[1].refHeight = 16;
    const std::vector<ViewTile> tiles = viewTiles(views, 32, 16, 8);
    ASSERT_EQ(tiles.size(), 8u + 2u);  // view 0: all 4x2; view 1: the two tiles of x 16..32, row 0
    FrameAssembler a;
    a.beginFrame(5, 32, 16, tiles, 2);
    ASSERT_EQ(a.images().size(), 2u);
    for (uint32_t t = 0; t < tiles.size(); ++t) {
        EXPECT_EQ(a.viewOf(t), tiles[t].view);
        ASSERT_TRUE(writeTile(a, 5, t, colourOf(t)));
        EXPECT_EQ(a.complete(), t + 1 == tiles.size());
    }
    EXPECT_EQ(writeTile(a, 5, 8, colourOf(0)), false);  // each tile once
    EXPECT_EQ(at(a.image(0), 16, 0), colourOf(2));
    EXPECT_EQ(at(a.image(1), 16, 0), colourOf(8));
    EXPECT_EQ(at(a.image(1), 31, 7), colourOf(9));
    EXPECT_EQ(at(a.image(1), 0, 0), (std::array<uint8_t, 3>{0, 0, 0}));  // outside its region: never written
    // A later mono frame is one image again.
    a.beginFrame(6, 32, 16, 8);
    EXPECT_EQ(a.images().size(), 1u);
    EXPECT_EQ(a.tiles().size(), 8u);
    EXPECT_EQ(a.viewOf(7), 0u);
}

// Issue 27: with FrameHolding::depth each view has a depth buffer, written through the tile's
// claim (depthAt), and NaN wherever no tile of this frame wrote, even where the last frame's did
// (a stale depth would be a surface the warp moves that is no longer there).
TEST(Assembler, DepthBuffersPerViewAreHolesUntilATileWrites) {
    std::vector<FrameView> views(2);
    views[1].regions = {{20, 0, 12, 8}};  // x 16..32 of a 32x16 frame
    views[1].refWidth = 40;
    views[1].refHeight = 16;
    const std::vector<ViewTile> tiles = viewTiles(views, 32, 16, 8);
    FrameHolding holding;
    holding.depth = true;
    FrameAssembler a;
    for (uint32_t frame : {1u, 2u}) {
        a.beginFrame(frame, 32, 16, tiles, 2, holding);
        ASSERT_TRUE(a.depth());
        ASSERT_EQ(a.depthImages().size(), 2u);
        for (const std::vector<float>& d : a.depthImages()) {
            ASSERT_EQ(d.size(), size_t(32 * 16));
            for (float v : d) ASSERT_TRUE(std::isnan(v)) << "frame " << frame;
        }
        // Frame 1 writes every tile; frame 2 only view 1's first tile.
        for (uint32_t t = 0; t < tiles.size(); ++t) {
            if (frame == 2 && t != 8) continue;
            TileRect rect;
            TileView view;
            ASSERT_EQ(a.claim(frame, t, rect, view), Claim::Granted);
            for (int y = 0; y < rect.height(); ++y)
                for (int x = 0; x < rect.width(); ++x) a.depthAt(a.viewOf(t), rect.x0, rect.y0)[y * 32 + x] = float(t + 1);
            a.commit(t);
        }
    }
    const std::vector<float>& right = a.depthImages()[1];
    EXPECT_EQ(right[3 * 32 + 17], 9.0f);                // tile 8: x 16..24, y 0..8 of view 1
    EXPECT_TRUE(std::isnan(right[3 * 32 + 25]));        // tile 9, written in frame 1 only
    EXPECT_TRUE(std::isnan(right[3 * 32 + 2]));         // outside the view's region
    EXPECT_TRUE(std::isnan(a.depthImages()[0][0]));     // view 0: nothing this frame
    // Without depth there are no buffers.
    a.beginFrame(3, 32, 16, tiles, 2);
    EXPECT_FALSE(a.depth());
    EXPECT_TRUE(a.depthImages().empty());
}

// The tiling of a multi-view frame: view by view, only the tiles that meet a view's regions,
// with the regions scaled as the wall scales a smaller frame (rounded outwards).
TEST(FrameViews, TilesMeetScaledRegions) {
    EXPECT_EQ(viewTiles({}, 64, 64, 16).size(), 0u);
    std::vector<FrameView> views(3);
    EXPECT_EQ(viewTiles(views, 64, 32, 16).size(), 3 * 8u);  // no regions: the whole image each
    views[0].regions = {{0, 0, 1000, 500}};
    views[0].refWidth = 3000;
    views[0].refHeight = 500;
    views[1].regions = {{1000, 0, 1000, 500}};
    views[1].refWidth = 3000;
    views[1].refHeight = 500;
    views[2].regions = {{2000, 0, 1000, 250}};
    views[2].refWidth = 3000;
    views[2].refHeight = 500;
    // 96x32, tiles of 16: plane 0 covers x 0..32, plane 1 x 32..64, plane 2 x 64..96, y 0..16.
    const std::vector<ViewTile> t = viewTiles(views, 96, 32, 16);
    ASSERT_EQ(t.size(), 4u + 4u + 2u);
    EXPECT_EQ(t[0].view, 0u);
    EXPECT_EQ(t[4].view, 1u);
    EXPECT_EQ(t[4].rect.x0, 32);
    EXPECT_EQ(t[8].view, 2u);
    EXPECT_EQ(t[8].rect.x0, 64);
    EXPECT_EQ(t[9].rect.x1, 96);
    // A region edge inside a tile takes that tile; scaled, x0 rounds down and x1 up.
    const TileRect r = scaledRegion({1000, 0, 1000, 500}, 3000, 500, 100, 10);
    EXPECT_EQ(r.x0, 33);
    EXPECT_EQ(r.x1, 67);
    EXPECT_EQ(viewTiles({views[1]}, 100, 10, 16).size(), 3u);  // x 33..67 meets the tiles at 32, 48 and 64
    // A region outside the image, or an empty one, takes no tile; a bad reference size neither.
    FrameView none;
    none.regions = {{0, 0, 0, 0}};
    none.refWidth = 10;
    none.refHeight = 10;
    EXPECT_EQ(viewTiles({none}, 64, 64, 16).size(), 0u);
    none.refWidth = 0;
    none.regions = {{0, 0, 5, 5}};
    EXPECT_EQ(viewTiles({none}, 64, 64, 16).size(), 0u);
}

// A view's warps at a frame smaller than the wall (issue 30): rectangles scaled as regions are,
// screen offsets by image pixels per wall pixel (exactly 1 at the wall's size), grids shared
// (sent once, never copied per frame); a grid the client was not sent throws.
TEST(Views, FrameWarpsScaleRectanglesAndOffsetsToTheFrame) {
    auto grid = std::make_shared<const PixelWarp>(PixelWarp{PixelWarp::Kind::ScreenOffsets, 1, 1, {{2.0f, -1.0f, 0.0f}}});
    const std::vector<std::shared_ptr<const PixelWarp>> grids{nullptr, grid};
    FrameView v;
    v.refWidth = 1600;
    v.refHeight = 1200;
    RoomToWorld room;
    room.scale = 3.0f;
    v.warps = {{1, {800, 600, 800, 600}, room}};
    const std::vector<ScreenWarp> full = frameWarps(v, grids, 1600, 1200);
    ASSERT_EQ(full.size(), 1u);
    EXPECT_EQ(full[0].rect, (TileRect{800, 600, 1600, 1200}));
    EXPECT_EQ(full[0].warp.get(), grid.get());
    EXPECT_EQ(full[0].room, room);
    EXPECT_EQ(full[0].offsetScaleX, 1.0f);
    EXPECT_EQ(full[0].offsetScaleY, 1.0f);
    const std::vector<ScreenWarp> half = frameWarps(v, grids, 800, 400);
    EXPECT_EQ(half[0].rect, (TileRect{400, 200, 800, 400}));
    EXPECT_EQ(half[0].offsetScaleX, 0.5f);
    EXPECT_FLOAT_EQ(half[0].offsetScaleY, 1.0f / 3.0f);
    // Through the camera: the offset of 2 wall pixels is 1 frame pixel at half the width.
    CameraDesc c;
    const Camera flat(c, 800, 400), warped(c, 800, 400, half);
    const Float3 want = flat.direction(401.5f, 300.5f - 1.0f / 3.0f), got = warped.direction(400.5f, 300.5f);
    EXPECT_FLOAT_EQ(got.x, want.x);
    EXPECT_FLOAT_EQ(got.y, want.y);
    v.warps[0].grid = 0;  // null: never sent
    EXPECT_THROW(frameWarps(v, grids, 800, 400), std::out_of_range);
    v.warps[0].grid = 2;
    EXPECT_THROW(frameWarps(v, grids, 800, 400), std::out_of_range);
}

}  // namespace
}  // namespace rtwall
