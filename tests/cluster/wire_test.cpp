// Tests for cluster/src/wire.cpp: byte order, counting versus writing, and every bounds check.
#include "wire.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace rtwall::cluster {
namespace {

// Everything the Writer can write, once; used to compare counting and writing.
void writeAll(Writer& w) {
    w.u8(0xA5);
    w.u16(0x0102);
    w.u32(0x01020304u);
    w.u64(0x0102030405060708ull);
    w.i32(-2);
    w.f32(1.0f);
    w.f64(-2.0);
    w.boolean(true);
    w.boolean(false);
    const uint8_t raw[3] = {9, 8, 7};
    w.bytes(raw, sizeof raw);
    w.blob(raw, 2);
    w.string("hey");
    w.string("");
}

TEST(Wire, CountingAndWritingAgree) {
    Writer counter;
    writeAll(counter);
    std::vector<uint8_t> out;
    Writer writer(&out);
    writeAll(writer);
    EXPECT_EQ(counter.size(), writer.size());
    EXPECT_EQ(out.size(), writer.size());
    EXPECT_EQ(counter.size(), size_t(1 + 2 + 4 + 8 + 4 + 4 + 8 + 1 + 1 + 3 + (4 + 2) + (4 + 3) + 4));
}

TEST(Wire, WriterAppendsToExistingBytes) {
    std::vector<uint8_t> out{0xEE};
    Writer w(&out);
    w.u16(0xBEEF);
    EXPECT_EQ(w.size(), 2u);
    EXPECT_EQ(out, (std::vector<uint8_t>{0xEE, 0xEF, 0xBE}));
}

TEST(Wire, LittleEndianLayout) {
    std::vector<uint8_t> out;
    Writer w(&out);
    w.u16(0x0102);
    w.u32(0x01020304u);
    w.u64(0x0102030405060708ull);
    w.i32(-1);
    w.f32(1.0f);    // 0x3F800000
    w.f64(1.0);     // 0x3FF0000000000000
    w.f32(-0.0f);   // sign bit only: bits are kept exactly
    w.string("ab");
    const std::vector<uint8_t> expected{
        0x02, 0x01,                                      //
        0x04, 0x03, 0x02, 0x01,                          //
        0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01,  //
        0xFF, 0xFF, 0xFF, 0xFF,                          //
        0x00, 0x00, 0x80, 0x3F,                          //
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF0, 0x3F,  //
        0x00, 0x00, 0x00, 0x80,                          //
        0x02, 0x00, 0x00, 0x00, 'a', 'b'};
    EXPECT_EQ(out, expected);
}

TEST(Wire, ReadsBackWhatWasWritten) {
    std::vector<uint8_t> out;
    Writer w(&out);
    writeAll(w);
    Reader r(out.data(), out.size());
    EXPECT_EQ(r.u8(), 0xA5);
    EXPECT_EQ(r.u16(), 0x0102);
    EXPECT_EQ(r.u32(), 0x01020304u);
    EXPECT_EQ(r.u64(), 0x0102030405060708ull);
    EXPECT_EQ(r.i32(), -2);
    EXPECT_EQ(r.f32(), 1.0f);
    EXPECT_EQ(r.f64(), -2.0);
    EXPECT_TRUE(r.boolean());
    EXPECT_FALSE(r.boolean());
    uint8_t raw[3] = {};
    r.bytes(raw, 3);
    EXPECT_EQ(raw[0], 9);
    EXPECT_EQ(raw[2], 7);
    EXPECT_EQ(r.blob(2), (std::vector<uint8_t>{9, 8}));
    EXPECT_EQ(r.string(3), "hey");
    EXPECT_EQ(r.string(0), "");
    EXPECT_EQ(r.remaining(), 0u);
    EXPECT_NO_THROW(r.expectEnd());
}

TEST(Wire, EveryReadChecksTheRemainingBytes) {
    const uint8_t data[8] = {};
    for (size_t size = 0; size < 8; ++size) {
        Reader r(data, size);
        if (size < 1) {
            EXPECT_THROW(r.u8(), DecodeError);
        }
        if (size < 2) {
            EXPECT_THROW(r.u16(), DecodeError);
        }
        if (size < 4) {
            EXPECT_THROW(r.u32(), DecodeError);
            EXPECT_THROW(r.i32(), DecodeError);
            EXPECT_THROW(r.f32(), DecodeError);
            EXPECT_THROW(r.f32Any(), DecodeError);
        }
        EXPECT_THROW(r.u64(), DecodeError);
        EXPECT_THROW(r.f64(), DecodeError);
        uint8_t out[9];
        EXPECT_THROW(r.bytes(out, size + 1), DecodeError);
        // A failed read consumes nothing.
        EXPECT_EQ(r.remaining(), size);
    }
}

TEST(Wire, FloatsMustBeFinite) {
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                      -std::numeric_limits<float>::infinity()}) {
        std::vector<uint8_t> out;
        Writer w(&out);
        w.f32(bad);
        Reader r(out.data(), out.size());
        EXPECT_THROW(r.f32(), DecodeError);
        Reader any(out.data(), out.size());
        const float v = any.f32Any();
        EXPECT_EQ(std::memcmp(&v, &bad, sizeof v), 0);
    }
    for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
        std::vector<uint8_t> out;
        Writer w(&out);
        w.f64(bad);
        Reader r(out.data(), out.size());
        EXPECT_THROW(r.f64(), DecodeError);
    }
}

