// Tile pixel codecs: 8-bit sRGB RGB tiles, compressed per session with raw, LZ4, zstd or JPEG.
#pragma once

#include <rtwall/cluster.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rtwall::cluster {

// Encodes a width x height RGB8 tile (rows `stride` bytes apart) and appends the bytes to out.
void encodeTile(const CodecSettings& codec, const uint8_t* rgb, int width, int height, size_t stride,
                std::vector<uint8_t>& out);

// Decodes into dst (rows dstStride bytes apart), which must hold width x height RGB8 pixels.
// Throws DecodeError when the data is malformed or does not decode to exactly that size;
// never writes outside dst.
void decodeTile(TileCodec codec, const uint8_t* data, size_t size, int width, int height, uint8_t* dst,
                size_t dstStride);

// Linear RGB tiles for accumulated frames: each float rounded to an IEEE half (roundToHalf),
// stored as two byte planes (all low bytes, then all high bytes: the high bytes of neighbouring
// pixels repeat, which the compressors find), then compressed with a lossless codec as if it
// were an 8-bit tile twice as wide. JPEG would defeat the purpose: it becomes LZ4 (wideCodec).
TileCodec wideCodec(TileCodec codec);
float roundToHalf(float v);
// `stride` and `dstStride` count floats. `scratch` is reused between calls (no allocation per tile).
void encodeWideTile(const CodecSettings& codec, const float* rgb, int width, int height, size_t stride,
                    std::vector<uint8_t>& scratch, std::vector<uint8_t>& out);
// Throws DecodeError as decodeTile; never writes outside dst.
void decodeWideTile(TileCodec codec, const uint8_t* data, size_t size, int width, int height, float* dst,
                    size_t dstStride, std::vector<uint8_t>& scratch);

// A tile's depth (issue 27): each float through the 16-bit log code of rtwall/depth_codec.h
// (background and holes keep their codes), stored as two byte planes (all low bytes, then all
// high bytes: neighbouring pixels share their high bytes, which the compressor finds), then
// compressed with kDepthCodec. Lossless after the 16-bit code: decoding gives exactly
// decodeDepth(encodeDepth(d)) for every pixel. `stride` and `dstStride` count floats.
// kDepthCodec: zstd at level 1 (docs/benchmarks.md, "Depth with every tile"): on the demo scene
// at 1600x1200 in 64-pixel tiles it sends 0.47 MB of depth per frame against LZ4's 0.65 MB
// (28% less), for about 0.01 ms more per tile to encode.
inline constexpr TileCodec kDepthCodec = TileCodec::Zstd;
inline constexpr int kDepthZstdLevel = 1;
void encodeDepthTile(TileCodec codec, const float* depth, int width, int height, size_t stride,
                     std::vector<uint8_t>& scratch, std::vector<uint8_t>& out);
// Throws DecodeError when the data is malformed or does not decode to exactly width x height
// codes; never writes outside dst.
void decodeDepthTile(TileCodec codec, const uint8_t* data, size_t size, int width, int height, float* dst,
                     size_t dstStride, std::vector<uint8_t>& scratch);

// A tile's features for the denoiser (issue 28): the bytes of rtwall/feature_codec.h
// (encodeFeatures: planar, 11 bytes a pixel with every feature), compressed with kDepthCodec.
// `stride` and `dstStride` count pixels; `view` gives the source or destination buffers.
void encodeFeatureTile(uint8_t bits, const FeatureView& view, int width, int height, std::vector<uint8_t>& scratch,
                       std::vector<uint8_t>& out);
// Throws DecodeError when the data is malformed or does not decode to exactly width x height
// pixels of those features; never writes outside the view's buffers.
void decodeFeatureTile(uint8_t bits, const uint8_t* data, size_t size, int width, int height, const FeatureView& view,
                       std::vector<uint8_t>& scratch);

// A display node's picture cells (issue 31, NodePreview): `cells` x 4 values (red, green, blue
// sums and pixel count), each `valueBytes` bytes (1, 2 or 4: previewValueBytes of the largest),
// stored as byte planes (every value's low byte, then the next) and compressed with zstd at
// level 1. Decoding checks the stream decodes to exactly that many bytes (DecodeError).
int previewValueBytes(uint32_t largest);
void encodePreviewCells(const uint32_t* values, size_t cells, int valueBytes, std::vector<uint8_t>& out,
                        std::vector<uint8_t>& scratch);
void decodePreviewCells(const uint8_t* data, size_t size, size_t cells, int valueBytes, uint32_t* values,
                        std::vector<uint8_t>& scratch);

// Upper bound of an encoded tile's size, for ZMQ_MAXMSGSIZE.
size_t maxEncodedTileBytes(int width, int height);
// The same for a tile's encoded depth.
size_t maxEncodedDepthBytes(int width, int height);
size_t maxEncodedFeatureBytes(int width, int height);

const char* codecName(TileCodec codec);

}  // namespace rtwall::cluster
