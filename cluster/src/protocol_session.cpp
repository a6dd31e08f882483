// The session on the wire: the header every message starts with, a client's Hello and the master's
// Welcome, heartbeats and goodbyes.
#include "protocol_values.h"

namespace rtwall::cluster {

// -- Header --------------------------------------------------------------------------------------

RTWALL_WIRE_COUNT(Header, 6);
// `payloadSize`: the bytes after the header (the reader checks the header's length against it).
template <class Io> void headerFields(Io& io, In<Io, Header> h, size_t payloadSize) {
    uint32_t magic = kMagic;
    io.u32(magic);
    io.expect(magic == kMagic, [&] { return "bad magic number " + std::to_string(magic); });
    // A version mismatch is the caller's to report (with both versions), not an error here.
    io.u16(h.version);
    uint16_t type = uint16_t(h.type);
    io.u16(type);
    io.expect(type >= 1 && type <= kMaxMsgType, [&] { return "unknown message type " + std::to_string(type); });
    if constexpr (Io::decoding) h.type = MsgType(type);
    io.u64(h.session);
    io.u32(h.frame);
    io.u32(h.sceneVersion);
    io.u32(h.payloadLength);
    io.expect(h.payloadLength == payloadSize, [&] {
        return "header says " + std::to_string(h.payloadLength) + " payload bytes, message has " +
               std::to_string(payloadSize);
    });
    uint32_t reserved = 0;
    io.u32(reserved);
    io.expect(reserved == 0, [&] { return "reserved header field is " + std::to_string(reserved) + ", not 0"; });
}

void writeHeader(Writer& w, const Header& h) {
    FieldWriter io(w);
    headerFields(io, h, h.payloadLength);
}

Header decodeHeader(const uint8_t* data, size_t size) {
    if (size < kHeaderSize)
        fail("message of " + std::to_string(size) + " bytes is shorter than the " + std::to_string(kHeaderSize) +
             "-byte header");
    Reader r(data, kHeaderSize);
    FieldReader io(r);
    Header h;
    headerFields(io, h, size - kHeaderSize);
    return h;
}

// -- Messages ------------------------------------------------------------------------------------

RTWALL_WIRE_MESSAGE(Hello, 3) {
    io.u16(m.protocolVersion);  // returned as read, so that the master can name both versions
    io.u32(m.threads);
    io.expect(m.threads <= uint32_t(kMaxThreads),
              [&] { return "thread count " + std::to_string(m.threads) + " exceeds the limit"; });
    io.string(m.host, kMaxStringBytes);
}

RTWALL_WIRE_MESSAGE(Welcome, 5) {
    io.u32(m.clientId);
    fields(io, m.codec);
    io.u32(m.prefetch);
    // A client never needs more tiles in flight than one assignment can carry.
    io.expect(m.prefetch <= kMaxTilesPerMessage, [&] { return "prefetch " + std::to_string(m.prefetch) + " exceeds the limit"; });
    io.u32(m.heartbeatMs);
    io.u32(m.timeoutMs);
    // The client turns these into socket options (ints) and timers: keep them sane.
    io.expect(m.heartbeatMs <= kMaxTimeoutMs && m.timeoutMs <= kMaxTimeoutMs, [&] {
        return "heartbeat " + std::to_string(m.heartbeatMs) + " ms or timeout " + std::to_string(m.timeoutMs) +
               " ms exceeds the limit";
    });
}

RTWALL_WIRE_MESSAGE(Heartbeat, 3) {
    io.u32(m.frame);
    io.u32(m.tilesSeen);
    io.boolean(m.idle);
}

RTWALL_WIRE_MESSAGE(Goodbye, 1) { io.string(m.reason, kMaxStringBytes); }

}  // namespace rtwall::cluster
