// The swap barrier of a wall on several display nodes (issue 19): every node presents frame N
// only when every node holds all of frame N's tiles that its screens show. A node that died or
// stalls must not stop the wall: once the first node holds a frame, the others get
// `stallSeconds` to follow; a node that has not by then is left out (its screens stay dark, the
// overlay names it) until it holds a frame again, when it rejoins. A plain class like the
// scheduler: no sockets, no threads, no clock of its own (the caller passes the time).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace rtwall::cluster {

using NodeId = uint32_t;

struct SwapBarrierStats {
    uint64_t released = 0;      // frames every taking-part node held, released to swap
    uint64_t superseded = 0;    // frames dropped because a newer one was released first
    uint64_t leftOut = 0;       // times a node was left out of a frame (stalled)
    uint64_t rejoined = 0;      // times a left-out node took part again
    uint64_t passedOver = 0;    // times a frame was released without a node that had gone on to a newer one
    double lastSkew = 0;        // seconds between the first and the last node's swap of the newest swapped frame
    double maxSkew = 0;
};

class SwapBarrier {
public:
    explicit SwapBarrier(double stallSeconds = 0.5) : stallSeconds_(stallSeconds) {}

    // A node connected (again): it takes part in frames from `firstFrame` on (the first frame
    // begun after it joined: the tiles of one begun before went out before the clients knew
    // where it is, so it may never hold that one, and no frame waits for it).
    void join(NodeId node, uint32_t firstFrame = 0);
    // It said goodbye or timed out: frames no longer wait for it.
    void leave(NodeId node);

    // Node `node` holds every tile of `frame` its screens show. Returns the frame to release
    // (the newest frame that every taking-part node now holds), if this completes one. Frames
    // are released in increasing order; a frame older than one released is stale and ignored.
    // A node reports its frames in increasing order (it holds two at most and shows them in
    // turn), so a report of `frame` also says it will never hold an older one: older frames
    // no longer wait for it. (Without that, node A holding frame 2 for its swap and node B,
    // which lost 2 to frame 4 overtaking it, holding 3 for its swap waited for each other
    // until the stall time.)
    std::optional<uint32_t> have(NodeId node, uint32_t frame, double now);
    // Leaves out the nodes that let a frame wait longer than stallSeconds after the first node
    // held it; returns the frame that releases, if any. Call it regularly.
    std::optional<uint32_t> poll(double now);

    // A node reports that it swapped `frame` (at `now`, the caller's clock when the report came):
    // the spread of these times per frame is the swap skew.
    void swapped(NodeId node, uint32_t frame, double now);

    // Nodes that are connected but left out (stalled), and all connected ones.
    std::vector<NodeId> leftOut() const;
    std::vector<NodeId> nodes() const {
        std::vector<NodeId> out;
        for (const auto& [node, first] : joined_) out.push_back(node);
        return out;
    }
    uint32_t lastReleased() const { return lastReleased_; }
    const SwapBarrierStats& stats() const { return stats_; }

private:
    struct Pending {
        std::set<NodeId> have;
        double firstSeconds = 0;  // when the first node held it
    };
    std::optional<uint32_t> releaseReady();
    // Frame `frame` waits for node `node`: it takes part and has not gone on to a newer one.
    bool waitsFor(NodeId node, uint32_t frame) const {
        const auto it = newest_.find(node);
        return takingPart(node, frame) && (it == newest_.end() || it->second <= frame);
    }
    bool takingPart(NodeId node, uint32_t frame) const {
        const auto it = joined_.find(node);
        return it != joined_.end() && frame >= it->second && !out_.count(node);
    }

    double stallSeconds_;
    std::map<NodeId, uint32_t> joined_;  // each node's first frame
    std::map<NodeId, uint32_t> newest_;  // the newest frame each node reported
    std::set<NodeId> out_;  // joined, but left out for stalling
    std::map<uint32_t, Pending> pending_;  // frames some node holds, not released yet
    uint32_t lastReleased_ = 0;
    bool anyReleased_ = false;
    struct Swaps {
        double first = 0, last = 0;
        size_t count = 0;
    };
    std::map<uint32_t, Swaps> swaps_;  // per released frame, the swap reports so far
    SwapBarrierStats stats_;
};

}  // namespace rtwall::cluster
