// ZeroMQ helpers shared by the master and the client: socket options in one place, and
// sends that never block.
#pragma once

#include "protocol.h"

#include <zmq.hpp>

#include <chrono>
#include <cstdint>
#include <string>

namespace rtwall::cluster {

inline double nowSeconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// High-water marks, in messages (the default; the master's is ClusterSettings::highWaterMark).
// A tile result is at most one tile's pixels; 1000 of them in a queue are a few tens of MB at
// worst, so memory stays bounded while a peer is slow.
inline constexpr int kSendHwm = 1000;

// Options every rtwall socket gets: finite linger (a dead peer cannot keep the process alive),
// bounded queues, the largest legitimate message as ZMQ_MAXMSGSIZE, and ZMTP heartbeats so a
// peer that vanished without a FIN is noticed by the transport as well as by our own timeouts.
inline void configureSocket(zmq::socket_t& s, int64_t maxMessageBytes, int heartbeatMs, int timeoutMs,
                            int highWaterMark = kSendHwm) {
    s.set(zmq::sockopt::linger, 100);
    s.set(zmq::sockopt::sndhwm, highWaterMark);
    s.set(zmq::sockopt::rcvhwm, highWaterMark);
    s.set(zmq::sockopt::maxmsgsize, maxMessageBytes);
    s.set(zmq::sockopt::heartbeat_ivl, heartbeatMs);
    s.set(zmq::sockopt::heartbeat_timeout, timeoutMs);
    s.set(zmq::sockopt::heartbeat_ttl, timeoutMs);
}

// Non-blocking send of one message; false if the peer's queue is full or it is unreachable
// (ZMQ_ROUTER_MANDATORY), which the caller treats as a sign of a dead or stuck peer. Never a
// blocking send: with ZMQ_ROUTER_MANDATORY a blocking send to a peer at its high-water mark
// that then disconnects waits forever (libzmq issue #2348, pull request #4665); with
// ZMQ_DONTWAIT it returns EAGAIN or EHOSTUNREACH at once.
inline bool sendNow(zmq::socket_t& s, const std::vector<uint8_t>& bytes) {
    try {
        return s.send(zmq::const_buffer(bytes.data(), bytes.size()), zmq::send_flags::dontwait).has_value();
    } catch (const zmq::error_t&) {
        return false;
    }
}

// What became of a send to one peer of a ROUTER (ZMQ_ROUTER_MANDATORY). Full (EAGAIN) is not
// death: a live peer busy for a moment can be at its high-water mark; Gone (EHOSTUNREACH) means
// its connection has closed.
enum class SendResult { Sent, Full, Gone };

inline SendResult sendToPeerResult(zmq::socket_t& router, const std::string& peer, const std::vector<uint8_t>& bytes) {
    try {
        if (!router.send(zmq::buffer(peer), zmq::send_flags::sndmore | zmq::send_flags::dontwait)) return SendResult::Full;
        // The high-water mark is checked at the first frame; the second cannot find it full.
        if (!router.send(zmq::const_buffer(bytes.data(), bytes.size()), zmq::send_flags::dontwait)) return SendResult::Full;
        return SendResult::Sent;
    } catch (const zmq::error_t& e) {
        return e.num() == EAGAIN ? SendResult::Full : SendResult::Gone;
    }
}

inline bool sendToPeer(zmq::socket_t& router, const std::string& peer, const std::vector<uint8_t>& bytes) {
    return sendToPeerResult(router, peer, bytes) == SendResult::Sent;
}

// Reads the rest of a multi-frame message after `first` (rtwall messages are one frame; the
// rest is thrown away). Returns how many frames followed it. Parts of one message arrive
// together, so this never waits.
inline size_t discardRestOf(zmq::socket_t& s, const zmq::message_t& first) {
    size_t extra = 0;
    for (bool more = first.more(); more; ++extra) {
        zmq::message_t part;
        if (!s.recv(part, zmq::recv_flags::dontwait)) break;
        more = part.more();
    }
    return extra;
}

// The address a received message came from ("Peer-Address", libzmq >= 4.1), or "?".
inline std::string peerAddressOf(const zmq::message_t& msg) {
    const char* a = zmq_msg_gets(msg.handle(), "Peer-Address");
    return a ? std::string(a) : std::string("?");
}

}  // namespace rtwall::cluster
