#include "codec.h"

#include "wire.h"

#include <rtwall/depth_codec.h>
#include <rtwall/feature_codec.h>

#include <lz4.h>
#include <turbojpeg.h>
#include <zstd.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

namespace rtwall::cluster {

namespace {

// The largest tile side accepted; the image itself is limited to 16384 pixels a side, so a
// tile is never larger, and this keeps every size below LZ4's and TurboJPEG's int limits.
constexpr int kMaxTileSide = 16384;

// Encoded tiles carry no header of their own: the TileResult names the codec and the master
// knows the tile's size, so each codec's stream is checked against that size instead.

size_t tileBytes(int width, int height, size_t stride, const char* what) {
    // Bad sizes here are the caller's mistake, not the peer's, hence invalid_argument.
    if (width < 1 || height < 1 || width > kMaxTileSide || height > kMaxTileSide)
        throw std::invalid_argument(std::string(what) + ": tile size " + std::to_string(width) + "x" +
                                    std::to_string(height) + " is out of range");
    const size_t rowBytes = size_t(width) * 3;
    if (stride < rowBytes || stride > size_t(INT_MAX))
        throw std::invalid_argument(std::string(what) + ": stride " + std::to_string(stride) + " for rows of " +
                                    std::to_string(rowBytes) + " bytes");
    return rowBytes * size_t(height);
}

struct TjDeleter {
    void operator()(void* handle) const { tjDestroy(handle); }
};
struct ZstdCDeleter {
    void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};
struct ZstdDDeleter {
    void operator()(ZSTD_DCtx* d) const { ZSTD_freeDCtx(d); }
};

// One context per thread and use: creating them costs allocations on every tile otherwise,
// and none of them may be shared between threads.
tjhandle jpegCompressor() {
    thread_local std::unique_ptr<void, TjDeleter> handle(tjInitCompress());
    if (!handle) throw std::runtime_error("TurboJPEG: cannot create a compressor");
    return handle.get();
}

tjhandle jpegDecompressor() {
    thread_local std::unique_ptr<void, TjDeleter> handle(tjInitDecompress());
    if (!handle) throw std::runtime_error("TurboJPEG: cannot create a decompressor");
    return handle.get();
}

ZSTD_CCtx* zstdCompressor() {
    thread_local std::unique_ptr<ZSTD_CCtx, ZstdCDeleter> ctx(ZSTD_createCCtx());
    if (!ctx) throw std::runtime_error("zstd: cannot create a compression context");
    return ctx.get();
}

ZSTD_DCtx* zstdDecompressor() {
    thread_local std::unique_ptr<ZSTD_DCtx, ZstdDDeleter> ctx(ZSTD_createDCtx());
    if (!ctx) throw std::runtime_error("zstd: cannot create a decompression context");
    return ctx.get();
}

// LZ4 or zstd: appends the compressed bytes of src[0, n) to out.
void compress(TileCodec codec, int zstdLevel, const uint8_t* src, size_t n, std::vector<uint8_t>& out) {
    const size_t start = out.size();
    if (codec == TileCodec::Lz4) {
        const int bound = LZ4_compressBound(int(n));
        out.resize(start + size_t(bound));
        const int written = LZ4_compress_default(reinterpret_cast<const char*>(src),
                                                 reinterpret_cast<char*>(out.data() + start), int(n), bound);
        if (written <= 0) {
            out.resize(start);
            throw std::runtime_error("LZ4: compression failed");
        }
        out.resize(start + size_t(written));
        return;
    }
    const size_t bound = ZSTD_compressBound(n);
    out.resize(start + bound);
    const size_t written = ZSTD_compressCCtx(zstdCompressor(), out.data() + start, bound, src, n, zstdLevel);
    if (ZSTD_isError(written)) {
        out.resize(start);
        throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(written));
    }
    out.resize(start + written);
}

// The way back, into exactly n bytes at dst; anything else is a DecodeError naming `what`.
void decompress(TileCodec codec, const uint8_t* data, size_t size, uint8_t* dst, size_t n, const char* what) {
    if (codec == TileCodec::Lz4) {
        // Any valid stream for this tile is at most the bound; this also keeps size within int.
        if (size == 0 || size > size_t(LZ4_compressBound(int(n))))
            throw DecodeError(std::string("LZ4 ") + what + " of " + std::to_string(size) + " bytes for " +
                              std::to_string(n) + " bytes");
        const int got =
            LZ4_decompress_safe(reinterpret_cast<const char*>(data), reinterpret_cast<char*>(dst), int(size), int(n));
        if (got < 0 || size_t(got) != n)
            throw DecodeError(std::string("LZ4 ") + what + " does not decode to " + std::to_string(n) + " bytes");
        return;
    }
    const unsigned long long content = ZSTD_getFrameContentSize(data, size);
    if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN || content != n)
        throw DecodeError(std::string("zstd ") + what + " does not declare " + std::to_string(n) + " bytes");
    // Exactly one frame: trailing frames or bytes would be ignored data.
    const size_t frame = ZSTD_findFrameCompressedSize(data, size);
    if (ZSTD_isError(frame) || frame != size) throw DecodeError(std::string("zstd ") + what + " is not exactly one frame");
    const size_t got = ZSTD_decompressDCtx(zstdDecompressor(), dst, n, data, size);
    if (ZSTD_isError(got)) throw DecodeError(std::string("zstd ") + what + ": " + ZSTD_getErrorName(got));
    if (got != n) throw DecodeError(std::string("zstd ") + what + " does not decode to " + std::to_string(n) + " bytes");
}

