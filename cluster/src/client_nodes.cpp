// A render client's links to the display nodes (issue 19): one DEALER per node of the master's
// list; a finished tile goes to the nodes of its mask, and a TileDone to the master.
#include "client_runtime.h"

#include <cstdio>

namespace rtwall::cluster {

// One DEALER per node of the master's list (CURVE with the node's server key when this
// client has keys); kept while the node's endpoint and key stay the same. ZMQ_IMMEDIATE: a
// tile for a node that is not connected is dropped, never queued for a dead peer.
void ClientRuntime::onNodeList(const NodeList& list) {
    std::map<uint32_t, NodeLink> next;
    for (const NodeEndpoint& e : list.nodes) {
        auto old = nodeLinks_.find(e.node);
        if (old != nodeLinks_.end() && old->second.endpoint == e.endpoint && old->second.serverKey == e.serverKey) {
            next.emplace(e.node, std::move(old->second));
            continue;
        }
        if (!settings_.keyFile.empty() && e.serverKey.empty()) {
            // Behind CURVE, pixels never go in the clear.
            std::fprintf(stderr, "rtwall client %u: display node '%s' at %s has no CURVE key: its tiles are not sent\n", id_,
                         e.name.c_str(), e.endpoint.c_str());
            continue;
        }
        NodeLink link{e.endpoint, e.serverKey, zmq::socket_t(ctx_, zmq::socket_type::dealer), e.name, {}, false};
        link.socket.set(zmq::sockopt::linger, 0);
        link.socket.set(zmq::sockopt::immediate, 1);
        link.socket.set(zmq::sockopt::sndhwm, 1000);
        link.socket.set(zmq::sockopt::reconnect_ivl, 100);
        if (!settings_.keyFile.empty() && !e.serverKey.empty()) {
            setCurveClient(link.socket, e.serverKey, keys_);
            // A node that refuses this client's key is said once (readNodeMonitors).
            link.monitor.start(ctx_, link.socket, "inproc://rtwall-client-node-monitor-" + std::to_string(++monitorSeq_),
                               ZMQ_EVENT_HANDSHAKE_FAILED_AUTH | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                                   ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL);
        }
        try {
            link.socket.connect(e.endpoint);
        } catch (const zmq::error_t& err) {
            std::fprintf(stderr, "rtwall client %u: cannot connect to display node '%s' at %s: %s\n", id_, e.name.c_str(),
                         e.endpoint.c_str(), err.what());
            continue;
        }
        next.emplace(e.node, std::move(link));
    }
    nodeLinks_ = std::move(next);  // links of nodes no longer listed close here
}

// Handshake failures of the links to the nodes, each said once per link.
void ClientRuntime::readNodeMonitors() {
    for (auto& entry : nodeLinks_) {
        auto& link = entry.second;  // not a structured binding: clang 14 cannot capture those in the lambda
        if (!link.monitor) continue;
        link.monitor.read(8, [&](const MonitorEvent& e) {
            if (settings_.counters) ++(e.id == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH ? settings_.counters->refusedHandshakes
                                                                               : settings_.counters->failedHandshakes);
            if (link.said) return;
            link.said = true;
            if (e.id == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH)
                std::fprintf(stderr, "rtwall client %u: display node '%s' at %s refused this client's key %s (status %u): "
                                     "it takes the keys the master gives it\n",
                             id_, link.name.c_str(), link.endpoint.c_str(), keys_.publicKey.c_str(), e.value);
            else
                std::fprintf(stderr, "rtwall client %u: the CURVE handshake with display node '%s' at %s failed (event %u, "
                                     "value %u)\n", id_, link.name.c_str(), link.endpoint.c_str(), unsigned(e.id), e.value);
        });
    }
}

// The masks for frames from routes.frame on; the previous set stays for the results of
// earlier frames still on their way (async frames overlap by one).
void ClientRuntime::onTileRoutes(TileRoutes routes) {
    const uint32_t from = routes.frame;
    tileRoutes_[from] = std::move(routes.masks);
    while (tileRoutes_.size() > 2) tileRoutes_.erase(tileRoutes_.begin());
}

// A finished tile (an encoded TileResult) goes to every node of its mask, then a TileDone
// to the master. Nothing blocks: a node whose queue is full or that is not connected misses
// the tile (and is left out of that frame's swap).
void ClientRuntime::sendToNodes(const zmq::message_t& msg) {
    const auto* bytes = static_cast<const uint8_t*>(msg.data());
    if (msg.size() < kHeaderSize) return;
    TileResultInfo info;
    try {
        info = peekTileResult(bytes + kHeaderSize, msg.size() - kHeaderSize);  // written by this client itself
    } catch (const DecodeError&) {
        return;
    }
    const uint32_t frame = info.frame, tile = info.tile;
    auto routes = tileRoutes_.upper_bound(frame);
    if (routes == tileRoutes_.begin()) return;  // no masks for a frame this old
    const std::vector<uint64_t>& masks = std::prev(routes)->second;
    if (tile >= masks.size()) return;
    for (auto& [node, link] : nodeLinks_) {
        if (!(masks[tile] >> node & 1)) continue;
        zmq::message_t copy(msg.data(), msg.size());
        if (!link.socket.send(copy, zmq::send_flags::dontwait)) ++lostResults_;
    }
    send(TileDone{frame, tile, info.renderMicros, info.pixelBytes + info.depthBytes}, frame);
}

}  // namespace rtwall::cluster
