// The cluster simulation: the master's TileScheduler, driven exactly as the master drives it,
// against simulated render clients and links. Event-driven on a simulated clock, so the same
// profile and configuration give the same figures on any machine, for 1 or 256 clients.
//
// What is modelled, and how (the real code it stands for in brackets):
// - Frames follow each other: beginFrame, FrameBegin to every client (Impl::beginFrame).
// - A client that receives FrameBegin drops its queued work and asks for `prefetch` tiles
//   (Client::onFrameBegin); every result is also a request for one more tile
//   (Impl::onTileResult: credits += 1, serve). Credits are capped at 64, as in the master.
// - The master's network thread handles one message at a time, masterSecondsPerMessage each;
//   every housekeepingSeconds it re-serves every client (stragglers, returned tiles).
// - A client renders with threadsPerClient threads; a tile costs its recorded render time plus
//   its encode time, divided by clientSpeed.
// - A result crosses the client's link and then the master's shared uplink. Both are FIFO; a
//   message pipelines through them (packets, not store-and-forward of whole messages): it
//   occupies the master's link for its size over that rate, starting no earlier than its first
//   bytes arrive and ending no earlier than its last. Messages to the clients (FrameBegin,
//   assignments) are small: they cost latency only. Order per direction is kept, as with TCP.
// - Accepted tiles are decoded by decodeThreads threads; a frame ends when its last tile is
//   decoded (Impl::finishFrameIfDone).
// - With hostCores > 0 (local clients on the master's PC) every thread's CPU work, renders,
//   the network thread's messages and decodes, runs on one pool of that many cores under
//   processor sharing: n running threads progress at min(1, cores / (n + b)) each, b being
//   other jobs' runnable threads on a shared PC (hostBackgroundThreads). This is what
//   makes 4 local clients on 2 cores no faster than 2, and slows the master's replies when the
//   clients saturate the cores.
// - Host costs besides rendering (SimConfig::clientSecondsPerResult and the rest, measured by
//   rtwall bench cluster per thread): a client's network work per result delays its send; the
//   master's receive per result (one I/O thread, FIFO) comes before its network thread; the
//   master's per-frame work follows the last decode. On shared cores all are CPU jobs there.
// - Display nodes (SimConfig::displayNodes > 0; issue 19): a finished tile goes once per node of
//   its mask over the client's link (Client::sendToNodes), each copy through the node's own link
//   to its decode threads (runDisplayNode), then a TileDone ack to the master (header bytes over
//   both links; Impl::onTileDone completes it in the scheduler, nothing is decoded). The frame
//   is swapped a round trip after the last ack is in and the slowest node has decoded its tiles
//   (SwapBarrier); the next frame begins at the swap, as `rtwall bench cluster --display-nodes`
//   paces them. A node's decodes are timed when the copy is sent (its arrival is known then).
// Not modelled: heartbeats, timeouts and dead clients, scene updates, TCP congestion control,
// nodes left out of a frame.
#include "scheduler.h"

#include <rtwall/cluster.h>

#include <algorithm>
#include <bit>
#include <deque>
#include <queue>
#include <random>
#include <stdexcept>