// The rows packed without padding; a view of the input when it already is.
const uint8_t* packed(const uint8_t* rgb, int width, int height, size_t stride, std::vector<uint8_t>& scratch) {
    const size_t rowBytes = size_t(width) * 3;
    if (stride == rowBytes) return rgb;
    scratch.resize(rowBytes * size_t(height));
    for (int y = 0; y < height; ++y) std::memcpy(scratch.data() + y * rowBytes, rgb + y * stride, rowBytes);
    return scratch.data();
}

void unpack(const uint8_t* src, int width, int height, uint8_t* dst, size_t dstStride) {
    const size_t rowBytes = size_t(width) * 3;
    for (int y = 0; y < height; ++y) std::memcpy(dst + y * dstStride, src + y * rowBytes, rowBytes);
}

int jpegSubsampling(const CodecSettings& codec) { return codec.jpegSubsample ? TJSAMP_420 : TJSAMP_444; }

size_t jpegBufferBound(int width, int height, int subsampling) {
    const unsigned long bound = tjBufSize(width, height, subsampling);
    if (bound == static_cast<unsigned long>(-1)) throw std::invalid_argument("TurboJPEG: tile too large");
    return bound;
}

}  // namespace

void encodeTile(const CodecSettings& codec, const uint8_t* rgb, int width, int height, size_t stride,
                std::vector<uint8_t>& out) {
    const size_t n = tileBytes(width, height, stride, "encodeTile");
    // Settings arrive validated (the Welcome decoder checks them); anything else is a caller's bug.
    if (codec.codec == TileCodec::Jpeg && (codec.jpegQuality < 1 || codec.jpegQuality > 100))
        throw std::invalid_argument("encodeTile: JPEG quality " + std::to_string(codec.jpegQuality));
    if (codec.codec == TileCodec::Zstd && (codec.zstdLevel < 1 || codec.zstdLevel > 19))
        throw std::invalid_argument("encodeTile: zstd level " + std::to_string(codec.zstdLevel));
    const size_t start = out.size();
    std::vector<uint8_t> scratch;
    switch (codec.codec) {
        case TileCodec::Raw: {
            out.reserve(start + n);
            const size_t rowBytes = size_t(width) * 3;
            for (int y = 0; y < height; ++y) out.insert(out.end(), rgb + y * stride, rgb + y * stride + rowBytes);
            return;
        }
        case TileCodec::Lz4:
        case TileCodec::Zstd:
            compress(codec.codec, codec.zstdLevel, packed(rgb, width, height, stride, scratch), n, out);
            return;
        case TileCodec::Jpeg: {
            // Compressed straight into `out`, sized to TurboJPEG's worst case, without a copy.
            const int subsampling = jpegSubsampling(codec);
            const size_t bound = jpegBufferBound(width, height, subsampling);
            out.resize(start + bound);
            tjhandle tj = jpegCompressor();
            unsigned char* dst = out.data() + start;
            unsigned long written = bound;
            if (tjCompress2(tj, rgb, width, int(stride), height, TJPF_RGB, &dst, &written, subsampling,
                            codec.jpegQuality, TJFLAG_NOREALLOC | TJFLAG_ACCURATEDCT) != 0) {
                out.resize(start);
                throw std::runtime_error(std::string("TurboJPEG: ") + tjGetErrorStr2(tj));
            }
            out.resize(start + written);
            return;
        }
    }
    throw std::invalid_argument("encodeTile: unknown codec " + std::to_string(int(codec.codec)));
}

