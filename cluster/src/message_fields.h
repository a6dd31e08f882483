// One description of a wire value serves both directions. Each message or scene value has one
// `fields(io, value)` function template that names its fields in wire order, with the range each
// one must lie in; called with a FieldWriter it writes them (and checks nothing: a sender writes
// what it has), called with a FieldReader it reads and checks them, throwing DecodeError. So a
// message's layout is written once, and its encoder and decoder cannot drift apart.
//
// Internal to the protocol code (protocol_*.cpp); everything else uses protocol.h.
#pragma once

#include "fields.h"
#include "protocol.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace rtwall::cluster {

[[noreturn]] inline void fail(const std::string& what) { throw DecodeError(what); }

// The value a fields() function takes: const for the writer, writable for the reader.
template <class Io, class T> using In = std::conditional_t<Io::decoding, T&, const T&>;

// What a sequence's count may be on the sending side: any u32 (the reader enforces the limit, and
// tests send too many on purpose), or the reader's limit too (a list the sender builds itself
// and must never make too long).
enum class SendLimit { U32, Strict };

class FieldWriter {
public:
    static constexpr bool decoding = false;
    explicit FieldWriter(Writer& w) : w_(w) {}

    void u8(uint8_t v) { w_.u8(v); }
    void u16(uint16_t v) { w_.u16(v); }
    void u32(uint32_t v) { w_.u32(v); }
    void u64(uint64_t v) { w_.u64(v); }
    void i32(int32_t v) { w_.i32(v); }
    void f32(float v) { w_.f32(v); }
    void f64(double v) { w_.f64(v); }
    void boolean(bool v) { w_.boolean(v); }
    void float3(const Float3& v) {
        w_.f32(v.x);
        w_.f32(v.y);
        w_.f32(v.z);
    }
    void float3OrNaN(const Float3& v) { float3(v); }
    void hash(const Hash128& h) {
        w_.u64(h[0]);
        w_.u64(h[1]);
    }
    void string(const std::string& s, size_t) { w_.string(s); }
    void blob(const std::vector<uint8_t>& b, size_t) { w_.blob(b.data(), b.size()); }

    // The reader's range checks; the writer writes the value as it is.
    void intIn(int32_t v, int64_t, int64_t, const char*) { w_.i32(v); }
    void floatIn(float v, float, float, const char*) { w_.f32(v); }
    void unitColor(const Color& c, const char*) { float3(c); }
    void nonNegativeColor(const Color& c, const char*) { float3(c); }
    template <class E> void enumUpTo(E v, E, const char*) { w_.u8(uint8_t(v)); }
    template <class E> void enumInRange(E v, E, const char*) { w_.u8(uint8_t(v)); }
    template <class F> void expect(bool, F&&) {}
    // A field at the very end of a message that only some messages carry (version 14's depth):
    // written only when present, so that a message without it is, byte for byte, what it was
    // before the field existed.
    template <class F> void trailing(bool present, F&& each) {
        if (present) each();
    }

    // A u32 count, then each element.
    template <class T, class Each, class CountCheck = void (*)(uint32_t)>
    void sequence(const std::vector<T>& v, size_t, uint64_t maxCount, Each&& each, SendLimit limit = SendLimit::U32,
                  CountCheck&& = [](uint32_t) {}) {
        const uint64_t most = limit == SendLimit::Strict ? maxCount : std::numeric_limits<uint32_t>::max();
        if (v.size() > most)
            throw std::length_error("protocol: " + std::to_string(v.size()) + " elements exceed the limit of " +
                                    std::to_string(most));
        w_.u32(uint32_t(v.size()));
        for (const T& e : v) each(e);
    }

private:
    Writer& w_;
};

class FieldReader {
public:
    static constexpr bool decoding = true;
    explicit FieldReader(Reader& r) : r_(r) {}