TEST(Wire, BooleanIsZeroOrOne) {
    const uint8_t data[] = {0, 1, 2, 0xFF};
    Reader r(data, sizeof data);
    EXPECT_FALSE(r.boolean());
    EXPECT_TRUE(r.boolean());
    EXPECT_THROW(r.boolean(), DecodeError);
    EXPECT_THROW(r.boolean(), DecodeError);
}

TEST(Wire, BlobChecksLimitAndRemainingBytes) {
    std::vector<uint8_t> out;
    Writer w(&out);
    w.string("hello");
    {
        Reader r(out.data(), out.size());
        EXPECT_THROW(r.string(4), DecodeError);  // over the limit
    }
    {
        Reader r(out.data(), out.size() - 1);
        EXPECT_THROW(r.blob(100), DecodeError);  // shorter than its length
    }
    {
        Reader r(out.data(), out.size());
        const auto [p, n] = r.blobView(5);
        EXPECT_EQ(n, 5u);
        EXPECT_EQ(p, out.data() + 4);
        EXPECT_EQ(r.remaining(), 0u);
    }
    // A length of 4 GiB - 1 with nothing behind it must fail before allocating.
    const uint8_t huge[] = {0xFF, 0xFF, 0xFF, 0xFF, 'x'};
    Reader r(huge, sizeof huge);
    EXPECT_THROW(r.blob(std::numeric_limits<size_t>::max()), DecodeError);
    Reader r2(huge, sizeof huge);
    EXPECT_THROW(r2.string(std::numeric_limits<size_t>::max()), DecodeError);
}

TEST(Wire, WriterRejectsBlobsLongerThanAU32) {
    Writer counter;  // counting only: the pointer is never read
    const uint8_t byte = 0;
    EXPECT_THROW(counter.blob(&byte, size_t(1) << 32), std::length_error);
}

TEST(Wire, ExpectElements) {
    const uint8_t data[16] = {};
    Reader r(data, sizeof data);
    EXPECT_NO_THROW(r.expectElements(4, 4, 4));
    EXPECT_NO_THROW(r.expectElements(0, 4, 0));
    EXPECT_THROW(r.expectElements(5, 4, 100), DecodeError);  // 20 bytes > 16
    EXPECT_THROW(r.expectElements(4, 4, 3), DecodeError);    // over the count limit
    EXPECT_THROW(r.expectElements(3, 8, 100), DecodeError);
    // count * elementSize overflows 64 bits: must still be rejected.
    EXPECT_THROW(r.expectElements(uint64_t(1) << 62, 16, std::numeric_limits<uint64_t>::max()), DecodeError);
    EXPECT_THROW(r.expectElements(std::numeric_limits<uint64_t>::max(), 2, std::numeric_limits<uint64_t>::max()),
                 DecodeError);
    EXPECT_EQ(r.remaining(), 16u);
}

TEST(Wire, TrailingBytesAreAnError) {
    const uint8_t data[2] = {1, 2};
    Reader r(data, sizeof data);
    EXPECT_THROW(r.expectEnd(), DecodeError);
    r.u8();
    EXPECT_THROW(r.expectEnd(), DecodeError);
    r.u8();
    EXPECT_NO_THROW(r.expectEnd());
}

}  // namespace
}  // namespace rtwall::cluster