void decodeTile(TileCodec codec, const uint8_t* data, size_t size, int width, int height, uint8_t* dst,
                size_t dstStride) {
    const size_t n = tileBytes(width, height, dstStride, "decodeTile");
    const size_t rowBytes = size_t(width) * 3;
    if (uint8_t(codec) > uint8_t(TileCodec::Jpeg))
        throw DecodeError("unknown tile codec " + std::to_string(int(codec)));
    // LZ4 and zstd decompress straight into dst when its rows are contiguous, otherwise through
    // one scratch tile, so memory stays at most twice the tile whatever the input claims.
    std::vector<uint8_t> scratch;
    uint8_t* target = dst;
    if (dstStride != rowBytes && (codec == TileCodec::Lz4 || codec == TileCodec::Zstd)) {
        scratch.resize(n);
        target = scratch.data();
    }
    switch (codec) {
        case TileCodec::Raw:
            if (size != n)
                throw DecodeError("raw tile of " + std::to_string(size) + " bytes, expected " + std::to_string(n));
            for (int y = 0; y < height; ++y) std::memcpy(dst + y * dstStride, data + y * rowBytes, rowBytes);
            return;
        case TileCodec::Lz4:
        case TileCodec::Zstd:
            decompress(codec, data, size, target, n, "tile");
            break;
        case TileCodec::Jpeg: {
            tjhandle tj = jpegDecompressor();
            int w = 0, h = 0, subsampling = 0, colorspace = 0;
            if (size == 0 || tjDecompressHeader3(tj, data, size, &w, &h, &subsampling, &colorspace) != 0)
                throw DecodeError(std::string("JPEG tile header: ") + tjGetErrorStr2(tj));
            // TurboJPEG would scale a different size to fit; the tile must be exactly this size.
            if (w != width || h != height)
                throw DecodeError("JPEG tile is " + std::to_string(w) + "x" + std::to_string(h) + ", expected " +
                                  std::to_string(width) + "x" + std::to_string(height));
            // Warnings (truncated data, corrupt segments) are errors here, and the scan limit guards
            // against progressive streams built to take unbounded time.
            if (tjDecompress2(tj, data, size, dst, width, int(dstStride), height, TJPF_RGB,
                              TJFLAG_STOPONWARNING | TJFLAG_LIMITSCANS | TJFLAG_ACCURATEDCT) != 0)
                throw DecodeError(std::string("JPEG tile: ") + tjGetErrorStr2(tj));
            return;
        }
    }
    if (target != dst) unpack(target, width, height, dst, dstStride);
}

TileCodec wideCodec(TileCodec codec) { return codec == TileCodec::Jpeg ? TileCodec::Lz4 : codec; }

float roundToHalf(float v) { return floatFromHalf(halfFromFloat(v)); }

void encodeWideTile(const CodecSettings& codec, const float* rgb, int width, int height, size_t stride,
                    std::vector<uint8_t>& scratch, std::vector<uint8_t>& out) {
    if (width < 1 || height < 1 || width > kMaxTileSide / 2 || height > kMaxTileSide || stride < size_t(width) * 3)
        throw std::invalid_argument("encodeWideTile: tile size " + std::to_string(width) + "x" + std::to_string(height));
    const size_t values = size_t(width) * height * 3, rowValues = size_t(width) * 3;
    scratch.resize(2 * values);  // the two byte planes
    uint8_t* lo = scratch.data();
    uint8_t* hi = scratch.data() + values;
    uint16_t row[3 * (kMaxTileSide / 2)];  // one row of half floats (48 KB of stack at most)
    size_t k = 0;
    for (int y = 0; y < height; ++y) {
        halfFromFloat(rgb + size_t(y) * stride, rowValues, row);
        for (size_t i = 0; i < rowValues; ++i, ++k) {
            lo[k] = uint8_t(row[i] & 0xFF);
            hi[k] = uint8_t(row[i] >> 8);
        }
    }
    CodecSettings c = codec;
    c.codec = wideCodec(codec.codec);
    encodeTile(c, scratch.data(), 2 * width, height, size_t(width) * 6, out);
}

