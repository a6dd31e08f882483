#include "swap_barrier.h"

#include <algorithm>

namespace rtwall::cluster {

void SwapBarrier::join(NodeId node, uint32_t firstFrame) {
    joined_[node] = firstFrame;
    newest_.erase(node);
    out_.erase(node);
}

void SwapBarrier::leave(NodeId node) {
    joined_.erase(node);
    newest_.erase(node);
    out_.erase(node);
}

std::optional<uint32_t> SwapBarrier::have(NodeId node, uint32_t frame, double now) {
    if (!joined_.count(node) || (anyReleased_ && frame <= lastReleased_)) return releaseReady();
    if (out_.erase(node)) ++stats_.rejoined;  // it holds a current frame again: it takes part from here on
    uint32_t& newest = newest_[node];
    newest = std::max(newest, frame);
    Pending& p = pending_[frame];
    if (p.have.empty()) p.firstSeconds = now;
    p.have.insert(node);
    return releaseReady();
}

std::optional<uint32_t> SwapBarrier::poll(double now) {
    for (auto& [frame, p] : pending_) {
        if (now - p.firstSeconds <= stallSeconds_) continue;
        // Everyone still missing from a frame that waited too long is left out.
        for (const auto& [n, first] : joined_)
            if (waitsFor(n, frame) && !p.have.count(n)) {
                out_.insert(n);
                ++stats_.leftOut;
            }
    }
    return releaseReady();
}

std::optional<uint32_t> SwapBarrier::releaseReady() {
    std::optional<uint32_t> ready;
    for (const auto& [frame, p] : pending_) {
        bool all = true;
        for (const auto& [n, first] : joined_)
            if (waitsFor(n, frame) && !p.have.count(n)) {
                all = false;
                break;
            }
        // A frame nobody taking part holds (all left) is not released: it waits for a node.
        bool anyone = false;
        for (NodeId n : p.have) anyone |= takingPart(n, frame);
        if (all && anyone) ready = frame;
    }
    if (!ready) return std::nullopt;
    const Pending& released = pending_.at(*ready);
    for (const auto& [n, first] : joined_) stats_.passedOver += takingPart(n, *ready) && !released.have.count(n);
    for (auto it = pending_.begin(); it != pending_.end() && it->first <= *ready;) {
        if (it->first < *ready) ++stats_.superseded;
        it = pending_.erase(it);
    }
    lastReleased_ = *ready;
    anyReleased_ = true;
    ++stats_.released;
    return ready;
}

void SwapBarrier::swapped(NodeId node, uint32_t frame, double now) {
    if (!joined_.count(node) || !anyReleased_ || frame > lastReleased_) return;
    Swaps& s = swaps_[frame];
    if (s.count == 0) s.first = s.last = now;
    s.first = std::min(s.first, now);
    s.last = std::max(s.last, now);
    ++s.count;
    if (s.count >= 2) {
        stats_.lastSkew = s.last - s.first;
        stats_.maxSkew = std::max(stats_.maxSkew, stats_.lastSkew);
    }
    // Keep a few frames' reports: a late report of an old frame still counts, memory stays bounded.
    while (swaps_.size() > 8) swaps_.erase(swaps_.begin());
}

std::vector<NodeId> SwapBarrier::leftOut() const { return {out_.begin(), out_.end()}; }

}  // namespace rtwall::cluster
