// Puts numbered differential updates back in order on a client. Updates may arrive in any
// order (a resync's history after live ones, a reconnect), twice, or not at all; a frame may
// only start once every update up to its sequence number is there. A plain class, tested
// without a network.
#pragma once

#include "protocol.h"

#include <cstdint>
#include <map>
#include <vector>

namespace rtwall::cluster {

class UpdateSequencer {
public:
    // Bound on buffered updates: beyond it the client is hopelessly behind and resyncs.
    static constexpr size_t kMaxPending = 1 << 16;

    // The client now holds the state at `seq` (a snapshot): older buffered updates are dropped,
    // newer ones kept.
    void reset(uint32_t seq);

    // Buffers an update; ignores ones at or below the state, duplicates and ones whose base is
    // not below their seq. Returns false when the buffer overflowed (everything pending is
    // dropped; the caller must resync).
    bool add(Update update);

    enum class CatchUp {
        Ready,  // `out` holds the updates to apply, in order; the state is now `target`
        Gap,    // an update between the state and `target` is missing: resync
        Ahead,  // the state is already newer than `target`: this frame cannot be rendered here
    };
    CatchUp catchUp(uint32_t target, std::vector<Update>& out);

    uint32_t state() const { return state_; }
    size_t pending() const { return pending_.size(); }

private:
    uint32_t state_ = 0;
    std::map<uint32_t, Update> pending_;  // by baseSeq: the state each one applies to
};

}  // namespace rtwall::cluster
