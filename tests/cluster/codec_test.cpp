// Tests for cluster/src/codec.cpp: lossless codecs reproduce tiles exactly, JPEG stays close,
// and malformed data of every kind throws without writing outside the destination.
#include "codec.h"

#include "wire.h"

#include <rtwall/depth_codec.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace rtwall::cluster {
namespace {

constexpr TileCodec kAllCodecs[] = {TileCodec::Raw, TileCodec::Lz4, TileCodec::Zstd, TileCodec::Jpeg};
constexpr TileCodec kLossless[] = {TileCodec::Raw, TileCodec::Lz4, TileCodec::Zstd};

struct Size {
    int w, h;
};
constexpr Size kSizes[] = {{1, 1}, {7, 5}, {32, 32}, {64, 48}};

// An RGB8 tile with `pad` junk bytes after each row, which no codec may pick up.
struct Tile {
    int w = 0, h = 0;
    size_t stride = 0;
    std::vector<uint8_t> bytes;
    const uint8_t* pixel(int x, int y) const { return bytes.data() + size_t(y) * stride + 3 * size_t(x); }
};

// Gradients, plus noise of the given amplitude: compressible but not trivially so.
Tile makeTile(int w, int h, size_t pad, int noise, uint32_t seed = 1) {
    std::mt19937 rng(seed);
    Tile t{w, h, size_t(w) * 3 + pad, {}};
    t.bytes.resize(t.stride * size_t(h));
    for (uint8_t& b : t.bytes) b = uint8_t(rng());
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const int n = noise ? int(rng() % uint32_t(2 * noise + 1)) - noise : 0;
            const int base[3] = {x * 255 / std::max(1, w - 1), y * 255 / std::max(1, h - 1),
                                 (x + 2 * y) * 255 / std::max(1, w - 1 + 2 * (h - 1))};
            uint8_t* p = t.bytes.data() + size_t(y) * t.stride + 3 * size_t(x);
            for (int c = 0; c < 3; ++c) p[c] = uint8_t(std::clamp(base[c] + n, 0, 255));
        }
    }
    return t;
}

Tile makeNoise(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    Tile t{w, h, size_t(w) * 3, {}};
    t.bytes.resize(t.stride * size_t(h));
    for (uint8_t& b : t.bytes) b = uint8_t(rng());
    return t;
}

std::vector<uint8_t> encode(TileCodec codec, const Tile& t, int quality = 90, bool subsample = false) {
    CodecSettings s;
    s.codec = codec;
    s.jpegQuality = quality;
    s.jpegSubsample = subsample;
    s.zstdLevel = 3;
    std::vector<uint8_t> out;
    encodeTile(s, t.bytes.data(), t.w, t.h, t.stride, out);
    return out;
}

// A destination with guard bytes before, after and between the rows, to catch writes outside.
constexpr uint8_t kGuardByte = 0xCD;
constexpr size_t kGuard = 64;
struct Destination {
    int w, h;
    size_t stride;
    std::vector<uint8_t> buffer;
    Destination(int width, int height, size_t pad)
        : w(width), h(height), stride(size_t(width) * 3 + pad),
          buffer(2 * kGuard + stride * size_t(height), kGuardByte) {}
    uint8_t* data() { return buffer.data() + kGuard; }
    const uint8_t* pixel(int x, int y) const { return buffer.data() + kGuard + size_t(y) * stride + 3 * size_t(x); }
    bool guardsIntact() const {
        for (size_t i = 0; i < kGuard; ++i)
            if (buffer[i] != kGuardByte || buffer[buffer.size() - 1 - i] != kGuardByte) return false;
        for (int y = 0; y < h; ++y)
            for (size_t i = size_t(w) * 3; i < stride; ++i)
                if (buffer[kGuard + size_t(y) * stride + i] != kGuardByte) return false;
        return true;
    }
    void decode(TileCodec codec, const std::vector<uint8_t>& data) {
        decodeTile(codec, data.data(), data.size(), w, h, this->data(), stride);
    }
};

bool samePixels(const Tile& t, const Destination& d) {
    for (int y = 0; y < t.h; ++y)
        if (!std::equal(t.pixel(0, y), t.pixel(0, y) + 3 * t.w, d.pixel(0, y))) return false;
    return true;
}

