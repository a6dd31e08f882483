// Frames and tiles on the wire: a frame's start with its views, tile requests and assignments,
// results (and acks for tiles that went to display nodes), stalled and failed tiles, routes.
#include "codec.h"
#include "protocol_values.h"

namespace rtwall::cluster {

RTWALL_WIRE_MESSAGE(FrameBegin, 6) {
    static const size_t viewBytes = minViewBytes();
    io.u32(m.frame);
    io.u32(m.updateSeq);
    io.enumUpTo(m.pixels, TilePixels::LinearHalf, "tile pixel format");
    vectorOf(io, m.views, viewBytes, kMaxViews);
    // Version 13: the views are the frame's only camera; a frame without one cannot be rendered.
    io.expect(!m.views.empty(), [&] { return "frame " + std::to_string(m.frame) + " has no view"; });
    // Version 14: depth with every tile, a byte at the end only when asked for.
    io.trailing(m.depth, [&] {
        io.boolean(m.depth);
        io.expect(m.depth, [] { return std::string("a depth flag that says no (it is left out then)"); });
    });
    // Version 16: the features every tile carries, a byte after the depth flag only when asked
    // for (never without depth or linear tiles).
    bool withFeatures = m.features != 0;
    io.trailing(withFeatures, [&] {
        io.u8(m.features);
        io.expect(m.features != 0 && m.features <= kFeatureAll,
                  [&] { return "feature bits " + std::to_string(int(m.features)) + " (1 to 7; none are left out)"; });
        io.expect(m.depth && m.pixels == TilePixels::LinearHalf,
                  [] { return std::string("features asked for without depth or linear tiles"); });
    });
}

RTWALL_WIRE_MESSAGE(TileRequest, 2) {
    io.u32(m.frame);
    io.u32(m.count);
    io.expect(m.count <= kMaxTilesPerMessage,
              [&] { return "tile request for " + std::to_string(m.count) + " tiles exceeds the limit"; });
}

RTWALL_WIRE_MESSAGE(TileAssign, 2) {
    io.u32(m.frame);
    io.sequence(m.tiles, sizeof(uint32_t), kMaxTilesPerMessage, [&](auto& t) { io.u32(t); });
}

// A half-float tile is encoded as an 8-bit tile twice as wide.
const size_t kMaxPixelBytes = maxEncodedTileBytes(2 * kMaxTileSize, kMaxTileSize);
const size_t kMaxDepthBytes = maxEncodedDepthBytes(kMaxTileSize, kMaxTileSize);
const size_t kMaxFeatureBytes = maxEncodedFeatureBytes(kMaxTileSize, kMaxTileSize);

size_t bytesOf(const std::vector<uint8_t>& v) { return v.size(); }
size_t bytesOf(const std::pair<const uint8_t*, size_t>& view) { return view.second; }

// A TileResult's fields with its pixels and depth as `pixels` and `depth`: vectors
// (decodePayload copies them) or views into the message (peekTileResult does not).
template <class Io, class Result, class Bytes>
void tileResultFields(Io& io, Result& m, Bytes& pixels, Bytes& depth, Bytes& features) {
    io.u32(m.frame);
    io.u32(m.tile);
    io.enumUpTo(m.codec, TileCodec::Jpeg, "tile codec");
    io.u32(m.renderMicros);
    io.blob(pixels, kMaxPixelBytes);
    io.enumUpTo(m.format, TilePixels::LinearHalf, "tile pixel format");
    // Version 14: the tile's depth (encodeDepthTile), at the end and only when the frame asked
    // for it: a tile without depth travels as in version 13.
    bool withDepth = bytesOf(depth) > 0;
    io.trailing(withDepth, [&] {
        io.blob(depth, kMaxDepthBytes);
        io.expect(bytesOf(depth) > 0, [] { return std::string("an empty depth field (it is left out then)"); });
    });
    // Version 16: its features (encodeFeatureTile), after the depth, only when asked for.
    bool withFeatures = bytesOf(features) > 0;
    io.trailing(withFeatures, [&] {
        io.blob(features, kMaxFeatureBytes);
        io.expect(bytesOf(features) > 0, [] { return std::string("an empty feature field (it is left out then)"); });
    });
}
RTWALL_WIRE_MESSAGE(TileResult, 8) { tileResultFields(io, m, m.pixels, m.depth, m.features); }

TileResultInfo peekTileResult(const uint8_t* data, size_t size) {
    Reader r(data, size);
    FieldReader io(r);
    TileResult m;  // all but the pixels and depth
    std::pair<const uint8_t*, size_t> pixels{}, depth{}, features{};
    tileResultFields(io, m, pixels, depth, features);
    r.expectEnd();
    return {m.frame, m.tile, m.renderMicros, uint32_t(pixels.second), uint32_t(depth.second), uint32_t(features.second)};
}

size_t maxTileResultBytes() { return kHeaderSize + 64 + kMaxPixelBytes + kMaxDepthBytes + kMaxFeatureBytes; }

RTWALL_WIRE_MESSAGE(TileStalled, 3) {
    io.u32(m.frame);
    io.u32(m.tile);
    io.u32(m.elapsedMs);
}

RTWALL_WIRE_COUNT(TileRect, 4);  // written with TileFailed
RTWALL_WIRE_MESSAGE(TileFailed, 5) {
    io.u32(m.frame);
    io.u32(m.tile);
    io.intIn(m.rect.x0, 0, kMaxImageSide - 1, "failed tile x0");
    io.intIn(m.rect.y0, 0, kMaxImageSide - 1, "failed tile y0");
    io.intIn(m.rect.x1, int64_t(m.rect.x0) + 1, kMaxImageSide, "failed tile x1");
    io.intIn(m.rect.y1, int64_t(m.rect.y0) + 1, kMaxImageSide, "failed tile y1");
    io.intIn(m.packetWidth, 4, 16, "packet width");
    io.expect(m.packetWidth == 4 || m.packetWidth == 8 || m.packetWidth == 16,
              [&] { return "packet width " + std::to_string(m.packetWidth) + " is not 4, 8 or 16"; });
    io.string(m.reason, kMaxStringBytes);
}

RTWALL_WIRE_MESSAGE(TileRoutes, 2) {
    io.u32(m.frame);
    io.sequence(m.masks, sizeof(uint64_t), kMaxTilesPerFrame, [&](auto& mask) { io.u64(mask); }, SendLimit::Strict);
}

RTWALL_WIRE_MESSAGE(TileDone, 4) {
    io.u32(m.frame);
    io.u32(m.tile);
    io.u32(m.renderMicros);
    io.u32(m.bytes);
}

}  // namespace rtwall::cluster
