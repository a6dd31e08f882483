// Demand-driven tile scheduling with spatio-temporal affinity, stealing and straggler
// re-issue. A plain class: no sockets, no threads, no clock of its own (the caller passes the
// time), so every policy is tested exhaustively without a network.
//
// - Clients ask for tiles (request); nothing is pre-assigned.
// - Affinity: at beginFrame each client's queue holds the tiles it rendered last frame, in
//   image order. A client first drains its own queue, then the shared queue (tiles nobody
//   owns: the first frame, new tiles, tiles of departed clients), then steals from the back of
//   a randomly chosen peer's queue. With affinity off every tile starts in the shared queue.
// - Stragglers: when no queued tile is left, a tile outstanding for more than stragglerFactor
//   times the frame's median assignment-to-result time (and at least minStragglerSeconds) is
//   handed to the asking client as well; the first result wins, later ones are duplicates.
// - A departed client's outstanding and queued tiles go back to the shared queue.
// - Lost hand-outs: a client that holds none of its hand-outs any more (its idle report says so,
//   it asked for a resync, the assignment could not be sent) or whose render thread is stuck on
//   a tile has them released: they go back to the shared queue, so the next client to ask gets
//   them, the same one included. That is what recovers a lost result when only one client is
//   left; a stuck tile avoids its client while another is present. A released hand-out's late
//   result still counts (the first result wins).
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace rtwall::cluster {

using ClientId = uint32_t;

struct SchedulerOptions {
    bool affinity = true;
    double stragglerFactor = 4.0;
    double minStragglerSeconds = 0.05;
    uint64_t seed = 1;  // for the choice of steal victim; fixed for reproducible tests
};

struct SchedulerStats {
    uint64_t assigned = 0;       // tile hand-outs, re-issues included
    uint64_t completed = 0;      // first results
    uint64_t stolen = 0;         // hand-outs taken from another client's queue
    uint64_t affinityHits = 0;   // first results from the client that rendered the tile last frame
    uint64_t reissued = 0;       // straggler hand-outs
    uint64_t duplicates = 0;     // results for a tile already done
    uint64_t stale = 0;          // results for another frame
    uint64_t unexpected = 0;     // results for a tile never handed to that client
    uint64_t released = 0;       // hand-outs released (lost or stuck): their tiles were queued again
    std::map<ClientId, uint64_t> completedBy;
    std::map<ClientId, uint64_t> stolenBy;
};

class TileScheduler {
public:
    explicit TileScheduler(SchedulerOptions options = {});

    // Adding a present client again does nothing. A client id must not be kNobody.
    void addClient(ClientId client);
    // Puts the client's outstanding and queued tiles back in the shared queue; returns how many.
    size_t removeClient(ClientId client);
    bool hasClient(ClientId client) const;

    // Starts a frame of tileCount tiles (ids 0..tileCount-1). Tiles left over from an
    // unfinished frame are forgotten; their results will be stale.
    void beginFrame(uint32_t frame, uint32_t tileCount);

    // Up to `count` tiles for this client, now. May be empty (nothing left to give). A client
    // that was never added, or was removed, gets nothing: a late request from a client declared
    // dead must not bring it back without the master's say-so (addClient).
    std::vector<uint32_t> request(ClientId client, uint32_t count, double now);

    enum class Result { Accepted, Duplicate, Stale, Unexpected };
    // A tile's pixels arrived. Only Accepted results may be written to the frame.
    Result complete(ClientId client, uint32_t frame, uint32_t tile, double now);

    // Releases every outstanding hand-out of `client` in this frame: it holds none of them (its
    // results were lost on the way, or it dropped its work). Their tiles go back to the shared
    // queue unless another client is rendering them too. Returns how many hand-outs were released.
    size_t release(ClientId client);
    // Releases one hand-out: `tile` of `frame` given to `client` (a stuck render thread, an
    // assignment that could not be sent). With `avoid` the tile is not handed to that client
    // again while another client is present. False if there was no such outstanding hand-out.
    bool release(ClientId client, uint32_t frame, uint32_t tile, bool avoid);
    // Hand-outs to `client` still awaiting a result.
    size_t outstanding(ClientId client) const;

    // An accepted result turned out unusable (its pixels did not decode): the tile is open
    // again and goes to the shared queue. False if it was not done or belongs to another frame.
    bool reopen(uint32_t frame, uint32_t tile);

    bool frameComplete() const;
    uint32_t frame() const { return frame_; }
    uint32_t tileCount() const { return tileCount_; }
    uint32_t remaining() const;  // tiles without an accepted result
    const SchedulerStats& stats() const { return stats_; }  // of the current frame
    const std::vector<double>& latencies() const { return latencies_; }  // hand-out to result, this frame
    const std::vector<ClientId>& owners() const { return owner_; }       // who rendered each tile, this frame

    static constexpr ClientId kNobody = UINT32_MAX;

private:
    struct Outstanding {
        ClientId client;
        double since;
    };
    SchedulerOptions options_;
    std::mt19937_64 rng_;
    uint32_t frame_ = 0;
    uint32_t tileCount_ = 0;
    std::vector<ClientId> clients_;
    // Invariant: a tile not yet done is either in exactly one queue (own or shared) and not
    // outstanding, or outstanding with one client or more (re-issues) and in no queue. A done
    // tile is in no queue (a released hand-out whose late result wins leaves the shared queue).
    std::map<ClientId, std::deque<uint32_t>> queues_;  // affinity queues, image order, next tile at front
    std::set<uint32_t> shared_;                         // image order by construction
    std::map<uint32_t, ClientId> avoid_;                // tiles in shared_ not to hand back to a client stuck on them
    std::vector<uint8_t> done_;
    uint32_t doneCount_ = 0;
    std::vector<ClientId> lastOwner_;     // who rendered each tile last frame (kNobody if none)
    std::vector<ClientId> owner_;         // who rendered each tile this frame
    std::multimap<uint32_t, Outstanding> outstanding_;  // tile -> hand-outs awaiting a result
    // (tile, client) of every hand-out this frame that still counts: tells a losing re-issue
    // (Duplicate) from a result nobody asked for (Unexpected) after the tile's hand-outs are gone.
    std::set<std::pair<uint32_t, ClientId>> handed_;
    std::vector<double> latencies_;       // assignment-to-result times this frame
    SchedulerStats stats_;

    void handOut(ClientId client, uint32_t tile, double now);
    void requeueIfOrphaned(uint32_t tile);
    void stealInto(ClientId thief, uint32_t need, double now, std::vector<uint32_t>& out);
    void reissueInto(ClientId client, uint32_t need, double now, std::vector<uint32_t>& out);
    double medianLatency() const;
};

}  // namespace rtwall::cluster
