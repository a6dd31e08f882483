// libFuzzer target for every decoder that reads bytes from the network: the message header,
// every message payload, canonical meshes and the four tile codecs.
//
// Input layout: the first byte picks the decoder (its value modulo fuzz::kSelectors, in
// protocol_selectors.h), the rest is its input.
//   0      a whole message: decodeHeader, then the payload decoder its type names
//   1..27  decodePayload<T> for MsgType(n)
//   28     decodeMesh
//   29..32 decodeTile for TileCodec(n - 29); three more bytes give the width (1 + b % 64),
//          the height (1 + b % 64) and the destination's row padding (b % 8)
//   33..34 decodeWideTile (linear half-float tiles) for LZ4 and zstd, the same three bytes
// (Until issue 26 the selectors were taken modulo 25 and the mesh and tile numbers sat among the
// message types, so the mesh and tile decoders were never reached; make_protocol_corpus writes
// the seeds with these numbers.)
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
#include "protocol_selectors.h"

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
        info.pixelBytes != msg.pixels.size() || info.depthBytes != msg.depth.size() ||
        info.featureBytes != msg.features.size())
        finding("peekTileResult disagrees with decodePayload<TileResult>");
    const std::vector<uint8_t> again = encodeMessage(Header{}, msg);
    if (again.size() != kHeaderSize + size || std::memcmp(again.data() + kHeaderSize, data, size) != 0)
        finding("a decoded payload does not re-encode to the same bytes");
}

