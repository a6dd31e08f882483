#include "update_sequencer.h"

namespace rtwall::cluster {

void UpdateSequencer::reset(uint32_t seq) {
    state_ = seq;
    // Drop what the snapshot already holds, and merged updates that straddle it (they cannot
    // be applied in part; the gap they leave asks for a resync if a frame needs them).
    for (auto it = pending_.begin(); it != pending_.end();)
        it = it->second.seq <= seq || it->first < seq ? pending_.erase(it) : std::next(it);
}

bool UpdateSequencer::add(Update update) {
    if (update.baseSeq >= update.seq || update.seq <= state_ || update.baseSeq < state_ ||
        pending_.count(update.baseSeq))
        return true;
    if (pending_.size() >= kMaxPending) {
        pending_.clear();
        return false;
    }
    const uint32_t base = update.baseSeq;
    pending_.emplace(base, std::move(update));
    return true;
}

UpdateSequencer::CatchUp UpdateSequencer::catchUp(uint32_t target, std::vector<Update>& out) {
    out.clear();
    if (target < state_) return CatchUp::Ahead;
    // Follow the chain of updates from the state to the target without changing anything.
    std::vector<uint32_t> chain;
    for (uint32_t s = state_; s < target;) {
        auto it = pending_.find(s);
        if (it == pending_.end() || it->second.seq > target) return CatchUp::Gap;
        chain.push_back(s);
        s = it->second.seq;
    }
    for (uint32_t base : chain) {
        auto it = pending_.find(base);
        out.push_back(std::move(it->second));
        pending_.erase(it);
    }
    state_ = target;
    return CatchUp::Ready;
}

}  // namespace rtwall::cluster