void decodeWideTile(TileCodec codec, const uint8_t* data, size_t size, int width, int height, float* dst,
                    size_t dstStride, std::vector<uint8_t>& scratch) {
    if (codec == TileCodec::Jpeg) throw DecodeError("a linear tile cannot be JPEG");
    if (width < 1 || height < 1 || width > kMaxTileSide / 2 || height > kMaxTileSide || dstStride < size_t(width) * 3)
        throw std::invalid_argument("decodeWideTile: tile size " + std::to_string(width) + "x" + std::to_string(height));
    const size_t values = size_t(width) * height * 3, rowValues = size_t(width) * 3;
    scratch.resize(2 * values);
    decodeTile(codec, data, size, 2 * width, height, scratch.data(), size_t(width) * 6);
    const uint8_t* lo = scratch.data();
    const uint8_t* hi = scratch.data() + values;
    uint16_t row[3 * (kMaxTileSide / 2)];
    size_t k = 0;
    for (int y = 0; y < height; ++y) {
        for (size_t i = 0; i < rowValues; ++i, ++k) row[i] = uint16_t(lo[k] | (hi[k] << 8));
        floatFromHalf(row, rowValues, dst + size_t(y) * dstStride);
    }
}

void encodeDepthTile(TileCodec codec, const float* depth, int width, int height, size_t stride,
                     std::vector<uint8_t>& scratch, std::vector<uint8_t>& out) {
    if (width < 1 || height < 1 || width > kMaxTileSide || height > kMaxTileSide || stride < size_t(width) ||
        (codec != TileCodec::Lz4 && codec != TileCodec::Zstd))
        throw std::invalid_argument("encodeDepthTile: tile size " + std::to_string(width) + "x" + std::to_string(height) +
                                    " or codec " + codecName(codec));
    const size_t pixels = size_t(width) * size_t(height);
    scratch.resize(encodedDepthBytes(pixels));
    uint8_t* lo = scratch.data();
    uint8_t* hi = scratch.data() + pixels;
    size_t k = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x, ++k) {
            const uint16_t code = encodeDepth(depth[size_t(y) * stride + size_t(x)]);
            lo[k] = uint8_t(code & 0xFF);
            hi[k] = uint8_t(code >> 8);
        }
    compress(codec, kDepthZstdLevel, scratch.data(), scratch.size(), out);
}

namespace {
// decodeDepth of every code, made once: the master decodes every pixel of every frame with depth
// (two million a frame), and an exp() each cost more than the rest of the tile's decoding.
const std::vector<float>& depthOfCode() {
    static const std::vector<float> table = [] {
        std::vector<float> t(65536);
        for (size_t c = 0; c < t.size(); ++c) t[c] = decodeDepth(uint16_t(c));
        return t;
    }();
    return table;
}
}  // namespace

void decodeDepthTile(TileCodec codec, const uint8_t* data, size_t size, int width, int height, float* dst,
                     size_t dstStride, std::vector<uint8_t>& scratch) {
    if (width < 1 || height < 1 || width > kMaxTileSide || height > kMaxTileSide || dstStride < size_t(width))
        throw std::invalid_argument("decodeDepthTile: tile size " + std::to_string(width) + "x" + std::to_string(height));
    if (codec != TileCodec::Lz4 && codec != TileCodec::Zstd)
        throw DecodeError(std::string("depth cannot come as ") + codecName(codec));
    const size_t pixels = size_t(width) * size_t(height);
    scratch.resize(encodedDepthBytes(pixels));
    decompress(codec, data, size, scratch.data(), scratch.size(), "depth tile");
    const uint8_t* lo = scratch.data();
    const uint8_t* hi = scratch.data() + pixels;
    const float* depthOf = depthOfCode().data();
    size_t k = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x, ++k) dst[size_t(y) * dstStride + size_t(x)] = depthOf[lo[k] | (hi[k] << 8)];
}

void encodeFeatureTile(uint8_t bits, const FeatureView& view, int width, int height, std::vector<uint8_t>& scratch,
                       std::vector<uint8_t>& out) {
    if (width < 1 || height < 1 || width > kMaxTileSide || height > kMaxTileSide || view.stride < size_t(width) || bits == 0 ||
        bits > kFeatureAll)
        throw std::invalid_argument("encodeFeatureTile: tile size " + std::to_string(width) + "x" + std::to_string(height) +
                                    " or feature bits " + std::to_string(int(bits)));
    scratch.resize(encodedFeatureBytes(size_t(width) * size_t(height), bits));
    encodeFeatures(bits, view.albedo, view.normal, view.id, width, height, view.stride, scratch.data());
    compress(kDepthCodec, kDepthZstdLevel, scratch.data(), scratch.size(), out);
}