namespace rtwall {

using namespace cluster;

namespace {

enum class Ev {
    FrameBeginAtClient, AssignAtClient, RenderDone, RequestAtMaster, ResultAtMaster, MasterHandle, Housekeeping, FrameDone,
    CpuTick,     // shared cores: the next CPU job may have finished (count = the pool's generation)
    DecodeDone,  // shared cores: a decode finished (frame = its frame)
    ClientSend,  // a client's network work for a result is done: it leaves
    MasterIoDone,  // the master's I/O thread has received a result: on to the network thread
};

struct Event {
    double t;
    uint64_t seq;  // ties broken by creation order: deterministic
    Ev kind;
    uint32_t client = 0, frame = 0;
    std::vector<uint32_t> tiles;  // assignment; or one tile (result, render)
    bool isResult = false;        // MasterHandle: a result (else a request)
    uint32_t count = 0;           // request count
};

Event makeEvent(double t, Ev kind, uint32_t client, uint32_t frame) {
    Event e;
    e.t = t;
    e.seq = 0;
    e.kind = kind;
    e.client = client;
    e.frame = frame;
    return e;
}

struct Later {
    bool operator()(const Event& a, const Event& b) const { return a.t != b.t ? a.t > b.t : a.seq > b.seq; }
};

struct SimClient {
    uint32_t frame = 0;                 // the frame it works on (0 = none)
    std::deque<uint32_t> queue;         // assigned tiles of that frame, not started
    int idle = 0;
    uint32_t credits = 0;               // master side
    double linkFree = 0, linkBusy = 0;  // its uplink
    double lastUp = 0, lastDown = 0;    // arrival times, for in-order delivery
    double busy = 0;                    // render time started in the measured window
};

// A display node: its link and decode threads, and the current frame's tiles it waits for.
struct SimNode {
    double linkFree = 0, linkBusy = 0;
    std::vector<double> decoders;  // when each decode thread is free
    std::vector<uint32_t> held;    // per tile: the last frame whose copy arrived (duplicates decode nothing)
    uint32_t pending = 0;          // tiles of the current frame not yet sent to it
    double doneAt = 0;             // when its last tile of the current frame is decoded
    uint64_t frameBytes = 0, measuredBytes = 0;
};

class Simulation {
public:
    Simulation(const TileProfile& p, const SimConfig& c)
        : profile_(p), config_(c), scheduler_(SchedulerOptions{c.affinity, c.stragglerFactor, 0.05, c.seed}),
          rng_(c.seed ^ 0x9e3779b97f4a7c15ull), clients_(size_t(c.clients)) {
        if (c.clients < 1) throw InputError("simulation: at least one client");
        if (c.threadsPerClient < 1 || c.prefetch < 1 || c.decodeThreads < 1 || c.frames < 1 || c.warmupFrames < 0)
            throw InputError("simulation: threads, prefetch, decode threads and frames must be positive");
        if (!(c.clientSpeed > 0) || !(c.decodeSpeed > 0)) throw InputError("simulation: speeds must be positive");
        if (p.tileCount() == 0) throw InputError("simulation: the tile profile has no tiles");
        if (c.codec >= p.codecs.size()) throw InputError("simulation: the tile profile has no codec #" + std::to_string(c.codec));
        for (const auto& f : p.renderSeconds)
            if (f.size() != p.tileCount()) throw InputError("simulation: the profile's frames differ in tile count");
        const auto& cc = p.codecs[c.codec];
        if (cc.bytes.size() != p.tileCount() || cc.encodeSeconds.size() != p.tileCount() || cc.decodeSeconds.size() != p.tileCount())
            throw InputError("simulation: the profile's codec data do not match its tile count");
        for (uint32_t i = 0; i < uint32_t(c.clients); ++i) {
            scheduler_.addClient(i);
            clients_[i].idle = c.threadsPerClient;
        }
        if (!(c.hostCores >= 0) || !(c.hostBackgroundThreads >= 0))
            throw InputError("simulation: host cores and background threads must be zero or positive");
        for (double x : {c.clientSecondsPerResult, c.clientSecondsPerByte, c.masterSecondsPerResult, c.masterSecondsPerByte,
                         c.masterSecondsPerFrame})
            if (!(x >= 0)) throw InputError("simulation: host costs must be zero or positive");
        decoders_.assign(size_t(c.decodeThreads), 0.0);
        if (c.displayNodes < 0 || size_t(c.displayNodes) > 64) throw InputError("simulation: 0 to 64 display nodes");
        if (c.displayNodes > 0) {
            if (c.nodeDecodeThreads < 1 || !(c.nodeBitsPerSecond >= 0))
                throw InputError("simulation: node decode threads must be positive and node links zero or positive");
            masks_ = c.tileNodes.empty() ? columnNodeMasks(p.width, p.height, p.tileSize, c.displayNodes) : c.tileNodes;
            if (masks_.size() != p.tileCount())
                throw InputError("simulation: " + std::to_string(masks_.size()) + " tile node masks for " +
                                 std::to_string(p.tileCount()) + " tiles");
            const uint64_t valid = c.displayNodes == 64 ? ~0ull : (1ull << c.displayNodes) - 1;
            for (uint64_t m : masks_)
                if (m & ~valid) throw InputError("simulation: a tile's node mask names a node beyond the " +
                                                 std::to_string(c.displayNodes) + " display nodes");
            nodes_.resize(size_t(c.displayNodes));
            for (SimNode& n : nodes_) {
                n.decoders.assign(size_t(c.nodeDecodeThreads), 0.0);
                n.held.assign(p.tileCount(), 0);
            }
        }
    }

