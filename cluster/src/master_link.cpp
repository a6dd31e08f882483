// The master's link: the network thread's receive loop, the dispatch of every message to its
// job, sends that never block, and the counting of what is dropped.
#include "master_impl.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace rtwall {

namespace {

std::string hex(uint32_t v) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%x", v);
    return buf;
}

}  // namespace

MasterCounters Master::Impl::countersNow() const {
    MasterCounters c;
    {
        std::lock_guard lock(countersMutex);
        c = counts;
    }
    if (link.zap) c.refused += link.zap->denied();
    return c;
}

// "client 3 at 127.0.0.1" or "127.0.0.1 (not a client)", for log lines.
std::string Master::Impl::who() const {
    std::string s;
    if (currentClient) s = "client " + std::to_string(currentClient->id) + " at ";
    s += current ? peerAddressOf(*current) : std::string("?");
    if (!currentClient) s += " (not a client)";
    return s;
}

// Counts one event of a kind; the first few are logged with what and from whom.
void Master::Impl::count(uint64_t MasterCounters::*kind, const char* kindName, const std::string& what) {
    uint64_t n;
    {
        std::lock_guard lock(countersMutex);
        n = ++(counts.*kind);
    }
    if (n <= kLoggedPerKind)
        std::fprintf(stderr, "rtwall master: %s from %s: %s%s\n", kindName, who().c_str(), what.c_str(),
                     n == kLoggedPerKind ? " (more of this kind are counted, not logged)" : "");
}

void Master::Impl::add(uint64_t MasterCounters::*kind, uint64_t n) {
    std::lock_guard lock(countersMutex);
    counts.*kind += n;
}

SendResult Master::Impl::sendBytes(ClientState& c, MsgType type, const std::vector<uint8_t>& bytes) {
    const SendResult r = sendToPeerResult(link.router, c.peer, bytes);
    const double now = nowSeconds();
    if (r == SendResult::Sent) {
        c.lastSent = now;
        c.fullSince = 0;
        return r;
    }
    uint64_t n;
    {
        std::lock_guard lock(countersMutex);
        n = ++counts.failedSends;
    }
    if (n <= kLoggedPerKind)
        std::fprintf(stderr, "rtwall master: could not send a message (type %d) to client %u: %s%s\n",
                     int(type), c.id, r == SendResult::Full ? "its queue is full" : "it is gone",
                     n == kLoggedPerKind ? " (more failed sends are counted, not logged)" : "");
    if (r == SendResult::Gone) {
        markDead(c, "its connection is gone");
    } else {
        if (c.fullSince == 0) c.fullSince = now;
        c.retryAt = now + 0.01;
    }
    return r;
}

void Master::Impl::wake() {
    std::lock_guard lock(link.wakeMutex);
    const uint8_t one = 1;
    link.wakeSend.send(zmq::const_buffer(&one, 1), zmq::send_flags::dontwait);
}

void Master::Impl::handle(zmq::message_t& identity, zmq::message_t& msg) {
    const std::string peer(static_cast<const char*>(identity.data()), identity.size());
    const auto* bytes = static_cast<const uint8_t*>(msg.data());
    auto known = clients.find(peer);
    currentClient = known == clients.end() ? nullptr : &known->second;
    Header h;
    try {
        h = decodeHeader(bytes, msg.size());
    } catch (const DecodeError& e) {
        malformed(e.what());
        return;
    }
    const uint8_t* payload = bytes + kHeaderSize;
    const size_t payloadSize = msg.size() - kHeaderSize;
    try {
        if (h.type == MsgType::Hello) {
            onHello(peer, h, payload, payloadSize);
            return;
        }
        if (h.type == MsgType::NodeHello) {
            onNodeHello(peer, h, payload, payloadSize);
            return;
        }
        if (auto node = display.nodes.find(peer); node != display.nodes.end()) {
            if (h.session != session || h.version != kProtocolVersion) {
                count(&MasterCounters::unknownPeer, "dropped a message", "another session or protocol version");
                return;
            }
            handleNode(node->second, h, payload, payloadSize);
            return;
        }
        if (known == clients.end() || h.session != session || h.version != kProtocolVersion) {
            // Not (or no longer) one of ours.
            count(&MasterCounters::unknownPeer, "dropped a message",
                  known == clients.end() ? "it is not a client (no hello, or dropped)" : "another session or protocol version");
            return;
        }
        ClientState& c = known->second;
        c.lastSeen = nowSeconds();
        switch (h.type) {
        case MsgType::Ready: onReady(c, payload, payloadSize); break;
        case MsgType::MeshRequest: onMeshRequest(c, payload, payloadSize); break;
        case MsgType::AssetRequest: onAssetRequest(c, payload, payloadSize); break;
        case MsgType::TileRequest: {
            const TileRequest req = decodePayload<TileRequest>(payload, payloadSize);
            if (frameActive && req.frame == currentFrame) {
                c.credits = std::min<uint32_t>(c.credits + req.count, kMaxCredits);
                c.window = std::max(c.window, std::min<uint32_t>(req.count, kMaxCredits));
                serve(c);
            } else {
                stale("a tile request for frame " + std::to_string(req.frame) + ", which is not being rendered");
            }
            break;
        }
        case MsgType::TileResult: onTileResult(c, h, payload, payloadSize); break;
        case MsgType::TileDone: onTileDone(c, h, decodePayload<TileDone>(payload, payloadSize)); break;
        case MsgType::Heartbeat: onHeartbeat(c, decodePayload<Heartbeat>(payload, payloadSize)); break;
        case MsgType::TileStalled: onTileStalled(c, decodePayload<TileStalled>(payload, payloadSize)); break;
        case MsgType::TileFailed: onTileFailed(c, decodePayload<TileFailed>(payload, payloadSize)); break;
        case MsgType::ResyncRequest: onResyncRequest(c, payload, payloadSize); break;
        case MsgType::Goodbye: {
            const Goodbye bye = decodePayload<Goodbye>(payload, payloadSize);
            std::fprintf(stderr, "rtwall master: client %u says goodbye: %s\n", c.id, bye.reason.c_str());
            markDead(c, "it said goodbye");
            break;
        }
        default:  // a master-to-client type from a client
            unexpected("a message of type " + std::to_string(int(h.type)) + ", which only the master sends");
            break;
        }
    } catch (const DecodeError& e) {
        malformed(std::string("message type ") + std::to_string(int(h.type)) + ": " + e.what());
    }
}