double psnr(const Tile& t, const Destination& d) {
    double sum = 0;
    for (int y = 0; y < t.h; ++y)
        for (int x = 0; x < t.w; ++x)
            for (int c = 0; c < 3; ++c) {
                const double e = double(t.pixel(x, y)[c]) - double(d.pixel(x, y)[c]);
                sum += e * e;
            }
    const double mse = sum / (3.0 * t.w * t.h);
    return mse == 0 ? INFINITY : 10.0 * std::log10(255.0 * 255.0 / mse);
}

std::string label(TileCodec codec, Size s) {
    return std::string(codecName(codec)) + " " + std::to_string(s.w) + "x" + std::to_string(s.h);
}

TEST(Codec, LosslessCodecsReproduceTilesExactly) {
    for (TileCodec codec : kLossless) {
        for (Size size : kSizes) {
            for (auto [srcPad, dstPad] : {std::pair<size_t, size_t>{0, 0}, {5, 7}, {3, 0}, {0, 9}}) {
                SCOPED_TRACE(label(codec, size) + " pads " + std::to_string(srcPad) + "/" + std::to_string(dstPad));
                const Tile tile = makeTile(size.w, size.h, srcPad, 6);
                const std::vector<uint8_t> encoded = encode(codec, tile);
                EXPECT_LE(encoded.size(), maxEncodedTileBytes(size.w, size.h));
                Destination dst(size.w, size.h, dstPad);
                dst.decode(codec, encoded);
                EXPECT_TRUE(samePixels(tile, dst));
                EXPECT_TRUE(dst.guardsIntact());
            }
        }
    }
}

TEST(Codec, EncodeAppends) {
    const Tile tile = makeTile(7, 5, 2, 6);
    for (TileCodec codec : kAllCodecs) {
        SCOPED_TRACE(codecName(codec));
        std::vector<uint8_t> out{1, 2, 3};
        CodecSettings s;
        s.codec = codec;
        encodeTile(s, tile.bytes.data(), tile.w, tile.h, tile.stride, out);
        ASSERT_GT(out.size(), 3u);
        EXPECT_EQ(out[0], 1);
        EXPECT_EQ(out[2], 3);
        const std::vector<uint8_t> alone = encode(codec, tile);
        EXPECT_TRUE(std::equal(alone.begin(), alone.end(), out.begin() + 3, out.end()));
    }
}

TEST(Codec, CompressionActuallyCompresses) {
    // A flat tile (sky, background) must come out far smaller than raw, or a codec is silently
    // falling back to copying.
    Tile flat{64, 48, 64 * 3, std::vector<uint8_t>(64 * 48 * 3)};
    for (size_t i = 0; i < flat.bytes.size(); ++i) flat.bytes[i] = uint8_t(40 + 30 * (i % 3));
    const size_t raw = encode(TileCodec::Raw, flat).size();
    EXPECT_EQ(raw, 64u * 48u * 3u);
    for (TileCodec codec : {TileCodec::Lz4, TileCodec::Zstd, TileCodec::Jpeg})
        EXPECT_LT(encode(codec, flat).size(), raw / 8) << codecName(codec);
}

TEST(Codec, ZstdLevels) {
    const Tile tile = makeTile(32, 32, 4, 3);
    for (int level : {1, 9, 19}) {
        CodecSettings s;
        s.codec = TileCodec::Zstd;
        s.zstdLevel = level;
        std::vector<uint8_t> out;
        encodeTile(s, tile.bytes.data(), tile.w, tile.h, tile.stride, out);
        Destination dst(32, 32, 0);
        dst.decode(TileCodec::Zstd, out);
        EXPECT_TRUE(samePixels(tile, dst)) << level;
    }
}

TEST(Codec, JpegQuality) {
    for (bool subsample : {false, true}) {
        for (size_t pad : {size_t(0), size_t(11)}) {
            SCOPED_TRACE(std::string(subsample ? "4:2:0" : "4:4:4") + " pad " + std::to_string(pad));
            const Tile tile = makeTile(64, 48, pad, 0);
            Destination dst(64, 48, pad + 2);
            dst.decode(TileCodec::Jpeg, encode(TileCodec::Jpeg, tile, 95, subsample));
            EXPECT_GT(psnr(tile, dst), 35.0);
            EXPECT_TRUE(dst.guardsIntact());
        }
    }
    // The settings reach the encoder: lower quality and subsampling give fewer bytes.
    const Tile noisy = makeTile(64, 48, 0, 20);
    EXPECT_LT(encode(TileCodec::Jpeg, noisy, 20).size(), encode(TileCodec::Jpeg, noisy, 95).size());
    EXPECT_LT(encode(TileCodec::Jpeg, noisy, 95, true).size(), encode(TileCodec::Jpeg, noisy, 95, false).size());
    // Every size decodes to the right size, including partial blocks.
    for (Size size : kSizes) {
        SCOPED_TRACE(label(TileCodec::Jpeg, size));
        const Tile tile = makeTile(size.w, size.h, 1, 0);
        Destination dst(size.w, size.h, 3);
        dst.decode(TileCodec::Jpeg, encode(TileCodec::Jpeg, tile, 95, true));
        EXPECT_TRUE(dst.guardsIntact());
    }
}

