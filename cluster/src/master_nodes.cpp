// Display nodes on the master's ROUTER (issue 19): control only, their tiles come from the
// clients. Hello and welcome, the tile routes of a frame, the swap barrier.
#include "master_impl.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace rtwall {

NodeList Master::Impl::nodeList() const {
    NodeList list;
    for (const auto& [peer, n] : display.nodes)
        if (!n.deathReason && n.answered) list.nodes.push_back({n.index, n.name, n.endpoint, n.publicKey});
    std::sort(list.nodes.begin(), list.nodes.end(), [](const NodeEndpoint& a, const NodeEndpoint& b) { return a.node < b.node; });
    return list;
}

void Master::Impl::sendNodeListToClients() {
    const NodeList list = nodeList();
    for (auto& [peer, c] : clients)
        if (!c.deathReason) send(c, list);
}

// The frame's tile masks (recomputed only when the tiling changes) and its NodeFrame.
void Master::Impl::beginNodeFrame(const RenderSettings& rs) {
    display.tilesDone = 0;
    auto key = std::make_tuple(rs.width, rs.height, rs.tileSize, frameViews);
    if (display.routesFrame == UINT32_MAX || key != display.routesKey) {
        // Without a routing (or when it cannot route this frame) every node gets every tile:
        // more traffic, the same screens.
        std::vector<uint64_t> masks(scheduler.tileCount(), ~uint64_t(0));
        if (settings.displayNodes.routes) {
            try {
                masks = settings.displayNodes.routes(rs.width, rs.height, rs.tileSize, frameViews);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "rtwall master: cannot route the tiles of frame %u to the display nodes (%s): every "
                                     "node gets every tile\n", currentFrame, e.what());
            }
        }
        if (masks.size() != scheduler.tileCount()) {
            // An invariant of the wall library's routing, not an input.
            std::fprintf(stderr, "rtwall master: internal error: %zu tile masks for a frame of %u tiles\n", masks.size(),
                         scheduler.tileCount());
            std::abort();
        }
        display.routes = std::move(masks);
        display.routesKey = std::move(key);
        display.routesFrame = currentFrame;
    }
    for (auto& [peer, n] : display.nodes) sendNodeFrame(n, rs);
    // The frame sizes the nodes may answer a picture with (onNodePreview).
    display.frameSizes.push_back({currentFrame, rs.width, rs.height});
    while (display.frameSizes.size() > DisplayNodes::kFrameSizes) display.frameSizes.pop_front();
}

void Master::Impl::sendNodeFrame(NodeState& n, const RenderSettings& rs) {
    if (n.deathReason) return;
    if (n.routesFrame != display.routesFrame) {
        if (!sendNode(n, TileRoutes{display.routesFrame, display.routes}, currentFrame)) return;
        n.routesFrame = display.routesFrame;
    }
    NodeFrame f{currentFrame, rs.width, rs.height, rs.tileSize, framePixels, frameViews, {}, frameStochastic, shownSeq,
                settings.depth, frameDenoise, frameRoomEyes};
    const std::vector<int>& eyes = settings.displayNodes.viewEyes;
    for (size_t v = 0; v < frameViews.size(); ++v) f.eyes.push_back(int8_t(v < eyes.size() && eyes[v] >= 0 && eyes[v] <= 1 ? eyes[v] : -1));
    if (sendNode(n, f, currentFrame)) n.frameSent = currentFrame;
}