// Connections that broke off in the handshake (the router's monitor): ZMTP garbage, a peer
// without CURVE or with another server key. Key refusals are the ZAP handler's to count.
void Master::Impl::readMonitor() {
    link.monitor.read(64, [&](const MonitorEvent& e) {
        uint64_t n;
        {
            std::lock_guard lock(countersMutex);
            n = ++counts.failedHandshakes;
        }
        if (n > kLoggedPerKind) return;
        // The monitor names the listening endpoint, not the peer.
        std::string why;
        if (e.id != ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL) why = "it broke off (error " + std::to_string(e.value) + ")";
        else if (e.value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH) why = "the peer uses another security mechanism (no CURVE key?)";
        else if (e.value == ZMQ_PROTOCOL_ERROR_ZMTP_CRYPTOGRAPHIC) why = "CURVE failed (a client with another server key?)";
        else why = "ZMTP protocol error 0x" + hex(e.value) + " (not a ZeroMQ peer?)";
        std::fprintf(stderr, "rtwall master: a connection to %s failed its handshake: %s%s\n", e.endpoint.c_str(),
                     why.c_str(), n == kLoggedPerKind ? " (more are counted, not logged)" : "");
    });
}

void Master::Impl::loop() {
    zmq::pollitem_t items[] = {{link.router.handle(), 0, ZMQ_POLLIN, 0},
                               {link.wakeRecv.handle(), 0, ZMQ_POLLIN, 0},
                               {link.monitor.handle(), 0, ZMQ_POLLIN, 0}};
    double lastHousekeeping = 0;
    for (;;) {
        zmq::poll(items, 3, std::chrono::milliseconds(frameActive ? 2 : 20));
        if (items[1].revents & ZMQ_POLLIN) {
            zmq::message_t ignored;
            while (link.wakeRecv.recv(ignored, zmq::recv_flags::dontwait)) {
            }
            sendPendingPose();  // a refresh's pose first: it does not wait behind a frame's commands
            if (withNodes()) sendPictureAsks();
            if (!runCommands()) return;
            reopenFailedTiles();
        }
        if (items[2].revents & ZMQ_POLLIN) readMonitor();
        // Drain what is queued, bounded so commands and timers are not starved.
        for (int i = 0; i < 256 && (items[0].revents & ZMQ_POLLIN); ++i) {
            zmq::message_t identity, msg;
            if (!link.router.recv(identity, zmq::recv_flags::dontwait)) break;
            current = &identity;
            currentClient = nullptr;
            if (!identity.more()) {
                malformed("a frame without a routing id");
                continue;
            }
            if (!link.router.recv(msg, zmq::recv_flags::dontwait)) break;
            current = &msg;
            // rtwall messages are one frame: the extra frames of a message that has more go
            // with it (each recv here reads the next part, not the first part's flag again).
            if (const size_t extra = discardRestOf(link.router, msg); extra > 0) {
                auto known = clients.find(identity.to_string());
                currentClient = known == clients.end() ? nullptr : &known->second;
                malformed("a message of " + std::to_string(extra + 1) + " frames (rtwall messages are one frame)");
                continue;
            }
            handle(identity, msg);
            current = nullptr;
            currentClient = nullptr;
            if (settings.faults && settings.faults->consumeDelayUs > 0)
                std::this_thread::sleep_for(std::chrono::microseconds(settings.faults->consumeDelayUs));
        }
        current = nullptr;
        currentClient = nullptr;
        reap();
        finishFrameIfDone();
        const double now = nowSeconds();
        if (now - lastHousekeeping > 0.002) {
            lastHousekeeping = now;
            flushUpdates();
            checkTimeouts();
            reap();
            retryPending();
            if (withNodes()) nodeHousekeeping();
            serveAll();  // re-queued tiles of departed clients, stragglers
        }
    }
}

}  // namespace rtwall