    SimReport run() {
        const int total = config_.warmupFrames + config_.frames;
        beginFrame(1, 0.0);
        while (!events_.empty()) {
            Event e = events_.top();
            events_.pop();
            now_ = e.t;
            dispatch(e);
            if (finished_ == uint32_t(total)) break;
        }
        SimReport r;
        r.frameSeconds = frameSeconds_;
        const double window = measureEnd_ - measureStart_;
        r.fps = window > 0 ? double(config_.frames) / window : 0.0;
        r.bytesPerFrame = double(measuredBytes_) / config_.frames;
        if (config_.masterBitsPerSecond > 0 && window > 0) r.masterLinkLoad = measuredBytes_ * 8.0 / config_.masterBitsPerSecond / window;
        r.masterCpuLoad = window > 0 ? masterBusy_ / window : 0.0;
        double sum = 0;
        for (const SimClient& c : clients_) {
            const double u = window > 0 ? c.busy / (window * config_.threadsPerClient) : 0.0;
            r.clientUtilisation.push_back(u);
            sum += u;
            if (config_.clientLink.bitsPerSecond > 0 && window > 0)
                r.maxClientLinkLoad = std::max(r.maxClientLinkLoad, c.linkBusy / window);
        }
        r.meanUtilisation = sum / double(clients_.size());
        r.stolenPerFrame = double(stolen_) / config_.frames;
        r.reissuedPerFrame = double(reissued_) / config_.frames;
        r.duplicatesPerFrame = double(duplicates_) / config_.frames;
        r.affinityHitFraction = double(affinityHits_) / (double(config_.frames) * double(profile_.tileCount()));
        for (const SimNode& n : nodes_) {
            r.nodeBytesPerFrame.push_back(double(n.measuredBytes) / config_.frames);
            if (config_.nodeBitsPerSecond > 0 && window > 0) r.maxNodeLinkLoad = std::max(r.maxNodeLinkLoad, n.linkBusy / window);
        }
        r.meanBarrierWait = barrierWait_ / config_.frames;
        return r;
    }

private:
    const TileProfile& profile_;
    SimConfig config_;
    TileScheduler scheduler_;
    std::mt19937_64 rng_;
    std::vector<SimClient> clients_;
    std::priority_queue<Event, std::vector<Event>, Later> events_;
    uint64_t seq_ = 0;
    double now_ = 0;
    double masterFree_ = 0, masterBusy_ = 0, masterLinkFree_ = 0;
    std::vector<double> decoders_;  // when each decode thread is free
    bool frameActive_ = false;
    uint32_t frame_ = 0;
    double frameStart_ = 0, frameDecodeEnd_ = 0;
    bool frameDoneScheduled_ = false;
    uint32_t finished_ = 0;
    double measureStart_ = 0, measureEnd_ = 0;
    bool measuring_ = false;
    uint64_t measuredBytes_ = 0, frameBytes_ = 0;
    uint64_t stolen_ = 0, reissued_ = 0, duplicates_ = 0, affinityHits_ = 0;
    std::vector<double> frameSeconds_;

    // Shared cores (hostCores > 0): the running CPU jobs, each finishing with its event.
    struct CpuJob {
        double remaining;  // seconds of one core
        Event done;
    };
    std::vector<CpuJob> cpu_;
    double cpuLast_ = 0;
    uint64_t cpuGeneration_ = 0;
    std::deque<Event> masterQueue_;  // messages waiting for the network thread
    bool masterRunning_ = false;
    std::deque<double> decodeQueue_;  // decode costs waiting for a decode thread
    int decodesRunning_ = 0;
    std::deque<Event> ioQueue_;  // results waiting for the master's I/O thread
    bool ioRunning_ = false;
    std::vector<SimNode> nodes_;    // display nodes (none: the master takes the pixels)
    std::vector<uint64_t> masks_;   // per tile, the nodes it goes to
    double barrierWait_ = 0;        // measured frames: slowest node done - first node done

    double resultBytes(uint32_t tile) const {
        return double(profile_.codecs[config_.codec].bytes[tile]) + config_.messageOverheadBytes;
    }

