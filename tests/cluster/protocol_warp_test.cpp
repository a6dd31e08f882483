// Calibrated projectors on the wire (issue 30, protocol version 18): WarpGrids, sent once per
// client, and the warps a frame's views name. NaN samples travel (a pixel on no screen);
// infinite ones, wrong counts and hostile sizes do not.
#include "protocol.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace rtwall::cluster {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

template <class Msg> std::vector<uint8_t> payloadOf(const Msg& msg) {
    const std::vector<uint8_t> bytes = encodeMessage(Header{}, msg);
    return std::vector<uint8_t>(bytes.begin() + kHeaderSize, bytes.end());
}

template <class Msg> Msg decode(const std::vector<uint8_t>& payload) { return decodePayload<Msg>(payload.data(), payload.size()); }

PixelWarp grid(int w, int h) {
    PixelWarp g;
    g.kind = PixelWarp::Kind::SurfacePoints;
    g.width = w;
    g.height = h;
    for (int i = 0; i < w * h; ++i) g.samples.push_back({float(i), -float(i), 0.5f});
    return g;
}

FrameBegin warpedFrame() {
    FrameView v;
    v.camera.fovY = 40.0f;
    v.refWidth = 1600;
    v.refHeight = 1200;
    v.warps = {{0, {0, 0, 800, 600}, {}}, {1, {800, 0, 800, 600}, {}}};
    return FrameBegin{5, 1, TilePixels::Srgb8, {v}};
}

TEST(ProtocolWarps, NaNSamplesArriveAsNaNAndTheOthersExactly) {
    WarpGrids m{{grid(3, 2)}};
    m.grids[0].samples[4] = {kNaN, kNaN, kNaN};
    m.grids[0].samples[1].y = kNaN;  // one component is enough to be off the screens
    const WarpGrids back = decode<WarpGrids>(payloadOf(m));
    ASSERT_EQ(back.grids.size(), 1u);
    ASSERT_EQ(back.grids[0].samples.size(), 6u);
    EXPECT_EQ(std::memcmp(back.grids[0].samples.data(), m.grids[0].samples.data(), 6 * sizeof(Float3)), 0) << "bit for bit";
    EXPECT_TRUE(std::isnan(back.grids[0].samples[4].x) && std::isnan(back.grids[0].samples[1].y));
}

TEST(ProtocolWarps, GridsWithInfiniteSamplesWrongCountsOrHostileSizesAreRefused) {
    const auto refused = [](WarpGrids m, const std::string& says) {
        try {
            decode<WarpGrids>(payloadOf(m));
            ADD_FAILURE() << "accepted: " << says;
        } catch (const DecodeError& e) {
            EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
        }
    };
    WarpGrids inf{{grid(2, 2)}};
    inf.grids[0].samples[3].z = std::numeric_limits<float>::infinity();
    refused(inf, "infinite");
    WarpGrids fewer{{grid(2, 2)}};
    fewer.grids[0].samples.pop_back();
    refused(fewer, "warp grid of 2x2 has 3 samples");
    WarpGrids wide{{grid(1, 1)}};
    wide.grids[0].width = int(kMaxWarpSide) + 1;
    refused(wide, "warp grid width");
    WarpGrids zero{{grid(1, 1)}};
    zero.grids[0].height = 0;
    refused(zero, "warp grid height");
    WarpGrids kind{{grid(1, 1)}};
    kind.grids[0].kind = PixelWarp::Kind(7);
    refused(kind, "unknown warp kind");
}

// A grid claiming 16384 x 4096 samples in a message of a few bytes: refused before anything is
// allocated for them (the count is checked against the bytes left first).
TEST(ProtocolWarps, AClaimedHugeGridAllocatesNothing) {
    WarpGrids m{{grid(1, 1)}};
    std::vector<uint8_t> p = payloadOf(m);
    // count u32, kind u8, width i32, height i32, samples count u32, samples...
    const int32_t w = 16384, h = 4096;
    const uint32_t n = uint32_t(w) * uint32_t(h);
    std::memcpy(&p[5], &w, 4);
    std::memcpy(&p[9], &h, 4);
    std::memcpy(&p[13], &n, 4);
    try {
        decode<WarpGrids>(p);
        ADD_FAILURE() << "accepted";
    } catch (const DecodeError& e) {
        EXPECT_NE(std::string(e.what()).find("does not fit"), std::string::npos) << e.what();
    }
}

TEST(ProtocolWarps, AFramesWarpsRoundTripAndBadReferencesAreRefused) {
    const FrameBegin good = warpedFrame();
    EXPECT_EQ(decode<FrameBegin>(payloadOf(good)), good);
    FrameBegin outside = good;
    outside.views[0].warps[1].rect.width = 801;
    EXPECT_THROW(decode<FrameBegin>(payloadOf(outside)), DecodeError);
    FrameBegin noReference = good;
    noReference.views[0].refWidth = 0;
    EXPECT_THROW(decode<FrameBegin>(payloadOf(noReference)), DecodeError);
    FrameBegin farGrid = good;
    farGrid.views[0].warps[0].grid = kMaxWarpGrids;
    EXPECT_THROW(decode<FrameBegin>(payloadOf(farGrid)), DecodeError);
    FrameBegin scale = good;
    scale.views[0].warps[0].room.scale = 0.0f;
    EXPECT_THROW(decode<FrameBegin>(payloadOf(scale)), DecodeError);
    FrameBegin nanRoom = good;
    nanRoom.views[0].warps[0].room.origin.y = kNaN;
    EXPECT_THROW(decode<FrameBegin>(payloadOf(nanRoom)), DecodeError);
}

}  // namespace
}  // namespace rtwall::cluster