TEST(Codec, WrongSizeThrows) {
    const Tile tile = makeTile(32, 32, 0, 6);
    for (TileCodec codec : kAllCodecs) {
        const std::vector<uint8_t> encoded = encode(codec, tile);
        // Encoded tiles carry no size of their own, so a lossless tile of another shape but the same
        // byte count (16x64 for 32x32) is only caught by JPEG; the master never asks for one.
        for (Size other : {Size{32, 31}, Size{31, 32}, Size{64, 64}, Size{16, 64}, Size{1, 1}}) {
            if (codec != TileCodec::Jpeg && other.w * other.h == 32 * 32) continue;
            SCOPED_TRACE(label(codec, other));
            Destination dst(other.w, other.h, 4);
            EXPECT_THROW(dst.decode(codec, encoded), DecodeError);
            EXPECT_TRUE(dst.guardsIntact());
        }
    }
}

TEST(Codec, EveryTruncationThrows) {
    for (TileCodec codec : kAllCodecs) {
        for (int noise : {0, 30}) {
            SCOPED_TRACE(std::string(codecName(codec)) + " noise " + std::to_string(noise));
            const std::vector<uint8_t> encoded = encode(codec, makeTile(32, 32, 0, noise));
            Destination dst(32, 32, 5);
            for (size_t cut = 0; cut < encoded.size(); ++cut) {
                // Exactly sized, so that AddressSanitizer would see a read past the end.
                const std::vector<uint8_t> prefix(encoded.begin(), encoded.begin() + ptrdiff_t(cut));
                EXPECT_THROW(dst.decode(codec, prefix), DecodeError) << "cut at " << cut;
            }
            EXPECT_TRUE(dst.guardsIntact());
        }
    }
}

TEST(Codec, MalformedDataThrows) {
    const Tile tile = makeTile(32, 32, 0, 6);
    auto rejects = [](TileCodec codec, const std::vector<uint8_t>& data, const char* what) {
        Destination dst(32, 32, 3);
        EXPECT_THROW(dst.decode(codec, data), DecodeError) << codecName(codec) << ": " << what;
        EXPECT_TRUE(dst.guardsIntact()) << codecName(codec) << ": " << what;
    };
    const std::vector<uint8_t> garbage(200, 0xFF);
    for (TileCodec codec : kAllCodecs) {
        rejects(codec, garbage, "garbage");
        rejects(codec, {}, "empty");
        std::vector<uint8_t> trailing = encode(codec, tile);
        trailing.push_back(0);
        if (codec != TileCodec::Jpeg) rejects(codec, trailing, "a trailing byte");  // JPEG ends at its EOI marker
    }

    // LZ4: a match reaching before the start of the output, and a literal run past the input.
    rejects(TileCodec::Lz4, {0x00, 0x10, 0x00, 0x00, 0x00}, "match before the start");
    rejects(TileCodec::Lz4, {0xF0, 0xFF, 0xFF, 0xFF, 0x01, 0x02}, "literals past the end");

    // zstd: a broken magic number, two frames, and a frame that declares another size.
    std::vector<uint8_t> zstd = encode(TileCodec::Zstd, tile);
    zstd[0] ^= 0xFF;
    rejects(TileCodec::Zstd, zstd, "magic");
    std::vector<uint8_t> twoFrames = encode(TileCodec::Zstd, tile);
    const std::vector<uint8_t> second = encode(TileCodec::Zstd, makeTile(1, 1, 0, 0));
    twoFrames.insert(twoFrames.end(), second.begin(), second.end());
    rejects(TileCodec::Zstd, twoFrames, "two frames");

    // JPEG: no start-of-image marker.
    std::vector<uint8_t> jpeg = encode(TileCodec::Jpeg, tile);
    ASSERT_EQ(jpeg[0], 0xFF);
    ASSERT_EQ(jpeg[1], 0xD8);
    jpeg[1] = 0x00;
    rejects(TileCodec::Jpeg, jpeg, "SOI");

    // Unknown codecs.
    rejects(TileCodec(4), encode(TileCodec::Raw, tile), "codec 4");
}