    // A CPU job: on the shared cores, or a plain delay on a machine of its own.
    void work(double seconds, Event done) {
        if (shared()) {
            cpuSubmit(seconds, std::move(done));
        } else {
            done.t = now_ + seconds;
            push(std::move(done));
        }
    }

    void startIo() {
        if (ioRunning_ || ioQueue_.empty()) return;
        ioRunning_ = true;
        Event e = std::move(ioQueue_.front());
        ioQueue_.pop_front();
        const double cost = config_.masterSecondsPerResult + resultBytes(e.tiles.front()) * config_.masterSecondsPerByte;
        e.kind = Ev::MasterIoDone;
        work(cost, std::move(e));
    }

    void sendResult(uint32_t id, uint32_t frame, uint32_t tile) {
        if (!nodes_.empty()) {
            sendToNodes(id, frame, tile);
            return;
        }
        Event r = makeEvent(up(clients_[id], resultBytes(tile)), Ev::ResultAtMaster, id, frame);
        r.tiles = {tile};
        push(std::move(r));
    }

    void frameDone() {
        Event done = makeEvent(now_, Ev::FrameDone, 0, frame_);
        if (config_.masterSecondsPerFrame > 0) work(config_.masterSecondsPerFrame, std::move(done));
        else push(std::move(done));
    }

    bool shared() const { return config_.hostCores > 0; }
    double cpuRate() const {
        return std::min(1.0, config_.hostCores / std::max(1.0, double(cpu_.size()) + config_.hostBackgroundThreads));
    }

    void cpuAdvance() {
        const double done = (now_ - cpuLast_) * cpuRate();
        for (CpuJob& j : cpu_) j.remaining -= done;
        cpuLast_ = now_;
    }

    void cpuSchedule() {
        ++cpuGeneration_;
        if (cpu_.empty()) return;
        double least = cpu_.front().remaining;
        for (const CpuJob& j : cpu_) least = std::min(least, j.remaining);
        Event tick = makeEvent(now_ + std::max(0.0, least) / cpuRate(), Ev::CpuTick, 0, 0);
        tick.count = uint32_t(cpuGeneration_);
        push(std::move(tick));
    }

    void cpuSubmit(double seconds, Event done) {
        cpuAdvance();
        cpu_.push_back({seconds, std::move(done)});
        cpuSchedule();
    }

    void cpuTick(const Event& e) {
        if (e.count != uint32_t(cpuGeneration_)) return;  // the pool changed since: a later tick stands
        cpuAdvance();
        // Jobs finish in submission order when several end together (deterministic).
        constexpr double kEps = 1e-12;
        for (size_t i = 0; i < cpu_.size();) {
            if (cpu_[i].remaining <= kEps) {
                Event d = std::move(cpu_[i].done);
                d.t = now_;
                push(std::move(d));
                cpu_.erase(cpu_.begin() + std::ptrdiff_t(i));
            } else {
                ++i;
            }
        }
        cpuSchedule();
    }

    void startMaster() {
        if (masterRunning_ || masterQueue_.empty()) return;
        masterRunning_ = true;
        Event e = std::move(masterQueue_.front());
        masterQueue_.pop_front();
        if (measuring_) masterBusy_ += config_.masterSecondsPerMessage;
        e.kind = Ev::MasterHandle;
        cpuSubmit(config_.masterSecondsPerMessage, std::move(e));
    }

    void startDecodes() {
        while (decodesRunning_ < config_.decodeThreads && !decodeQueue_.empty()) {
            ++decodesRunning_;
            const double cost = decodeQueue_.front();
            decodeQueue_.pop_front();
            cpuSubmit(cost, makeEvent(0, Ev::DecodeDone, 0, frame_));
        }
    }

    void maybeFinishShared() {
        if (frameActive_ && scheduler_.frameComplete() && decodesRunning_ == 0 && decodeQueue_.empty() && !frameDoneScheduled_) {
            frameDoneScheduled_ = true;
            frameDone();
        }
    }

    void push(Event e) {
        e.seq = seq_++;
        events_.push(std::move(e));
    }

    // A latency spike: the message (and, since order is kept, every later one on the same link
    // and direction) arrives spikeSeconds late. It delays delivery, not the shared master link's
    // other traffic.
    double spike(const SimLink& link) {
        if (link.spikeProbability > 0 && std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < link.spikeProbability)
            return link.spikeSeconds;
        return 0.0;
    }

