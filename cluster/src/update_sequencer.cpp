#include "update_sequencer.h"

namespace rtwall::cluster {

void UpdateSequencer::reset(uint32_t seq) {
    state_ = seq;
    pending_.erase(pending_.begin(), pending_.upper_bound(seq));
}

bool UpdateSequencer::add(Update update) {
    if (update.seq <= state_ || pending_.count(update.seq)) return true;
    if (pending_.size() >= kMaxPending) {
        pending_.clear();
        return false;
    }
    const uint32_t seq = update.seq;
    pending_.emplace(seq, std::move(update));
    return true;
}

UpdateSequencer::CatchUp UpdateSequencer::catchUp(uint32_t target, std::vector<Update>& out) {
    out.clear();
    if (target < state_) return CatchUp::Ahead;
    for (uint32_t next = state_ + 1; next <= target && next != 0; ++next)
        if (!pending_.count(next)) return CatchUp::Gap;
    for (uint32_t next = state_ + 1; next <= target && next != 0; ++next) {
        auto it = pending_.find(next);
        out.push_back(std::move(it->second));
        pending_.erase(it);
    }
    state_ = target;
    return CatchUp::Ready;
}

}  // namespace rtwall::cluster
