#include "link_socket.h"

#include <cstdio>
#include <cstring>

namespace rtwall::cluster {

void setCurveServer(zmq::socket_t& s, const std::string& secretKeyZ85) {
    s.set(zmq::sockopt::curve_server, 1);
    s.set(zmq::sockopt::curve_secretkey, secretKeyZ85);
}

void setCurveClient(zmq::socket_t& s, const std::string& serverKeyZ85, const KeyPair& keys) {
    s.set(zmq::sockopt::curve_serverkey, serverKeyZ85);
    s.set(zmq::sockopt::curve_publickey, keys.publicKey);
    s.set(zmq::sockopt::curve_secretkey, keys.secretKey);
}

std::optional<MonitorEvent> decodeMonitorEvent(const zmq::message_t& head, const zmq::message_t& endpoint) {
    if (head.size() < 6) return std::nullopt;
    MonitorEvent e;
    std::memcpy(&e.id, head.data(), 2);
    std::memcpy(&e.value, static_cast<const uint8_t*>(head.data()) + 2, 4);
    e.endpoint = endpoint.to_string();
    return e;
}

bool SocketMonitor::start(zmq::context_t& ctx, zmq::socket_t& watched, const std::string& address, int events) {
    if (zmq_socket_monitor(watched.handle(), address.c_str(), events) != 0) return false;
    socket_ = zmq::socket_t(ctx, zmq::socket_type::pair);
    socket_.set(zmq::sockopt::linger, 0);
    socket_.connect(address);
    return true;
}

void SocketMonitor::stop(zmq::socket_t& watched) {
    zmq_socket_monitor(watched.handle(), nullptr, 0);
    socket_.close();
}

void MasterHandshakeWatch::onEvent(const MonitorEvent& e, const std::string& connect, const std::string& publicKey,
                                   std::atomic<uint64_t>* refused, std::atomic<uint64_t>* failed) {
    if (e.id == ZMQ_EVENT_HANDSHAKE_SUCCEEDED) {
        trouble_.clear();
        failures_ = 0;
        return;
    }
    std::atomic<uint64_t>* counter = e.id == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH ? refused : failed;
    if (counter) ++*counter;
    const std::string now = why(e, publicKey);
    if (now != trouble_) std::fprintf(stderr, "%s: %s: %s\n", logPrefix_.c_str(), connect.c_str(), now.c_str());
    trouble_ = now;
    ++failures_;
}

std::string MasterHandshakeWatch::why(const MonitorEvent& e, const std::string& publicKey) const {
    if (e.id == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH)
        return "the master refused this " + self_ + "'s key (status " + std::to_string(e.value) + "): is " +
               (publicKey.empty() ? std::string("its key") : publicKey) + " in the master's client_keys?";
    if (e.id == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL && e.value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH)
        return "the master and this " + self_ + " disagree on security: one uses CURVE keys, the other not";
    if (e.id == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL)
        return "the handshake failed (ZMTP protocol error " + std::to_string(e.value) + ")";
    // The master closes the connection as soon as it sees the other mechanism, and its greeting
    // may be lost with the reset: keyless, this is the likely cause.
    if (publicKey.empty())
        return "the master broke off the handshake: do the master and this " + self_ +
               " disagree on security (a master with CURVE keys needs --key and --server-key here)?";
    return "the master broke off the CURVE handshake: is --server-key its public key?";
}

bool refuseOtherVersion(const Header& fromMaster, const char* program, const char* self) {
    if (fromMaster.version == kProtocolVersion) return false;
    std::fprintf(stderr, "%s: the master speaks protocol version %u, this %s %u\n", program, unsigned(fromMaster.version), self,
                 unsigned(kProtocolVersion));
    return true;
}

}  // namespace rtwall::cluster