void Master::Impl::onNodeHello(const std::string& peer, const Header& h, const uint8_t* data, size_t size) {
    const NodeHello hello = decodePayload<NodeHello>(data, size);
    auto refuse = [&](const std::string& why) {
        if (!sendToPeer(link.router, peer, encodeMessage(header(MsgType::Goodbye), Goodbye{why}))) add(&MasterCounters::failedSends, 1);
        count(&MasterCounters::refused, "refused a display node", why);
    };
    if (h.version != kProtocolVersion || hello.protocolVersion != kProtocolVersion) {
        const unsigned theirs = h.version != kProtocolVersion ? h.version : hello.protocolVersion;
        refuse("protocol version " + std::to_string(theirs) + " is not the master's " + std::to_string(kProtocolVersion));
        return;
    }
    const std::vector<std::string>& names = settings.displayNodes.names;
    const auto at = std::find(names.begin(), names.end(), hello.name);
    if (at == names.end()) {
        refuse(names.empty() ? "this wall has no display nodes (node '" + hello.name + "')"
                             : "the wall has no display node '" + hello.name + "'");
        return;
    }
    // Behind CURVE the tiles must be too: a node reached over an authenticated link whose
    // tile socket has no key would take pixels in the clear.
    if (link.zap && hello.publicKey.empty()) {
        refuse("display node '" + hello.name + "' has no tile key, and this master uses CURVE keys");
        return;
    }
    // A node of that name on another connection (a restarted node) is replaced.
    for (auto& [otherPeer, other] : display.nodes)
        if (other.name == hello.name && !other.deathReason) other.deathReason = "another node of its name said hello";
    reapNodes();
    NodeState n;
    n.index = uint32_t(at - names.begin());
    n.name = hello.name;
    n.endpoint = hello.endpoint;
    n.publicKey = hello.publicKey;
    n.peer = peer;
    n.lastSeen = nowSeconds();
    NodeState& ref = display.nodes[peer] = n;
    if (!sendNode(ref, NodeWelcome{ref.index, uint32_t(settings.heartbeatMs), uint32_t(settings.timeoutMs),
                                   settings.displayNodes.wallText, link.allowedKeys, settings.displayNodes.reproject})) {
        reapNodes();
        return;
    }
    std::fprintf(stderr, "rtwall master: display node '%s' (%u) joins, tiles to %s\n", ref.name.c_str(), ref.index,
                 ref.endpoint.c_str());
    display.barrier.join(ref.index, currentFrame + 1);  // the frame begun now may never reach it whole
    publishNodes();
    if (frameActive) sendNodeFrame(ref, frameState.settings);
}

void Master::Impl::releaseSwap(std::optional<uint32_t> frame) {
    if (!frame) return;
    {
        std::lock_guard lock(m);
        swapReleased = std::max(swapReleased, *frame);
    }
    cv.notify_all();
    // Every node of the wall that does not take part: stalled, gone, or never came.
    NodeSwap swap{*frame, {}};
    const std::vector<NodeId> joined = display.barrier.nodes(), stalled = display.barrier.leftOut();
    const std::vector<std::string>& names = settings.displayNodes.names;
    for (NodeId i = 0; i < names.size(); ++i)
        if (std::find(joined.begin(), joined.end(), i) == joined.end() ||
            std::find(stalled.begin(), stalled.end(), i) != stalled.end())
            swap.leftOut.push_back(names[i]);
    for (auto& [peer, n] : display.nodes)
        if (!n.deathReason) sendNode(n, swap, *frame);
}