TEST(Codec, RandomCorruptionStaysInsideTheDestination) {
    std::mt19937 rng(777);
    for (TileCodec codec : kAllCodecs) {
        SCOPED_TRACE(codecName(codec));
        const std::vector<uint8_t> encoded = encode(codec, makeTile(24, 16, 0, 10));
        Destination dst(24, 16, 6);
        int decoded = 0;
        for (int iteration = 0; iteration < 400; ++iteration) {
            std::vector<uint8_t> bad = encoded;
            const int flips = 1 + int(rng() % 3);
            for (int f = 0; f < flips; ++f) bad[rng() % bad.size()] = uint8_t(rng());
            if (rng() % 4 == 0) bad.resize(rng() % bad.size());
            try {
                dst.decode(codec, bad);
                ++decoded;
            } catch (const DecodeError&) {
            }
            ASSERT_TRUE(dst.guardsIntact()) << "iteration " << iteration;
        }
        (void)decoded;  // either outcome is fine; only the destination's bounds are checked
    }
}

TEST(Codec, MaxEncodedTileBytesBoundsEveryCodec) {
    for (Size size : {Size{1, 1}, Size{3, 2}, Size{7, 5}, Size{16, 16}, Size{33, 17}, Size{64, 48}}) {
        const size_t bound = maxEncodedTileBytes(size.w, size.h);
        EXPECT_GE(bound, size_t(size.w) * size_t(size.h) * 3);
        const Tile noise = makeNoise(size.w, size.h, uint32_t(size.w * 100 + size.h));
        for (TileCodec codec : kAllCodecs) {
            for (bool subsample : {false, true}) {
                EXPECT_LE(encode(codec, noise, 100, subsample).size(), bound) << label(codec, size);
            }
        }
    }
    EXPECT_LT(maxEncodedTileBytes(64, 64), 64u * 64u * 3u * 4u);  // a small multiple of the raw size
}

TEST(Codec, InvalidArguments) {
    const Tile tile = makeTile(8, 8, 0, 0);
    std::vector<uint8_t> out;
    CodecSettings s;
    EXPECT_THROW(encodeTile(s, tile.bytes.data(), 8, 8, 23, out), std::invalid_argument);  // stride < 24
    EXPECT_THROW(encodeTile(s, tile.bytes.data(), 0, 8, 24, out), std::invalid_argument);
    EXPECT_THROW(encodeTile(s, tile.bytes.data(), 8, -1, 24, out), std::invalid_argument);
    s.codec = TileCodec(9);
    EXPECT_THROW(encodeTile(s, tile.bytes.data(), 8, 8, 24, out), std::invalid_argument);
    s = {TileCodec::Jpeg, 0, false, 1};
    EXPECT_THROW(encodeTile(s, tile.bytes.data(), 8, 8, 24, out), std::invalid_argument);
    s = {TileCodec::Zstd, 90, false, 20};
    EXPECT_THROW(encodeTile(s, tile.bytes.data(), 8, 8, 24, out), std::invalid_argument);
    EXPECT_TRUE(out.empty());
    std::vector<uint8_t> dst(8 * 8 * 3);
    EXPECT_THROW(decodeTile(TileCodec::Raw, tile.bytes.data(), tile.bytes.size(), 8, 8, dst.data(), 20),
                 std::invalid_argument);
}

TEST(Codec, Names) {
    EXPECT_STREQ(codecName(TileCodec::Raw), "raw");
    EXPECT_STREQ(codecName(TileCodec::Lz4), "lz4");
    EXPECT_STREQ(codecName(TileCodec::Zstd), "zstd");
    EXPECT_STREQ(codecName(TileCodec::Jpeg), "jpeg");
}

}  // namespace
}  // namespace rtwall::cluster