    // Master -> client: latency only, in order.
    double down(SimClient& c) {
        c.lastDown = std::max(now_ + config_.clientLink.latencySeconds + spike(config_.clientLink), c.lastDown);
        return c.lastDown;
    }

    // Client -> master through the client's link and the master's shared uplink.
    double up(SimClient& c, double bytes) {
        const double bits = bytes * 8.0;
        const double txStart = std::max(now_, c.linkFree);
        const double txTime = config_.clientLink.bitsPerSecond > 0 ? bits / config_.clientLink.bitsPerSecond : 0.0;
        const double txEnd = txStart + txTime;
        c.linkFree = txEnd;
        if (measuring_) c.linkBusy += txTime;
        const double lat = config_.clientLink.latencySeconds;
        double arrive = txEnd + lat;
        if (config_.masterBitsPerSecond > 0) {
            const double mTime = bits / config_.masterBitsPerSecond;
            const double mStart = std::max(txStart + lat, masterLinkFree_);
            arrive = std::max(mStart + mTime, arrive);
            masterLinkFree_ = arrive;
        }
        c.lastUp = std::max(arrive + spike(config_.clientLink), c.lastUp);
        return c.lastUp;
    }

    // Client -> each node of the tile's mask (a copy each over the client's link, then the
    // node's), decoded there; then the ack to the master over the client's and master's links.
    void sendToNodes(uint32_t id, uint32_t frame, uint32_t tile) {
        SimClient& c = clients_[id];
        const double bytes = resultBytes(tile), bits = bytes * 8.0, lat = config_.clientLink.latencySeconds;
        const double decode = profile_.codecs[config_.codec].decodeSeconds[tile] / config_.decodeSpeed;
        for (size_t i = 0; i < nodes_.size(); ++i) {
            if (!(masks_[tile] >> i & 1)) continue;
            SimNode& n = nodes_[i];
            const double txStart = std::max(now_, c.linkFree);
            const double txTime = config_.clientLink.bitsPerSecond > 0 ? bits / config_.clientLink.bitsPerSecond : 0.0;
            c.linkFree = txStart + txTime;
            if (measuring_) c.linkBusy += txTime;
            double arrive = c.linkFree + lat;
            if (config_.nodeBitsPerSecond > 0) {
                const double nTime = bits / config_.nodeBitsPerSecond;
                const double nStart = std::max(txStart + lat, n.linkFree);
                arrive = std::max(nStart + nTime, arrive);
                n.linkFree = arrive;
                if (measuring_) n.linkBusy += nTime;
            }
            arrive += spike(config_.clientLink);
            if (frame != frame_ || n.held[tile] == frame) continue;  // a late or repeated copy: the node drops it
            n.held[tile] = frame;
            auto free = std::min_element(n.decoders.begin(), n.decoders.end());
            *free = std::max(arrive, *free) + decode;
            n.doneAt = std::max(n.doneAt, *free);
            n.frameBytes += uint64_t(bytes);
            --n.pending;
        }
        Event r = makeEvent(up(c, config_.messageOverheadBytes), Ev::ResultAtMaster, id, frame);
        r.tiles = {tile};
        push(std::move(r));
    }

    // All acks are in: the swap, once the slowest node holds the frame (NodeHave up, NodeSwap down).
    void swapWhenNodesHold() {
        double first = now_, last = now_;
        bool any = false;
        for (const SimNode& n : nodes_) {
            if (n.pending != 0) continue;  // cannot happen: every tile's copies leave before its ack
            first = any ? std::min(first, n.doneAt) : n.doneAt;
            last = any ? std::max(last, n.doneAt) : n.doneAt;
            any = true;
        }
        if (measuring_) barrierWait_ += last - first;
        const double lat = config_.clientLink.latencySeconds;
        const double swap = std::max(now_, last + lat) + lat;
        push(makeEvent(swap + config_.masterSecondsPerFrame, Ev::FrameDone, 0, frame_));
    }