void Master::Impl::handleNode(NodeState& n, const Header& h, const uint8_t* payload, size_t payloadSize) {
    n.lastSeen = nowSeconds();
    if (!n.answered) {
        // Its first message after the welcome (it sends a heartbeat at once): the clients learn of it now.
        n.answered = true;
        sendNodeListToClients();
    }
    switch (h.type) {
    case MsgType::NodeHave: {
        const NodeHave have = decodePayload<NodeHave>(payload, payloadSize);
        if (have.frame > currentFrame || have.frame <= display.barrier.lastReleased()) {
            stale("display node '" + n.name + "' holds frame " + std::to_string(have.frame) + ", which is not waiting for a swap");
            return;
        }
        releaseSwap(display.barrier.have(n.index, have.frame, nowSeconds()));
        break;
    }
    case MsgType::NodeSwapped: display.barrier.swapped(n.index, decodePayload<NodeSwapped>(payload, payloadSize).frame, nowSeconds()); break;
    case MsgType::NodeShown: {
        const NodeShown shown = decodePayload<NodeShown>(payload, payloadSize);
        if (!settings.displayNodes.reproject || shown.refresh == 0 || shown.refresh > display.refreshes) {
            unexpected("display node '" + n.name + "' showed refresh " + std::to_string(shown.refresh) + ", which was never sent");
            return;
        }
        if (display.refreshes - shown.refresh >= DisplayNodes::kPoseRing) return;  // too old to time
        const double asked = display.poseAskedAt[shown.refresh % DisplayNodes::kPoseRing];
        std::lock_guard lock(poseMutex);
        nodeRefreshes.push_back({shown.refresh, n.name, asked, (nowSeconds() - asked) * 1e3});
        while (nodeRefreshes.size() > 4096) nodeRefreshes.pop_front();
        break;
    }
    case MsgType::NodePreview: {
        NodePreview part;
        try {
            part = decodePayload<NodePreview>(payload, payloadSize);
        } catch (const DecodeError&) {
            pictureNodeGone(n.index);  // a malformed part: the pictures asked of it go without it
            throw;
        }
        onNodePreview(n, part);
        break;
    }
    case MsgType::Heartbeat: decodePayload<Heartbeat>(payload, payloadSize); break;
    case MsgType::Goodbye: {
        const Goodbye bye = decodePayload<Goodbye>(payload, payloadSize);
        std::fprintf(stderr, "rtwall master: display node '%s' says goodbye: %s\n", n.name.c_str(), bye.reason.c_str());
        if (!n.deathReason) n.deathReason = "it said goodbye";
        break;
    }
    default: unexpected("a message of type " + std::to_string(int(h.type)) + " from display node '" + n.name + "'"); break;
    }
}

void Master::Impl::reapNodes() {
    bool any = false;
    for (auto it = display.nodes.begin(); it != display.nodes.end();) {
        if (!it->second.deathReason) {
            ++it;
            continue;
        }
        std::fprintf(stderr, "rtwall master: display node '%s' leaves: %s\n", it->second.name.c_str(), it->second.deathReason);
        // Leaving the barrier may complete a frame the others all hold.
        display.barrier.leave(it->second.index);
        pictureNodeGone(it->second.index);
        it = display.nodes.erase(it);
        any = true;
    }
    if (any) {
        publishNodes();
        sendNodeListToClients();
        releaseSwap(display.barrier.poll(nowSeconds()));
    }
}

// For the application's thread (displayNodesPresent, waitForDisplayNodes).
void Master::Impl::publishNodes() {
    std::vector<std::string> present;
    for (const std::string& name : settings.displayNodes.names)
        for (const auto& [peer, n] : display.nodes)
            if (n.name == name && !n.deathReason) {
                present.push_back(name);
                break;
            }
    {
        std::lock_guard lock(m);
        presentNodes = std::move(present);
    }
    cv.notify_all();
}

// The newest pose the application asked for (presentPose) to every node, for the newest frame
// the barrier released: one message, so every node shows one pose in this refresh.
void Master::Impl::sendPendingPose() {
    std::optional<PendingPose> pose;
    {
        std::lock_guard lock(poseMutex);
        pose.swap(pendingPose);
    }
    if (!pose || display.barrier.lastReleased() == 0) return;
    NodePose msg{++display.refreshes, display.barrier.lastReleased(), pose->debug, std::move(pose->cameras), pose->roomEyes};
    display.poseAskedAt[msg.refresh % DisplayNodes::kPoseRing] = pose->askedAt;
    for (auto& [peer, n] : display.nodes)
        if (!n.deathReason && n.answered) sendNode(n, msg, msg.frame);
}

void Master::Impl::nodeHousekeeping() {
    const double now = nowSeconds();
    const double timeout = settings.timeoutMs * 1e-3, beat = settings.heartbeatMs * 1e-3;
    for (auto& [peer, n] : display.nodes) {
        if (n.deathReason) continue;
        if (now - n.lastSeen > timeout) n.deathReason = "heartbeat timeout";
        else if (now - n.lastSent > beat) sendNode(n, Heartbeat{});
    }
    reapNodes();
    releaseSwap(display.barrier.poll(now));
}

}  // namespace rtwall
