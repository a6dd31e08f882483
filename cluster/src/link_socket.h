// Socket set-up that the master, the render clients and the display nodes share: CURVE keys on
// either side of a connection, a socket's monitor, and what a peer says when its handshake with
// the master fails. Written once here so that the three agree on every key option and log line.
#pragma once

#include "net.h"
#include "protocol.h"
#include "security.h"

#include <zmq.hpp>

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

namespace rtwall::cluster {

// A CURVE server: it holds `secretKeyZ85`; who may connect is the ZAP handler's to say.
void setCurveServer(zmq::socket_t& s, const std::string& secretKeyZ85);
// A CURVE client of the server whose public key is `serverKeyZ85`, with its own key pair.
void setCurveClient(zmq::socket_t& s, const std::string& serverKeyZ85, const KeyPair& keys);

// One event of a socket monitor (zmq_socket_monitor): the first frame holds a 16-bit event id
// and a 32-bit value, in this machine's byte order; the second frame is the endpoint.
struct MonitorEvent {
    uint16_t id = 0;
    uint32_t value = 0;
    std::string endpoint;  // the monitored socket's endpoint (a listening socket's, not the peer's)
};
// Nullopt for a first frame too short for an event.
std::optional<MonitorEvent> decodeMonitorEvent(const zmq::message_t& head, const zmq::message_t& endpoint);

// The handshake events a peer watches on its connection to the master.
inline constexpr int kMasterLinkEvents = ZMQ_EVENT_HANDSHAKE_FAILED_AUTH | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                                         ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_SUCCEEDED;

// A PAIR socket connected to another socket's monitor.
class SocketMonitor {
public:
    // Watches `events` of `watched`, published at inproc `address`. False when libzmq refuses
    // (zmq_errno() says why); this monitor is then left as it was.
    bool start(zmq::context_t& ctx, zmq::socket_t& watched, const std::string& address, int events);
    // Ends the watch of `watched` and closes this side.
    void stop(zmq::socket_t& watched);
    void reset() { socket_ = zmq::socket_t(); }
    explicit operator bool() const { return bool(socket_); }
    void* handle() { return socket_.handle(); }

    // Hands each of up to `max` queued events to `onEvent`, never waiting; a malformed one
    // (no endpoint frame, a short first frame) is skipped and counts towards `max`.
    template <class F> void read(int max, F&& onEvent) {
        for (int i = 0; i < max; ++i) {
            zmq::message_t head, endpoint;
            if (!socket_.recv(head, zmq::recv_flags::dontwait)) return;
            if (!head.more() || !socket_.recv(endpoint, zmq::recv_flags::dontwait)) continue;
            discardRestOf(socket_, endpoint);
            if (const std::optional<MonitorEvent> e = decodeMonitorEvent(head, endpoint)) onEvent(*e);
        }
    }

private:
    zmq::socket_t socket_;
};

// What a render client or a display node says about the handshakes of its connection to the
// master: a refusal is said, not just "no master"; the same trouble is said once until it
// changes, and a handshake that succeeds clears it.
class MasterHandshakeWatch {
public:
    // `self` names the peer in its lines ("client": "this client's key"); `logPrefix` starts
    // them ("rtwall client").
    MasterHandshakeWatch(std::string self, std::string logPrefix) : self_(std::move(self)), logPrefix_(std::move(logPrefix)) {}

    // One event of the connection to `connect`. `publicKey`: this peer's (empty without keys).
    // `refused`, `failed`: counters of refused and otherwise broken handshakes (may be null).
    void onEvent(const MonitorEvent& e, const std::string& connect, const std::string& publicKey,
                 std::atomic<uint64_t>* refused, std::atomic<uint64_t>* failed);

    const std::string& trouble() const { return trouble_; }  // the last failed handshake, or empty
    uint64_t failures() const { return failures_; }          // failed handshakes since the last success

private:
    std::string why(const MonitorEvent& e, const std::string& publicKey) const;
    std::string self_, logPrefix_;
    std::string trouble_;
    uint64_t failures_ = 0;
};

// A peer's refusal of a master that speaks another protocol version: prints the one line that
// names both ("rtwall client: the master speaks protocol version 12, this client 13") and returns
// true; false when the versions agree. `program` is the log prefix, `self` what this peer is.
bool refuseOtherVersion(const Header& fromMaster, const char* program, const char* self);

}  // namespace rtwall::cluster