    void beginFrame(uint32_t frame, double t) {
        frame_ = frame;
        frameActive_ = true;
        frameStart_ = t;
        frameDecodeEnd_ = t;
        frameDoneScheduled_ = false;
        frameBytes_ = 0;
        if (frame == uint32_t(config_.warmupFrames) + 1) {
            measuring_ = true;
            measureStart_ = t;
        }
        scheduler_.beginFrame(frame, uint32_t(profile_.tileCount()));
        for (size_t i = 0; i < nodes_.size(); ++i) {
            nodes_[i].pending = 0;
            for (uint64_t m : masks_) nodes_[i].pending += uint32_t(m >> i & 1);
            nodes_[i].doneAt = t;
            nodes_[i].frameBytes = 0;
        }
        for (uint32_t i = 0; i < clients_.size(); ++i) {
            clients_[i].credits = 0;
            Event e = makeEvent(down(clients_[i]), Ev::FrameBeginAtClient, i, frame);
            push(std::move(e));
        }
        if (config_.housekeepingSeconds > 0) push(makeEvent(t + config_.housekeepingSeconds, Ev::Housekeeping, 0, frame));
    }

    void serve(uint32_t id) {
        SimClient& c = clients_[id];
        if (!frameActive_ || c.credits == 0) return;
        std::vector<uint32_t> tiles = scheduler_.request(id, c.credits, now_);
        if (tiles.empty()) return;
        c.credits -= uint32_t(tiles.size());
        Event e = makeEvent(down(c), Ev::AssignAtClient, id, frame_);
        e.tiles = std::move(tiles);
        push(std::move(e));
    }

    void startWork(uint32_t id) {
        SimClient& c = clients_[id];
        const auto& codec = profile_.codecs[config_.codec];
        const auto& render = profile_.renderSeconds[(c.frame - 1) % profile_.renderSeconds.size()];
        while (c.idle > 0 && !c.queue.empty()) {
            const uint32_t tile = c.queue.front();
            c.queue.pop_front();
            --c.idle;
            const double cost = (render[tile] + codec.encodeSeconds[tile]) / config_.clientSpeed;
            if (measuring_) c.busy += cost;
            Event e = makeEvent(now_ + cost, Ev::RenderDone, id, c.frame);
            e.tiles = {tile};
            if (shared()) cpuSubmit(cost, std::move(e));
            else push(std::move(e));
        }
    }

    // The master's network thread: one message at a time.
    void toMaster(Event e) {
        if (shared()) {
            masterQueue_.push_back(std::move(e));
            startMaster();
            return;
        }
        const double start = std::max(now_, masterFree_);
        masterFree_ = start + config_.masterSecondsPerMessage;
        if (measuring_) masterBusy_ += config_.masterSecondsPerMessage;
        e.kind = Ev::MasterHandle;
        e.t = masterFree_;
        push(std::move(e));
    }

    void dispatch(Event& e) {
        switch (e.kind) {
        case Ev::FrameBeginAtClient: {
            SimClient& c = clients_[e.client];
            c.queue.clear();  // dropWork
            c.frame = e.frame;
            Event r = makeEvent(up(c, config_.messageOverheadBytes), Ev::RequestAtMaster, e.client, e.frame);
            r.count = uint32_t(config_.prefetch);
            push(std::move(r));
            break;
        }
        case Ev::AssignAtClient: {
            SimClient& c = clients_[e.client];
            if (e.frame != c.frame) break;  // dropped, as the client does
            for (uint32_t t : e.tiles) c.queue.push_back(t);
            startWork(e.client);
            break;
        }
        case Ev::RenderDone: {
            SimClient& c = clients_[e.client];
            ++c.idle;
            const uint32_t tile = e.tiles.front();
            const double send = config_.clientSecondsPerResult + resultBytes(tile) * config_.clientSecondsPerByte;
            if (send > 0) {
                Event s = makeEvent(0, Ev::ClientSend, e.client, e.frame);
                s.tiles = {tile};
                work(send, std::move(s));
            } else {
                sendResult(e.client, e.frame, tile);
            }
            startWork(e.client);
            break;
        }
        case Ev::ClientSend: sendResult(e.client, e.frame, e.tiles.front()); break;
        case Ev::MasterIoDone:
            ioRunning_ = false;
            e.isResult = true;
            toMaster(std::move(e));
            startIo();
            break;
        case Ev::ResultAtMaster:
            if (config_.masterSecondsPerResult > 0 || config_.masterSecondsPerByte > 0) {
                ioQueue_.push_back(std::move(e));
                startIo();
                break;
            }
            [[fallthrough]];
        case Ev::RequestAtMaster:
            e.isResult = e.kind == Ev::ResultAtMaster;
            toMaster(std::move(e));
            break;
        case Ev::MasterHandle:
            if (shared()) masterRunning_ = false;
            handle(e);
            if (shared()) startMaster();
            break;
        case Ev::CpuTick: cpuTick(e); break;
        case Ev::DecodeDone:
            --decodesRunning_;
            startDecodes();
            if (e.frame == frame_) maybeFinishShared();
            break;
        case Ev::Housekeeping:
            if (!frameActive_ || e.frame != frame_) break;
            for (uint32_t i = 0; i < clients_.size(); ++i) serve(i);
            push(makeEvent(now_ + config_.housekeepingSeconds, Ev::Housekeeping, 0, e.frame));
            break;
        case Ev::FrameDone: finishFrame(); break;
        }
    }

