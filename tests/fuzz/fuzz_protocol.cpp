// libFuzzer target for every decoder that reads bytes from the network: the message header,
// every message payload, canonical meshes and the four tile codecs.
//
// Input layout: the first byte picks the decoder (its value modulo 25), the rest is its input.
//   0      a whole message: decodeHeader, then the payload decoder its type names
//   1..17  decodePayload<T> for MsgType(n)
//   18     decodeMesh
//   19..22 decodeTile for TileCodec(n - 19); three more bytes give the width (1 + b % 64),
//          the height (1 + b % 64) and the destination's row padding (b % 8)
//   23..24 decodeWideTile (linear half-float tiles) for LZ4 and zstd, the same three bytes
// (Protocol version 4 moved the mesh and tile selectors up by 2, version 7 by 1 more;
// make_protocol_corpus writes the seeds with the new ones.)
// Besides the sanitizers, the target checks that whatever decodes re-encodes to the very same
// bytes (the encodings are canonical) and that decodeTile writes no byte outside the tile.
// Only DecodeError is an expected outcome; any other exception aborts as a finding.
//
// Build by hand with clang 14 (from the repository root; no CMake needed):
//   mkdir -p build-fuzz
//   clang++-14 -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
//     -Icluster/src -Icluster/include -Iengine/include -Imesh/include -Iengine/core/include \
//     tests/fuzz/fuzz_protocol.cpp cluster/src/wire.cpp cluster/src/protocol_*.cpp cluster/src/codec.cpp \
//     mesh/src/triangle_mesh.cpp engine/src/half.cpp -llz4 -lzstd -lturbojpeg -lxxhash -o build-fuzz/fuzz_protocol
// Run (new inputs go to the first directory, the committed seeds are only read):
//   mkdir -p build-fuzz/corpus
//   build-fuzz/fuzz_protocol -max_total_time=120 -malloc_limit_mb=256 -timeout=10 \
//     build-fuzz/corpus tests/fuzz/corpus/protocol
// Reproduce a finding: build-fuzz/fuzz_protocol crash-<hash>
//
// With CMake instead: configure with -DCMAKE_CXX_COMPILER=clang++-14 -DRTWALL_FUZZ=ON and build
// the target fuzz_protocol (tests/fuzz/CMakeLists.txt); make_protocol_corpus regenerates the seeds:
//   build/tests/fuzz/make_protocol_corpus tests/fuzz/corpus/protocol
#include "codec.h"
#include "protocol.h"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

using namespace rtwall;
using namespace rtwall::cluster;

