// Explicit little-endian encoding. Messages are written field by field, never by memcpy of
// structs (whose layout differs between compilers). One Writer class both measures and writes,
// so a message's size and its bytes cannot drift apart (OSPRay's WriteSizeCalculator idea).
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rtwall::cluster {

// A malformed message: the decoder found a length, range or value it cannot accept.
class DecodeError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class Writer {
public:
    // A Writer without a buffer only counts bytes.
    Writer() = default;
    explicit Writer(std::vector<uint8_t>* out) : out_(out) {}

    void u8(uint8_t v);
    void u16(uint16_t v);
    void u32(uint32_t v);
    void u64(uint64_t v);
    void i32(int32_t v) { u32(uint32_t(v)); }
    void f32(float v);   // IEEE-754 bits, little-endian
    void f64(double v);
    void boolean(bool v) { u8(v ? 1 : 0); }
    void bytes(const void* data, size_t n);          // raw, no length
    void blob(const void* data, size_t n);           // u32 length + bytes
    void string(std::string_view s) { blob(s.data(), s.size()); }

    size_t size() const { return size_; }

private:
    std::vector<uint8_t>* out_ = nullptr;
    size_t size_ = 0;
};

// Bounds-checked reader: every read checks the remaining length first and throws DecodeError.
class Reader {
public:
    Reader(const uint8_t* data, size_t size) : p_(data), end_(data + size) {}

    uint8_t u8();
    uint16_t u16();
    uint32_t u32();
    uint64_t u64();
    int32_t i32() { return int32_t(u32()); }
    float f32();          // rejects NaN and infinity: scene values must be finite
    double f64();         // rejects NaN and infinity too (transforms are scene values)
    float f32Any();       // any bit pattern
    bool boolean();       // 0 or 1, anything else is an error
    void bytes(void* out, size_t n);
    // A u32 length, checked against maxLength and the remaining bytes, then the bytes.
    std::vector<uint8_t> blob(size_t maxLength);
    std::string string(size_t maxLength);
    // Like blob but returns a view into the message (valid while the message lives).
    std::pair<const uint8_t*, size_t> blobView(size_t maxLength);
    // Checks that count elements of at least elementSize bytes each can still follow, before
    // anything is allocated for them.
    void expectElements(uint64_t count, size_t elementSize, uint64_t maxCount);

    size_t remaining() const { return size_t(end_ - p_); }
    void expectEnd() const;  // trailing bytes are an error

private:
    void need(size_t n) const;
    const uint8_t* p_;
    const uint8_t* end_;
};

}  // namespace rtwall::cluster
