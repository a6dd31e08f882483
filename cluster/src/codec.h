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

// Upper bound of an encoded tile's size, for ZMQ_MAXMSGSIZE.
size_t maxEncodedTileBytes(int width, int height);

const char* codecName(TileCodec codec);

}  // namespace rtwall::cluster
