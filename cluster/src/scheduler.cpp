#include "scheduler.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rtwall::cluster {

TileScheduler::TileScheduler(SchedulerOptions options) : options_(options), rng_(options.seed) {}

void TileScheduler::addClient(ClientId client) {
    // kNobody marks unowned tiles; a client with that id would silently own them all.
    if (client == kNobody) throw std::invalid_argument("tile scheduler: client id " + std::to_string(client) + " is reserved");
    if (hasClient(client)) return;
    clients_.push_back(client);
    queues_[client];
}

bool TileScheduler::hasClient(ClientId client) const { return queues_.count(client) != 0; }

size_t TileScheduler::removeClient(ClientId client) {
    auto q = queues_.find(client);
    if (q == queues_.end()) return 0;

    size_t returned = 0;
    for (uint32_t t : q->second) {
        shared_.insert(t);
        ++returned;
    }
    queues_.erase(q);
    clients_.erase(std::find(clients_.begin(), clients_.end(), client));

    std::vector<uint32_t> held;
    for (auto it = outstanding_.begin(); it != outstanding_.end();) {
        if (it->second.client == client) {
            held.push_back(it->first);
            it = outstanding_.erase(it);
        } else {
            ++it;
        }
    }
    for (uint32_t t : held) {
        // A tile re-issued to someone else is still being rendered there: queueing it again
        // would hand it to a third client without any sign of a straggler.
        if (!done_[t] && outstanding_.count(t) == 0) {
            shared_.insert(t);
            ++returned;
        }
    }
    for (auto it = avoid_.begin(); it != avoid_.end();) it = it->second == client ? avoid_.erase(it) : std::next(it);
    // Its late results must not count: forget which tiles it was handed.
    for (auto it = handed_.begin(); it != handed_.end();) {
        it = it->second == client ? handed_.erase(it) : std::next(it);
    }
    // Should the id come back it is a new process with a cold cache: no affinity for it next
    // frame, and no affinity hits credited to it this frame.
    std::replace(owner_.begin(), owner_.end(), client, kNobody);
    std::replace(lastOwner_.begin(), lastOwner_.end(), client, kNobody);
    return returned;
}

void TileScheduler::requeueIfOrphaned(uint32_t tile) {
    if (!done_[tile] && outstanding_.count(tile) == 0) shared_.insert(tile);
}

size_t TileScheduler::release(ClientId client) {
    std::vector<uint32_t> held;
    for (auto it = outstanding_.begin(); it != outstanding_.end();) {
        if (it->second.client == client) {
            held.push_back(it->first);
            it = outstanding_.erase(it);
        } else {
            ++it;
        }
    }
    // handed_ keeps the pairs: a result that was only late after all is still accepted.
    for (uint32_t t : held) requeueIfOrphaned(t);
    stats_.released += held.size();
    return held.size();
}

bool TileScheduler::release(ClientId client, uint32_t frame, uint32_t tile, bool avoid) {
    if (frame != frame_ || tile >= tileCount_) return false;
    auto [first, last] = outstanding_.equal_range(tile);
    for (auto it = first; it != last; ++it) {
        if (it->second.client != client) continue;
        outstanding_.erase(it);
        ++stats_.released;
        if (avoid) avoid_[tile] = client;
        requeueIfOrphaned(tile);
        return true;
    }
    return false;
}

size_t TileScheduler::outstanding(ClientId client) const {
    size_t n = 0;
    for (const auto& [tile, o] : outstanding_) n += o.client == client;
    return n;
}

bool TileScheduler::reopen(uint32_t frame, uint32_t tile) {
    if (frame != frame_ || tile >= tileCount_ || !done_[tile]) return false;
    done_[tile] = 0;
    --doneCount_;
    if (stats_.completed > 0) --stats_.completed;
    if (owner_[tile] != kNobody) {
        auto by = stats_.completedBy.find(owner_[tile]);
        if (by != stats_.completedBy.end() && by->second > 0) --by->second;
    }
    owner_[tile] = kNobody;
    shared_.insert(tile);
    return true;
}

void TileScheduler::beginFrame(uint32_t frame, uint32_t tileCount) {
    // Last frame's owners only mean something for the same tiling. They are kept with affinity
    // off too, so affinityHits shows the hit rate that affinity would have improved on.
    if (tileCount == tileCount_)
        lastOwner_ = owner_;
    else
        lastOwner_.assign(tileCount, kNobody);

    frame_ = frame;
    tileCount_ = tileCount;
    owner_.assign(tileCount, kNobody);
    done_.assign(tileCount, 0);
    doneCount_ = 0;
    outstanding_.clear();
    handed_.clear();
    latencies_.clear();
    stats_ = {};
    shared_.clear();
    avoid_.clear();
    for (auto& [client, queue] : queues_) queue.clear();

    for (uint32_t t = 0; t < tileCount; ++t) {
        const ClientId last = lastOwner_[t];
        if (options_.affinity && last != kNobody && hasClient(last))
            queues_[last].push_back(t);
        else
            shared_.insert(shared_.end(), t);
    }
}

void TileScheduler::handOut(ClientId client, uint32_t tile, double now) {
    outstanding_.emplace(tile, Outstanding{client, now});
    handed_.emplace(tile, client);
    ++stats_.assigned;
}

