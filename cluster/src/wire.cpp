#include "wire.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

namespace rtwall::cluster {

namespace {

// Little-endian byte order is spelled out with shifts so the encoding is the same on any host.
template <class T> void storeLe(uint8_t* p, T v) {
    for (size_t i = 0; i < sizeof(T); ++i) p[i] = uint8_t(v >> (8 * i));
}

template <class T> T loadLe(const uint8_t* p) {
    T v = 0;
    for (size_t i = 0; i < sizeof(T); ++i) v = T(v | T(T(p[i]) << (8 * i)));
    return v;
}

}  // namespace

// -- Writer ----------------------------------------------------------------------------------

void Writer::bytes(const void* data, size_t n) {
    // Counting and writing share this one place, so a measured size always equals the bytes written.
    if (out_ && n > 0) {
        const auto* p = static_cast<const uint8_t*>(data);
        out_->insert(out_->end(), p, p + n);
    }
    size_ += n;
}

void Writer::u8(uint8_t v) { bytes(&v, 1); }

void Writer::u16(uint16_t v) {
    uint8_t b[2];
    storeLe(b, v);
    bytes(b, sizeof b);
}

void Writer::u32(uint32_t v) {
    uint8_t b[4];
    storeLe(b, v);
    bytes(b, sizeof b);
}

void Writer::u64(uint64_t v) {
    uint8_t b[8];
    storeLe(b, v);
    bytes(b, sizeof b);
}

void Writer::f32(float v) { u32(std::bit_cast<uint32_t>(v)); }

void Writer::f64(double v) { u64(std::bit_cast<uint64_t>(v)); }

void Writer::blob(const void* data, size_t n) {
    // A length that does not fit the u32 prefix is a programming error on the sending side.
    if (n > std::numeric_limits<uint32_t>::max())
        throw std::length_error("Writer::blob: " + std::to_string(n) + " bytes do not fit a u32 length");
    u32(uint32_t(n));
    bytes(data, n);
}

// -- Reader ----------------------------------------------------------------------------------

void Reader::need(size_t n) const {
    if (n > remaining())
        throw DecodeError("truncated message: need " + std::to_string(n) + " bytes, " +
                          std::to_string(remaining()) + " remain");
}

uint8_t Reader::u8() {
    need(1);
    return *p_++;
}

uint16_t Reader::u16() {
    need(2);
    const uint16_t v = loadLe<uint16_t>(p_);
    p_ += 2;
    return v;
}

uint32_t Reader::u32() {
    need(4);
    const uint32_t v = loadLe<uint32_t>(p_);
    p_ += 4;
    return v;
}

uint64_t Reader::u64() {
    need(8);
    const uint64_t v = loadLe<uint64_t>(p_);
    p_ += 8;
    return v;
}

float Reader::f32Any() { return std::bit_cast<float>(u32()); }

float Reader::f32() {
    const float v = f32Any();
    if (!std::isfinite(v)) throw DecodeError("non-finite float value");
    return v;
}

double Reader::f64() {
    // Doubles carry transforms, which are scene values like any float: they must be finite.
    const double v = std::bit_cast<double>(u64());
    if (!std::isfinite(v)) throw DecodeError("non-finite double value");
    return v;
}

bool Reader::boolean() {
    const uint8_t v = u8();
    if (v > 1) throw DecodeError("boolean value " + std::to_string(v) + " is neither 0 nor 1");
    return v == 1;
}

void Reader::bytes(void* out, size_t n) {
    need(n);
    if (n > 0) std::memcpy(out, p_, n);
    p_ += n;
}

std::pair<const uint8_t*, size_t> Reader::blobView(size_t maxLength) {
    const uint32_t n = u32();
    if (n > maxLength)
        throw DecodeError("length " + std::to_string(n) + " exceeds the limit of " + std::to_string(maxLength));
    need(n);
    const uint8_t* p = p_;
    p_ += n;
    return {p, n};
}

std::vector<uint8_t> Reader::blob(size_t maxLength) {
    // blobView has checked the length against the limit and the message before anything is allocated.
    const auto [p, n] = blobView(maxLength);
    return std::vector<uint8_t>(p, p + n);
}

std::string Reader::string(size_t maxLength) {
    const auto [p, n] = blobView(maxLength);
    return std::string(reinterpret_cast<const char*>(p), n);
}

void Reader::expectElements(uint64_t count, size_t elementSize, uint64_t maxCount) {
    if (count > maxCount)
        throw DecodeError("element count " + std::to_string(count) + " exceeds the limit of " +
                          std::to_string(maxCount));
    // Divide rather than multiply: count * elementSize can overflow 64 bits for a hostile count.
    if (elementSize > 0 && count > remaining() / elementSize)
        throw DecodeError("element count " + std::to_string(count) + " of " + std::to_string(elementSize) +
                          " bytes each does not fit the " + std::to_string(remaining()) + " remaining bytes");
}

void Reader::expectEnd() const {
    if (remaining() != 0) throw DecodeError(std::to_string(remaining()) + " trailing bytes after the message");
}

}  // namespace rtwall::cluster