    void u8(uint8_t& v) { v = r_.u8(); }
    void u16(uint16_t& v) { v = r_.u16(); }
    void u32(uint32_t& v) { v = r_.u32(); }
    void u64(uint64_t& v) { v = r_.u64(); }
    void i32(int32_t& v) { v = r_.i32(); }
    void f32(float& v) { v = r_.f32(); }  // finite
    void f64(double& v) { v = r_.f64(); }  // finite
    void boolean(bool& v) { v = r_.boolean(); }
    void float3(Float3& v) {
        v.x = r_.f32();
        v.y = r_.f32();
        v.z = r_.f32();
    }
    // Finite or NaN (a warp's pixel on no screen): infinity is refused.
    void float3OrNaN(Float3& v) {
        v.x = r_.f32Any();
        v.y = r_.f32Any();
        v.z = r_.f32Any();
        if (std::isinf(v.x) || std::isinf(v.y) || std::isinf(v.z)) fail("warp sample is infinite");
    }
    void hash(Hash128& h) {
        h[0] = r_.u64();
        h[1] = r_.u64();
    }
    void string(std::string& s, size_t maxLength) { s = r_.string(maxLength); }
    void blob(std::vector<uint8_t>& b, size_t maxLength) {
        const auto [p, n] = r_.blobView(maxLength);
        b.assign(p, p + n);
    }
    // A view into the message instead of a copy (peekTileResult).
    void blob(std::pair<const uint8_t*, size_t>& view, size_t maxLength) { view = r_.blobView(maxLength); }

    void intIn(int32_t& v, int64_t lo, int64_t hi, const char* what) {
        v = r_.i32();
        if (v < lo || v > hi)
            fail(std::string(what) + " " + std::to_string(v) + " is out of range [" + std::to_string(lo) + ", " +
                 std::to_string(hi) + "]");
    }
    void floatIn(float& v, float lo, float hi, const char* what) {
        v = r_.f32();
        if (!(v >= lo && v <= hi)) fail(std::string(what) + " " + std::to_string(v) + " is out of range");
    }
    // A surface cannot reflect more than it receives; the shading code assumes it.
    void unitColor(Color& c, const char* what) {
        color(c, what, [](float v) { return v >= 0.0f && v <= 1.0f; }, " is outside [0, 1]");
    }
    void nonNegativeColor(Color& c, const char* what) {
        color(c, what, [](float v) { return v >= 0.0f && std::isfinite(v); }, " is negative");
    }
    template <class E> void enumUpTo(E& v, E last, const char* what) {
        const uint8_t b = r_.u8();
        if (b > uint8_t(last)) fail(std::string("unknown ") + what + " " + std::to_string(b));
        v = E(b);
    }
    template <class E> void enumInRange(E& v, E last, const char* what) {
        const uint8_t b = r_.u8();
        if (b > uint8_t(last)) fail(std::string(what) + " " + std::to_string(b) + " is out of range");
        v = E(b);
    }
    // A check on what was read so far; `message` builds the error text only when it fails.
    template <class F> void expect(bool ok, F&& message) {
        if (!ok) fail(message());
    }
    // Present when bytes are left (the field is the message's last); `each` reads it and must
    // refuse the value the writer leaves out, so that every message has one encoding.
    template <class F> void trailing(bool& present, F&& each) {
        present = r_.remaining() > 0;
        if (present) each();
    }

    // A u32 count, checked by countCheck and against maxCount and the bytes left (elements of at
    // least minElementBytes each) before anything is allocated, then each element.
    template <class T, class Each, class CountCheck = void (*)(uint32_t)>
    void sequence(std::vector<T>& v, size_t minElementBytes, uint64_t maxCount, Each&& each, SendLimit = SendLimit::U32,
                  CountCheck&& countCheck = [](uint32_t) {}) {
        const uint32_t n = r_.u32();
        countCheck(n);
        r_.expectElements(n, minElementBytes, maxCount);
        v.resize(n);
        for (T& e : v) each(e);
    }

private:
    template <class Ok> void color(Color& c, const char* what, Ok ok, const char* otherwise) {
        float3(c);
        for (float v : {c.x, c.y, c.z})
            if (!ok(v)) fail(std::string(what) + " component " + std::to_string(v) + otherwise);
    }