void TileScheduler::stealInto(ClientId thief, uint32_t need, double now, std::vector<uint32_t>& out) {
    std::vector<ClientId> victims;
    while (need > 0) {
        // Only peers with tiles left are candidates: picking an empty one would waste the
        // request, and the choice stays reproducible because clients_ has a fixed order.
        victims.clear();
        for (ClientId c : clients_)
            if (c != thief && !queues_[c].empty()) victims.push_back(c);
        if (victims.empty()) break;
        std::uniform_int_distribution<size_t> pick(0, victims.size() - 1);
        std::deque<uint32_t>& queue = queues_[victims[pick(rng_)]];

        // From the back: the victim keeps the tiles it is about to ask for, and the thief gets
        // a run of neighbouring tiles, handed out in image order.
        const uint32_t take = std::min<uint32_t>(need, uint32_t(queue.size()));
        const size_t first = out.size();
        for (uint32_t i = 0; i < take; ++i) {
            out.push_back(queue.back());
            queue.pop_back();
        }
        std::reverse(out.begin() + std::ptrdiff_t(first), out.end());
        for (size_t i = first; i < out.size(); ++i) handOut(thief, out[i], now);
        stats_.stolen += take;
        stats_.stolenBy[thief] += take;
        need -= take;
    }
}

double TileScheduler::medianLatency() const {
    std::vector<double> sorted = latencies_;
    auto mid = sorted.begin() + std::ptrdiff_t(sorted.size() / 2);
    std::nth_element(sorted.begin(), mid, sorted.end());
    return *mid;
}

void TileScheduler::reissueInto(ClientId client, uint32_t need, double now, std::vector<uint32_t>& out) {
    // Without a single result there is no notion of "slow" yet; the first tiles of a frame on
    // a cold client could otherwise be re-issued to everybody.
    if (latencies_.empty()) return;
    const double threshold = std::max(options_.minStragglerSeconds, options_.stragglerFactor * medianLatency());

    // Age counts from a tile's latest hand-out, so a tile just re-issued gets a fair chance
    // before it is re-issued again.
    std::vector<std::pair<double, uint32_t>> candidates;  // (latest hand-out, tile)
    for (auto it = outstanding_.begin(); it != outstanding_.end();) {
        const uint32_t tile = it->first;
        double latest = it->second.since;
        bool mine = false;
        for (; it != outstanding_.end() && it->first == tile; ++it) {
            latest = std::max(latest, it->second.since);
            mine = mine || it->second.client == client;
        }
        if (!mine && !done_[tile] && now - latest > threshold) candidates.emplace_back(latest, tile);
    }
    std::sort(candidates.begin(), candidates.end());  // oldest first, then image order
    for (size_t i = 0; i < candidates.size() && need > 0; ++i, --need) {
        out.push_back(candidates[i].second);
        handOut(client, candidates[i].second, now);
        ++stats_.reissued;
    }
}

std::vector<uint32_t> TileScheduler::request(ClientId client, uint32_t count, double now) {
    std::vector<uint32_t> out;
    auto own = queues_.find(client);
    if (own == queues_.end() || count == 0) return out;

    std::deque<uint32_t>& queue = own->second;
    while (out.size() < count && !queue.empty()) {
        out.push_back(queue.front());
        queue.pop_front();
        handOut(client, out.back(), now);
    }
    for (auto it = shared_.begin(); out.size() < count && it != shared_.end();) {
        const auto avoided = avoid_.find(*it);
        if (avoided != avoid_.end()) {
            // Stuck on this client: someone else's, unless nobody else is left.
            if (avoided->second == client && clients_.size() > 1) {
                ++it;
                continue;
            }
            avoid_.erase(avoided);
        }
        out.push_back(*it);
        it = shared_.erase(it);
        handOut(client, out.back(), now);
    }
    if (out.size() < count) stealInto(client, count - uint32_t(out.size()), now, out);
    // Every queue is empty now (stealing leaves none behind while it still needs tiles), but for
    // tiles this client is to avoid.
    if (out.size() < count) reissueInto(client, count - uint32_t(out.size()), now, out);
    return out;
}

TileScheduler::Result TileScheduler::complete(ClientId client, uint32_t frame, uint32_t tile, double now) {
    if (frame != frame_) {
        ++stats_.stale;
        return Result::Stale;
    }
    if (tile >= tileCount_ || handed_.count({tile, client}) == 0) {
        ++stats_.unexpected;
        return Result::Unexpected;
    }
    if (done_[tile]) {
        ++stats_.duplicates;
        return Result::Duplicate;
    }

    // handed_ without done_ means this hand-out is still outstanding.
    auto [first, last] = outstanding_.equal_range(tile);
    for (auto it = first; it != last; ++it) {
        if (it->second.client == client) {
            latencies_.push_back(std::max(0.0, now - it->second.since));
            break;
        }
    }
    outstanding_.erase(first, last);
    // A released hand-out's result may beat the tile's next hand-out: it leaves the queue.
    shared_.erase(tile);
    avoid_.erase(tile);

    done_[tile] = 1;
    ++doneCount_;
    owner_[tile] = client;
    ++stats_.completed;
    ++stats_.completedBy[client];
    if (lastOwner_[tile] == client) ++stats_.affinityHits;
    return Result::Accepted;
}

bool TileScheduler::frameComplete() const { return doneCount_ == tileCount_; }

uint32_t TileScheduler::remaining() const { return tileCount_ - doneCount_; }

}  // namespace rtwall::cluster