void decodeFeatureTile(uint8_t bits, const uint8_t* data, size_t size, int width, int height, const FeatureView& view,
                       std::vector<uint8_t>& scratch) {
    if (width < 1 || height < 1 || width > kMaxTileSide || height > kMaxTileSide || view.stride < size_t(width) || bits == 0 ||
        bits > kFeatureAll)
        throw std::invalid_argument("decodeFeatureTile: tile size " + std::to_string(width) + "x" + std::to_string(height));
    scratch.resize(encodedFeatureBytes(size_t(width) * size_t(height), bits));
    decompress(kDepthCodec, data, size, scratch.data(), scratch.size(), "feature tile");
    decodeFeatures(bits, scratch.data(), scratch.size(), width, height, view.albedo, view.normal, view.id, view.stride);
}

size_t maxEncodedTileBytes(int width, int height) {
    const size_t n = tileBytes(width, height, size_t(width) * 3, "maxEncodedTileBytes");
    // 4:2:0 pads to 16x16 blocks and can exceed 4:4:4's bound for small tiles, so take both.
    return std::max({n, size_t(LZ4_compressBound(int(n))), ZSTD_compressBound(n),
                     jpegBufferBound(width, height, TJSAMP_444), jpegBufferBound(width, height, TJSAMP_420)});
}

size_t maxEncodedDepthBytes(int width, int height) {
    const size_t n = encodedDepthBytes(tileBytes(width, height, size_t(width) * 3, "maxEncodedDepthBytes") / 3);
    return std::max(size_t(LZ4_compressBound(int(n))), ZSTD_compressBound(n));
}

size_t maxEncodedFeatureBytes(int width, int height) {
    const size_t n = encodedFeatureBytes(tileBytes(width, height, size_t(width) * 3, "maxEncodedFeatureBytes") / 3, kFeatureAll);
    return std::max(size_t(LZ4_compressBound(int(n))), ZSTD_compressBound(n));
}

int previewValueBytes(uint32_t largest) { return largest <= 0xFF ? 1 : largest <= 0xFFFF ? 2 : 4; }

void encodePreviewCells(const uint32_t* values, size_t cells, int valueBytes, std::vector<uint8_t>& out,
                        std::vector<uint8_t>& scratch) {
    const size_t n = cells * 4;
    scratch.resize(n * size_t(valueBytes));
    for (int k = 0; k < valueBytes; ++k) {
        uint8_t* plane = scratch.data() + size_t(k) * n;
        for (size_t i = 0; i < n; ++i) plane[i] = uint8_t(values[i] >> (8 * k));
    }
    out.clear();
    compress(TileCodec::Zstd, 1, scratch.data(), scratch.size(), out);
}

void decodePreviewCells(const uint8_t* data, size_t size, size_t cells, int valueBytes, uint32_t* values,
                        std::vector<uint8_t>& scratch) {
    const size_t n = cells * 4;
    scratch.resize(n * size_t(valueBytes));
    decompress(TileCodec::Zstd, data, size, scratch.data(), scratch.size(), "preview cells");
    std::fill(values, values + n, 0u);
    for (int k = 0; k < valueBytes; ++k) {
        const uint8_t* plane = scratch.data() + size_t(k) * n;
        for (size_t i = 0; i < n; ++i) values[i] |= uint32_t(plane[i]) << (8 * k);
    }
}

const char* codecName(TileCodec codec) {
    switch (codec) {
        case TileCodec::Raw: return "raw";
        case TileCodec::Lz4: return "lz4";
        case TileCodec::Zstd: return "zstd";
        case TileCodec::Jpeg: return "jpeg";
    }
    return "unknown";
}

}  // namespace rtwall::cluster

namespace rtwall {

TileCodec tileCodecFromName(const std::string& name) {
    for (TileCodec c : {TileCodec::Raw, TileCodec::Lz4, TileCodec::Zstd, TileCodec::Jpeg})
        if (name == cluster::codecName(c)) return c;
    throw InputError("unknown tile codec '" + name + "' (raw, lz4, zstd, jpeg)");
}

const char* tileCodecName(TileCodec codec) { return cluster::codecName(codec); }

}  // namespace rtwall