template <class Msg> void checkMessage(const Header& header, const uint8_t* data, size_t size) {
    const Msg msg = decodeMessage<Msg>(data, size);
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
// In MsgType order, 1..32.
using Messages = Table<Hello, Welcome, SceneSnapshot, MeshRequest, MeshData, Update, FrameBegin, TileRequest,
                       TileAssign, TileResult, Heartbeat, Goodbye, Ready, ResyncRequest, AssetRequest, AssetData,
                       TileStalled, TileFailed, NodeHello, NodeWelcome, NodeFrame, NodeHave, NodeSwap, NodeSwapped,
                       NodeList, TileRoutes, TileDone, NodePose, NodeShown, WarpGrids, NodePreviewAsk,
                       NodePreview>;
static_assert(std::size(Messages::payload) == kMaxMsgType);

void checkMesh(const uint8_t* data, size_t size) {
    const TriangleMesh mesh = decodeMesh(data, size);
    const std::vector<uint8_t> again = encodeMesh(mesh);
    if (again.size() != size || std::memcmp(again.data(), data, size) != 0)
        finding("a decoded mesh does not re-encode to the same bytes");
}

// The three bytes before a tile: its width and height (1 to 64) and the destination's row padding
// (0 to 7 elements).
struct TileInput {
    int width = 0, height = 0;
    size_t rowElements = 0, stride = 0;  // 3 a pixel
    const uint8_t* data = nullptr;
    size_t size = 0;
};

bool readTileInput(const uint8_t* data, size_t size, TileInput& t) {
    if (size < 3) return false;
    t.width = 1 + data[0] % 64;
    t.height = 1 + data[1] % 64;
    t.rowElements = size_t(t.width) * 3;
    t.stride = t.rowElements + data[2] % 8;
    t.data = data + 3;
    t.size = size - 3;
    return true;
}

// A destination exactly as large as the tile needs (the last row has no padding), so that
// AddressSanitizer sees any write past the end; the padding between rows is checked by hand.
template <class T> std::vector<T> guardedTile(const TileInput& t, T guard) {
    return std::vector<T>(t.stride * size_t(t.height - 1) + t.rowElements, guard);
}

template <class T> void checkPadding(const std::vector<T>& dst, const TileInput& t, T guard, const char* what) {
    for (int y = 0; y + 1 < t.height; ++y)
        for (size_t i = t.rowElements; i < t.stride; ++i)
            if (dst[size_t(y) * t.stride + i] != guard) finding(what);
}

void checkTile(TileCodec codec, const uint8_t* data, size_t size) {
    TileInput t;
    if (!readTileInput(data, size, t)) return;
    constexpr uint8_t kGuard = 0xA5;
    std::vector<uint8_t> dst = guardedTile(t, kGuard);
    decodeTile(codec, t.data, t.size, t.width, t.height, dst.data(), t.stride);
    checkPadding(dst, t, kGuard, "decodeTile wrote into the row padding");

    // A lossless tile that decodes must survive its own codec unchanged.
    if (codec == TileCodec::Lz4 || codec == TileCodec::Zstd) {
        CodecSettings settings;
        settings.codec = codec;
        std::vector<uint8_t> encoded;
        encodeTile(settings, dst.data(), t.width, t.height, t.stride, encoded);
        std::vector<uint8_t> back(t.rowElements * size_t(t.height));
        decodeTile(codec, encoded.data(), encoded.size(), t.width, t.height, back.data(), t.rowElements);
        for (int y = 0; y < t.height; ++y)
            if (std::memcmp(back.data() + size_t(y) * t.rowElements, dst.data() + size_t(y) * t.stride, t.rowElements) != 0)
                finding("a lossless tile does not survive a round trip");
    }
}

void checkWideTile(TileCodec codec, const uint8_t* data, size_t size) {
    TileInput t;
    if (!readTileInput(data, size, t)) return;
    const float kGuard = -7.0f;
    std::vector<float> dst = guardedTile(t, kGuard);
    std::vector<uint8_t> scratch;
    decodeWideTile(codec, t.data, t.size, t.width, t.height, dst.data(), t.stride, scratch);
    checkPadding(dst, t, kGuard, "decodeWideTile wrote into the row padding");
}

// A feature tile (width - 1, height - 1, feature bits in the low 3 bits of the third byte, 0
// meaning all, then the compressed features) decodes into its tile and nowhere else.
void checkFeatureTile(const uint8_t* data, size_t size) {
    if (size < 3) return;
    const int w = data[0] % 64 + 1, h = data[1] % 64 + 1;
    const uint8_t bits = (data[2] & 7) ? uint8_t(data[2] & 7) : uint8_t(kFeatureAll);
    const size_t stride = size_t(w) + 3, rows = size_t(h);
    const float kGuard = -7.0f;
    std::vector<float> albedo(stride * rows * 3, kGuard), normal(stride * rows * 3, kGuard);
    std::vector<uint32_t> id(stride * rows, 0xDEADBEEFu);
    std::vector<uint8_t> scratch;
    decodeFeatureTile(bits, data + 3, size - 3, w, h, {albedo.data(), normal.data(), id.data(), stride}, scratch);
    for (size_t y = 0; y < rows; ++y)
        for (size_t x = size_t(w); x < stride; ++x) {
            if (id[y * stride + x] != 0xDEADBEEFu) finding("decodeFeatureTile wrote an id into the row padding");
            for (int c = 0; c < 3; ++c)
                if (albedo[(y * stride + x) * 3 + size_t(c)] != kGuard || normal[(y * stride + x) * 3 + size_t(c)] != kGuard)
                    finding("decodeFeatureTile wrote into the row padding");
        }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    const unsigned selector = data[0] % fuzz::kSelectors;
    ++data;
    --size;
    try {
        if (selector == fuzz::kWholeMessage) {
            const Header header = decodeHeader(data, size);
            Messages::message[size_t(header.type) - 1](header, data, size);
        } else if (selector < fuzz::kMesh) {
            Messages::payload[selector - fuzz::kFirstPayload](data, size);
        } else if (selector == fuzz::kMesh) {
            checkMesh(data, size);
        } else if (selector < fuzz::kWideTile) {
            checkTile(TileCodec(selector - fuzz::kTile), data, size);
        } else if (selector < fuzz::kFeatureTile) {
            checkWideTile(selector == fuzz::kWideTile ? TileCodec::Lz4 : TileCodec::Zstd, data, size);
        } else {
            checkFeatureTile(data, size);
        }
    } catch (const DecodeError&) {
        // The expected outcome for malformed input.
    }
    return 0;
}