namespace {

[[noreturn]] void finding(const char* what) {
    std::fprintf(stderr, "fuzz_protocol: %s\n", what);
    std::abort();
}

template <class Msg> void checkPayload(const uint8_t* data, size_t size) {
    const Msg msg = decodePayload<Msg>(data, size);
    const std::vector<uint8_t> again = encodeMessage(Header{}, msg);
    if (again.size() != kHeaderSize + size || std::memcmp(again.data() + kHeaderSize, data, size) != 0)
        finding("a decoded payload does not re-encode to the same bytes");
}

// peekTileResult reads the same layout without copying the pixels: it must agree with the decoder.
template <> void checkPayload<TileResult>(const uint8_t* data, size_t size) {
    const TileResult msg = decodePayload<TileResult>(data, size);
    const TileResultInfo info = peekTileResult(data, size);
    if (info.frame != msg.frame || info.tile != msg.tile || info.renderMicros != msg.renderMicros ||
        info.pixelBytes != msg.pixels.size())
        finding("peekTileResult disagrees with decodePayload<TileResult>");
    const std::vector<uint8_t> again = encodeMessage(Header{}, msg);
    if (again.size() != kHeaderSize + size || std::memcmp(again.data() + kHeaderSize, data, size) != 0)
        finding("a decoded payload does not re-encode to the same bytes");
}

template <class Msg> void checkMessage(const Header& header, const uint8_t* data, size_t size) {
    const Msg msg = decodePayload<Msg>(data + kHeaderSize, size - kHeaderSize);
    const std::vector<uint8_t> again = encodeMessage(header, msg);
    if (again.size() != size || std::memcmp(again.data(), data, size) != 0)
        finding("a decoded message does not re-encode to the same bytes");
}

using PayloadCheck = void (*)(const uint8_t*, size_t);
using MessageCheck = void (*)(const Header&, const uint8_t*, size_t);

template <class... Msgs> struct Table {
    static constexpr PayloadCheck payload[] = {checkPayload<Msgs>...};
    static constexpr MessageCheck message[] = {checkMessage<Msgs>...};
};
// In MsgType order, 1..27.
using Messages = Table<Hello, Welcome, SceneSnapshot, MeshRequest, MeshData, Update, FrameBegin, TileRequest,
                       TileAssign, TileResult, Heartbeat, Goodbye, Ready, ResyncRequest, AssetRequest, AssetData,
                       TileStalled, TileFailed, NodeHello, NodeWelcome, NodeFrame, NodeHave, NodeSwap, NodeSwapped,
                       NodeList, TileRoutes, TileDone>;
static_assert(std::size(Messages::payload) == kMaxMsgType);

void checkMesh(const uint8_t* data, size_t size) {
    const TriangleMesh mesh = decodeMesh(data, size);
    const std::vector<uint8_t> again = encodeMesh(mesh);
    if (again.size() != size || std::memcmp(again.data(), data, size) != 0)
        finding("a decoded mesh does not re-encode to the same bytes");
}

void checkTile(TileCodec codec, const uint8_t* data, size_t size) {
    if (size < 3) return;
    const int width = 1 + data[0] % 64, height = 1 + data[1] % 64;
    const size_t rowBytes = size_t(width) * 3, stride = rowBytes + data[2] % 8;
    data += 3;
    size -= 3;
    // Exactly as large as the tile needs (the last row has no padding), so AddressSanitizer sees
    // any write past the end; the padding between rows is checked by hand.
    constexpr uint8_t kGuard = 0xA5;
    std::vector<uint8_t> dst(stride * size_t(height - 1) + rowBytes, kGuard);
    decodeTile(codec, data, size, width, height, dst.data(), stride);
    for (int y = 0; y + 1 < height; ++y)
        for (size_t i = rowBytes; i < stride; ++i)
            if (dst[size_t(y) * stride + i] != kGuard) finding("decodeTile wrote into the row padding");

    // A lossless tile that decodes must survive its own codec unchanged.
    if (codec == TileCodec::Lz4 || codec == TileCodec::Zstd) {
        CodecSettings settings;
        settings.codec = codec;
        std::vector<uint8_t> encoded;
        encodeTile(settings, dst.data(), width, height, stride, encoded);
        std::vector<uint8_t> back(rowBytes * size_t(height));
        decodeTile(codec, encoded.data(), encoded.size(), width, height, back.data(), rowBytes);
        for (int y = 0; y < height; ++y)
            if (std::memcmp(back.data() + size_t(y) * rowBytes, dst.data() + size_t(y) * stride, rowBytes) != 0)
                finding("a lossless tile does not survive a round trip");
    }
}

void checkWideTile(TileCodec codec, const uint8_t* data, size_t size) {
    if (size < 3) return;
    const int width = 1 + data[0] % 64, height = 1 + data[1] % 64;
    const size_t rowFloats = size_t(width) * 3, stride = rowFloats + data[2] % 8;
    data += 3;
    size -= 3;
    // Exactly as large as the tile needs (no padding after the last row), padding checked by hand.
    const float kGuard = -7.0f;
    std::vector<float> dst(stride * size_t(height - 1) + rowFloats, kGuard);
    std::vector<uint8_t> scratch;
    decodeWideTile(codec, data, size, width, height, dst.data(), stride, scratch);
    for (int y = 0; y + 1 < height; ++y)
        for (size_t i = rowFloats; i < stride; ++i)
            if (dst[size_t(y) * stride + i] != kGuard) finding("decodeWideTile wrote into the row padding");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    const unsigned selector = data[0] % 25u;
    ++data;
    --size;
    try {
        if (selector == 0) {
            const Header header = decodeHeader(data, size);
            Messages::message[size_t(header.type) - 1](header, data, size);
        } else if (selector <= kMaxMsgType) {
            Messages::payload[selector - 1](data, size);
        } else if (selector == 18) {
            checkMesh(data, size);
        } else if (selector <= 22) {
            checkTile(TileCodec(selector - 19), data, size);
        } else {
            checkWideTile(selector == 23 ? TileCodec::Lz4 : TileCodec::Zstd, data, size);
        }
    } catch (const DecodeError&) {
        // The expected outcome for malformed input.
    }
    return 0;
}