namespace rtwall::cluster {
namespace {

// Half precision: the documented IEEE values, ties to even, overflow to infinity.
TEST(WideTile, HalfRoundingIsIeee) {
    EXPECT_EQ(halfFromFloat(1.0f), 0x3C00);
    EXPECT_EQ(halfFromFloat(-2.0f), 0xC000);
    EXPECT_EQ(halfFromFloat(65504.0f), 0x7BFF);
    EXPECT_EQ(halfFromFloat(65520.0f), 0x7C00);                    // rounds up to infinity
    EXPECT_EQ(halfFromFloat(1.0f + std::ldexp(1.0f, -11)), 0x3C00);  // a tie: to even
    EXPECT_EQ(halfFromFloat(1.0f + 3 * std::ldexp(1.0f, -11)), 0x3C02);
    EXPECT_EQ(halfFromFloat(std::ldexp(1.0f, -24)), 0x0001);        // the smallest subnormal
    EXPECT_EQ(floatFromHalf(0x3555), 0.333251953125f);
    EXPECT_EQ(roundToHalf(0.1f), floatFromHalf(halfFromFloat(0.1f)));
    for (uint32_t h = 0; h < 0x7C00; ++h) EXPECT_EQ(halfFromFloat(floatFromHalf(uint16_t(h))), h);
}

// The bulk conversions (F16C, 8 values per instruction, then one at a time for the rest) give
// the scalar ones' bits: for every half, and for 4.4 million floats spread over every bit
// pattern (NaNs and infinities included), in runs of 1027 so that each run ends in the
// one-at-a-time tail.
TEST(WideTile, BulkHalfConversionsMatchTheScalarOnes) {
    std::vector<uint16_t> halves(65536);
    for (uint32_t h = 0; h < 65536; ++h) halves[h] = uint16_t(h);
    std::vector<float> floats(65536);
    floatFromHalf(halves.data(), halves.size(), floats.data());
    for (uint32_t h = 0; h < 65536; ++h)
        ASSERT_EQ(std::bit_cast<uint32_t>(floats[h]), std::bit_cast<uint32_t>(floatFromHalf(uint16_t(h)))) << h;
    std::vector<float> in(1027);
    std::vector<uint16_t> out(in.size());
    uint64_t bits = 0;
    while (bits < (uint64_t(1) << 32)) {
        size_t n = 0;
        for (; n < in.size() && bits < (uint64_t(1) << 32); ++n, bits += 977) in[n] = std::bit_cast<float>(uint32_t(bits));
        halfFromFloat(in.data(), n, out.data());
        for (size_t i = 0; i < n; ++i)
            ASSERT_EQ(out[i], halfFromFloat(in[i])) << "float bits " << std::bit_cast<uint32_t>(in[i]);
    }
}

// Linear tiles: every lossless codec (and JPEG, which becomes LZ4) gives back exactly the
// half-rounded values, whatever the strides; malformed data throws, JPEG-labelled data too.
TEST(WideTile, RoundTripsExactlyAtHalfPrecision) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> value(0.0f, 4.0f);
    for (const Size s : kSizes) {
        const size_t stride = size_t(s.w) * 3 + 5;
        std::vector<float> rgb(stride * size_t(s.h));
        for (float& v : rgb) v = value(rng);
        for (TileCodec c : kAllCodecs) {
            CodecSettings cs;
            cs.codec = c;
            std::vector<uint8_t> scratch, encoded;
            encodeWideTile(cs, rgb.data(), s.w, s.h, stride, scratch, encoded);
            const size_t dstStride = size_t(s.w) * 3 + 2;
            std::vector<float> back(dstStride * size_t(s.h), -1.0f);
            decodeWideTile(wideCodec(c), encoded.data(), encoded.size(), s.w, s.h, back.data(), dstStride, scratch);
            for (int y = 0; y < s.h; ++y)
                for (int i = 0; i < s.w * 3; ++i)
                    ASSERT_EQ(back[size_t(y) * dstStride + size_t(i)], roundToHalf(rgb[size_t(y) * stride + size_t(i)]))
                        << codecName(c) << " " << s.w << "x" << s.h;
            for (int y = 0; y < s.h; ++y)
                for (size_t i = size_t(s.w) * 3; i < dstStride; ++i) ASSERT_EQ(back[size_t(y) * dstStride + i], -1.0f);
            if (encoded.size() > 1) {
                std::vector<uint8_t> cut(encoded.begin(), encoded.end() - 1);
                EXPECT_THROW(decodeWideTile(wideCodec(c), cut.data(), cut.size(), s.w, s.h, back.data(), dstStride, scratch),
                             DecodeError);
            }
            EXPECT_THROW(decodeWideTile(TileCodec::Jpeg, encoded.data(), encoded.size(), s.w, s.h, back.data(), dstStride,
                                        scratch),
                         DecodeError);
        }
    }
}

// ---- Depth (issue 27) ----------------------------------------------------------------------------

// A tile's depth with everything the codec must keep: a smooth surface, background, holes
// (NaN, infinity, zero, negative), and junk in the padding of each row that must not travel.
std::vector<float> depthTile(int w, int h, size_t stride) {
    std::vector<float> d(stride * size_t(h), -123.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float v = 2.0f + 0.01f * float(x) + 0.37f * float(y);
            if ((x + y) % 7 == 0) v = kBackgroundDepth;
            if (x == 1 && y == 0) v = std::numeric_limits<float>::quiet_NaN();
            if (x == 2 && y == 0) v = std::numeric_limits<float>::infinity();
            if (x == 3 && y == 0) v = -1.0f;
            if (x == 4 && y == 0) v = 0.0f;
            if (x == 5 && y == 0) v = 5e9f;  // beyond the code's far end
            d[size_t(y) * stride + size_t(x)] = v;
        }
    return d;
}

TEST(Codec, DepthComesBackAsItsSixteenBitCode) {
    for (TileCodec codec : {TileCodec::Lz4, TileCodec::Zstd})
        for (const Size s : kSizes) {
            const size_t stride = size_t(s.w) + 3;
            const std::vector<float> d = depthTile(s.w, s.h, stride);
            std::vector<uint8_t> scratch, bytes{0xEE};  // appended to what is there
            encodeDepthTile(codec, d.data(), s.w, s.h, stride, scratch, bytes);
            ASSERT_EQ(bytes.front(), 0xEE);
            std::vector<float> back(size_t(s.w) * size_t(s.h) + 1, 42.0f);  // one float past the tile: untouched
            decodeDepthTile(codec, bytes.data() + 1, bytes.size() - 1, s.w, s.h, back.data(), size_t(s.w), scratch);
            for (int y = 0; y < s.h; ++y)
                for (int x = 0; x < s.w; ++x) {
                    const float want = decodeDepth(encodeDepth(d[size_t(y) * stride + size_t(x)]));
                    const float got = back[size_t(y) * size_t(s.w) + size_t(x)];
                    if (std::isnan(want)) EXPECT_TRUE(std::isnan(got)) << x << "," << y;
                    else EXPECT_EQ(got, want) << x << "," << y << " " << codecName(codec);
                }
            EXPECT_EQ(back.back(), 42.0f);
        }
}

TEST(Codec, MalformedDepthThrows) {
    const int w = 32, h = 32;
    const std::vector<float> d = depthTile(w, h, w);
    std::vector<uint8_t> scratch, good;
    encodeDepthTile(kDepthCodec, d.data(), w, h, w, scratch, good);
    std::vector<float> out(size_t(w) * h + 1, 7.0f);
    auto throws = [&](const std::vector<uint8_t>& bytes, int tw, int th, TileCodec codec, const char* what) {
        EXPECT_THROW(decodeDepthTile(codec, bytes.data(), bytes.size(), tw, th, out.data(), size_t(tw), scratch), DecodeError)
            << what;
        EXPECT_EQ(out.back(), 7.0f) << what;
    };
    throws({}, w, h, kDepthCodec, "empty");
    throws(std::vector<uint8_t>(good.begin(), good.begin() + ptrdiff_t(good.size() / 2)), w, h, kDepthCodec, "cut in half");
    throws(good, w, h - 1, kDepthCodec, "a smaller tile's size");
    throws(good, 16, h, kDepthCodec, "a narrower tile");
    throws(good, w, h, TileCodec::Raw, "not a depth codec");
    throws(good, w, h, TileCodec::Jpeg, "not a depth codec");
    std::vector<uint8_t> garbage(good.size());
    std::mt19937 rng(5);
    for (uint8_t& b : garbage) b = uint8_t(rng());
    throws(garbage, w, h, kDepthCodec, "garbage");
    std::vector<uint8_t> longer = good;
    longer.push_back(0);
    throws(longer, w, h, kDepthCodec, "a byte too many");
}

TEST(Codec, DepthCompressesAndIsBounded) {
    const int w = 64, h = 64;
    const std::vector<float> d = depthTile(w, h, w);
    std::vector<uint8_t> scratch, bytes;
    encodeDepthTile(kDepthCodec, d.data(), w, h, w, scratch, bytes);
    EXPECT_LT(bytes.size(), encodedDepthBytes(size_t(w) * h));
    EXPECT_LE(bytes.size(), maxEncodedDepthBytes(w, h));
}

}  // namespace
}  // namespace rtwall::cluster