    void handle(const Event& e) {
        SimClient& c = clients_[e.client];
        if (!e.isResult) {
            if (frameActive_ && e.frame == frame_) {
                c.credits = std::min<uint32_t>(c.credits + e.count, 64);
                serve(e.client);
            }
            return;
        }
        if (!frameActive_ || e.frame != frame_) return;  // a tile of a frame no longer current
        const uint32_t tile = e.tiles.front();
        const auto result = scheduler_.complete(e.client, e.frame, tile, now_);
        c.credits += 1;
        if (result == TileScheduler::Result::Accepted && !nodes_.empty()) {
            // As the master counts it: the tile's bytes once per node it went to.
            frameBytes_ += uint64_t(resultBytes(tile)) * uint64_t(std::popcount(masks_[tile]));
            if (scheduler_.frameComplete() && !frameDoneScheduled_) {
                frameDoneScheduled_ = true;
                swapWhenNodesHold();
            }
        } else if (result == TileScheduler::Result::Accepted) {
            const auto& codec = profile_.codecs[config_.codec];
            frameBytes_ += codec.bytes[tile] + config_.messageOverheadBytes;
            if (shared()) {
                decodeQueue_.push_back(codec.decodeSeconds[tile] / config_.decodeSpeed);
                startDecodes();
                maybeFinishShared();
                serve(e.client);
                return;
            }
            auto free = std::min_element(decoders_.begin(), decoders_.end());
            const double start = std::max(now_, *free);
            *free = start + codec.decodeSeconds[tile] / config_.decodeSpeed;
            frameDecodeEnd_ = std::max(frameDecodeEnd_, *free);
            if (scheduler_.frameComplete() && !frameDoneScheduled_) {
                frameDoneScheduled_ = true;
                push(makeEvent(frameDecodeEnd_ + config_.masterSecondsPerFrame, Ev::FrameDone, 0, frame_));
            }
        }
        serve(e.client);
    }

    void finishFrame() {
        frameActive_ = false;
        ++finished_;
        if (measuring_) {
            const SchedulerStats& st = scheduler_.stats();
            frameSeconds_.push_back(now_ - frameStart_);
            measuredBytes_ += frameBytes_;
            for (SimNode& n : nodes_) n.measuredBytes += n.frameBytes;
            stolen_ += st.stolen;
            reissued_ += st.reissued;
            duplicates_ += st.duplicates;
            affinityHits_ += st.affinityHits;
            measureEnd_ = now_;
        }
        if (finished_ < uint32_t(config_.warmupFrames + config_.frames)) beginFrame(frame_ + 1, now_);
    }
};

}  // namespace

std::vector<uint64_t> columnNodeMasks(int width, int height, int tileSize, int nodes) {
    if (nodes < 1 || nodes > 64) throw InputError("column node masks: 1 to 64 nodes");
    std::vector<uint64_t> masks;
    for (const TileRect& t : makeTiles(width, height, tileSize)) {
        // Node i's columns are [i * width / nodes, (i + 1) * width / nodes): the first and last
        // nodes whose run holds one of the tile's pixels, and every one between.
        const int first = int(int64_t(t.x0) * nodes / width), last = int(int64_t(t.x1 - 1) * nodes / width);
        uint64_t m = 0;
        for (int i = first; i <= last && i < nodes; ++i) m |= 1ull << i;
        masks.push_back(m);
    }
    return masks;
}

SimReport simulateCluster(const TileProfile& profile, const SimConfig& config) {
    return Simulation(profile, config).run();
}

}  // namespace rtwall