    Reader& r_;
};

// A u32 count, then each element by its own fields().
template <class Io, class V>
void vectorOf(Io& io, V& v, size_t minElementBytes, uint64_t maxCount, SendLimit limit = SendLimit::U32) {
    io.sequence(v, minElementBytes, maxCount, [&](auto& e) { fields(io, e); }, limit);
}

// The smallest encoding of a value (measured with the writer itself, so that the element-count
// checks cannot drift from the format).
template <class T> size_t minEncodedSize(const T& emptyValue) {
    Writer w;
    FieldWriter io(w);
    fields(io, emptyValue);
    return w.size();
}

// Measures with a counting writer, reserves exactly, then writes with the same code.
template <class F> std::vector<uint8_t> measureAndWrite(F&& writeAll) {
    Writer counter;
    writeAll(counter);
    std::vector<uint8_t> out;
    out.reserve(counter.size());
    Writer w(&out);
    writeAll(w);
    if (w.size() != counter.size())
        throw std::logic_error("protocol: measured " + std::to_string(counter.size()) + " bytes but wrote " +
                               std::to_string(w.size()));
    return out;
}

void writeHeader(Writer& w, const Header& h);  // protocol_session.cpp

template <class Msg> std::vector<uint8_t> encodeMessage(Header header, const Msg& msg) {
    // The type always follows the message, so a header copied from another message cannot mislabel it.
    header.type = messageTypeOf(msg);
    Writer counter;
    FieldWriter countIo(counter);
    fields(countIo, msg);
    if (counter.size() > std::numeric_limits<uint32_t>::max())
        throw std::length_error("protocol: payload of " + std::to_string(counter.size()) + " bytes is too large");
    header.payloadLength = uint32_t(counter.size());

    std::vector<uint8_t> out;
    out.reserve(kHeaderSize + counter.size());
    Writer w(&out);
    writeHeader(w, header);
    FieldWriter io(w);
    fields(io, msg);
    if (w.size() != kHeaderSize + counter.size())
        throw std::logic_error("protocol: measured " + std::to_string(kHeaderSize + counter.size()) +
                               " bytes but wrote " + std::to_string(w.size()));
    return out;
}

template <class Msg> Msg decodePayload(const uint8_t* data, size_t size) {
    Reader r(data, size);
    FieldReader io(r);
    Msg msg;
    fields(io, msg);
    r.expectEnd();
    return msg;
}

// The head of a value's fields() function (its body follows, with the value as `m`), after a check
// that the struct has exactly the members the body handles: a member added to one of these structs
// fails the build here until it is written and read (and set to a non-default value in the
// round-trip tests, which compare every member).
#define RTWALL_WIRE_COUNT(T, n)                                                                     \
    static_assert(fieldCount<T>() == (n), #T " has a member that its wire fields do not handle: " \
                                             "add it to fields() and update this count")
#define RTWALL_WIRE_FIELDS(T, n) \
    RTWALL_WIRE_COUNT(T, n);     \
    template <class Io> void fields(Io& io, In<Io, T> m)

// The same for a message, which also gets its MsgType, its encoder and its decoder here (they call
// the fields() whose body follows).
#define RTWALL_WIRE_MESSAGE(Msg, n)                                                  \
    template <class Io> void fields(Io& io, In<Io, Msg> m);                          \
    MsgType messageTypeOf(const Msg&) { return MsgType::Msg; }                       \
    template std::vector<uint8_t> encodeMessage<Msg>(Header header, const Msg& msg); \
    template Msg decodePayload<Msg>(const uint8_t* data, size_t size);               \
    RTWALL_WIRE_FIELDS(Msg, n)

// Ranges the engine relies on; the same bounds the scene-file loader enforces.
inline constexpr int kMaxImageSide = 16384;
inline constexpr int kMaxTileSize = 1024;
inline constexpr int kMaxThreads = 1024;

}  // namespace rtwall::cluster
