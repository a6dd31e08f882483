// The master's render clients: hello and welcome, proving the state they were sent, heartbeats
// and timeouts, leaving.
#include "master_impl.h"

#include <algorithm>
#include <cstdio>

namespace rtwall {

void Master::Impl::reap() {
    bool any = false;
    for (auto it = clients.begin(); it != clients.end();) {
        if (!it->second.deathReason) {
            ++it;
            continue;
        }
        std::fprintf(stderr, "rtwall master: client %u leaves: %s\n", it->second.id, it->second.deathReason);
        scheduler.removeClient(it->second.id);  // its tiles go back to the shared queue
        if (it->second.ready) {
            std::lock_guard lock(m);
            --readyClients;
        }
        it = clients.erase(it);
        add(&MasterCounters::clientsDropped, 1);
        any = true;
    }
    if (any) serveAll();
}

// The wall's warp grids, once per client after its Welcome (none: nothing is sent).
SendResult Master::Impl::sendWarpGrids(ClientState& c) {
    if (settings.warpGrids.empty()) return SendResult::Sent;
    WarpGrids grids;
    grids.grids.reserve(settings.warpGrids.size());
    for (const auto& g : settings.warpGrids) grids.grids.push_back(*g);
    return send(c, grids);
}

Welcome Master::Impl::welcomeFor(const ClientState& c) const {
    return Welcome{c.id, settings.codec, uint32_t(settings.prefetch), uint32_t(settings.heartbeatMs),
                   uint32_t(settings.timeoutMs)};
}

void Master::Impl::sendFrameBegin(ClientState& c) {
    if (withNodes() && c.routesFrame != display.routesFrame) {
        if (send(c, TileRoutes{display.routesFrame, display.routes}, currentFrame) != SendResult::Sent) return;
        c.routesFrame = display.routesFrame;
    }
    if (send(c, FrameBegin{currentFrame, frameSeq, framePixels, beginViews, settings.depth, frameFeatures}, currentFrame) == SendResult::Sent)
        c.frameBegun = currentFrame;
}

// Messages that did not fit a client's queue and that it cannot do without: a codec change,
// its state, the current frame's FrameBegin. Tried again every 10 ms while the queue is full.
void Master::Impl::retryPending() {
    const double now = nowSeconds();
    for (auto& [peer, c] : clients) {
        if (c.deathReason || now < c.retryAt) continue;
        if (c.needsWelcome) {
            if (send(c, welcomeFor(c)) != SendResult::Sent) continue;
            c.needsWelcome = false;
        }
        if (c.needsWarps) {
            if (sendWarpGrids(c) != SendResult::Sent) continue;
            c.needsWarps = false;
        }
        if (c.needsState) {
            sendState(c);
            if (c.needsState) continue;
        }
        if (frameActive && c.ready && c.frameBegun != currentFrame && c.stateSeq <= frameSeq) sendFrameBegin(c);
    }
}

void Master::Impl::onHello(const std::string& peer, const Header& h, const uint8_t* data, size_t size) {
    const Hello hello = decodePayload<Hello>(data, size);
    if (h.version != kProtocolVersion || hello.protocolVersion != kProtocolVersion) {
        const unsigned theirs = h.version != kProtocolVersion ? h.version : hello.protocolVersion;
        Goodbye bye{"protocol version " + std::to_string(theirs) + " is not the master's " + std::to_string(kProtocolVersion)};
        if (!sendToPeer(link.router, peer, encodeMessage(header(MsgType::Goodbye), bye))) add(&MasterCounters::failedSends, 1);
        count(&MasterCounters::refused, "refused a client",
              "it speaks protocol version " + std::to_string(theirs) + " (master: " + std::to_string(kProtocolVersion) + ")");
        return;
    }
    if (auto old = clients.find(peer); old != clients.end()) {
        markDead(old->second, "said hello again");
        currentClient = nullptr;
        reap();
    }
    ClientState c;
    c.id = nextClientId++;
    c.peer = peer;
    c.lastSeen = nowSeconds();
    c.threads = std::max(1u, hello.threads);
    auto& ref = clients[peer] = c;
    const SendResult r = send(ref, welcomeFor(ref));
    if (r == SendResult::Gone) return;
    if (r == SendResult::Sent && withNodes()) send(ref, nodeList());
    if (r == SendResult::Full) {
        // All again, in this order: a state before its Welcome would be thrown away, and the
        // grids come before the state (a client is ready for frames only with both).
        ref.needsWelcome = ref.needsState = true;
        ref.needsWarps = !settings.warpGrids.empty();
        return;
    }
    const SendResult w = sendWarpGrids(ref);
    if (w == SendResult::Gone) return;
    if (w == SendResult::Full) {
        ref.needsWarps = ref.needsState = true;
        return;
    }
    sendState(ref);
}

void Master::Impl::onReady(ClientState& c, const uint8_t* data, size_t size) {
    const Ready r = decodePayload<Ready>(data, size);
    if (!c.stateInFlight) {
        // Nothing to prove: a replayed or repeated Ready. Answering it with the state again
        // would let one message cost a whole snapshot.
        replayed("a Ready with no state on its way to the client");
        return;
    }
    if (r.updateSeq != c.stateSeq || r.stateHash != c.stateHash) {
        // It does not hold the state we sent: never accept its tiles; send the state again.
        unexpected("a Ready for state " + std::to_string(r.updateSeq) + " that is not the state it was sent (" +
                   std::to_string(c.stateSeq) + ")");
        sendState(c);
        return;
    }
    c.stateInFlight = false;
    // In the scheduler from its first proof on: a peer that never proves a state is no
    // client the scheduler waits for (a stuck tile avoids its client only while another
    // client could render it).
    scheduler.addClient(c.id);
    if (!c.ready) {
        c.ready = true;
        {
            std::lock_guard lock(m);
            ++readyClients;
        }
        cv.notify_all();
    }
    if (frameActive && c.stateSeq <= frameSeq) sendFrameBegin(c);
}

void Master::Impl::checkTimeouts() {
    const double now = nowSeconds();
    const double timeout = settings.timeoutMs * 1e-3, beat = settings.heartbeatMs * 1e-3;
    for (auto& [peer, c] : clients) {
        if (c.deathReason) continue;
        if (now - c.lastSeen > timeout) markDead(c, "heartbeat timeout");
        else if (c.fullSince != 0 && now - c.fullSince > timeout) markDead(c, "its queue has been full for longer than the timeout");
        else if (now - c.lastSent > beat && now >= c.retryAt) send(c, Heartbeat{});
    }
}

}  // namespace rtwall
