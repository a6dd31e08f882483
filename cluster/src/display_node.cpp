// A display node's network side (issue 19): a DEALER to the master for control (NodeHello,
// NodeFrame, NodeHave, NodeSwap, NodeSwapped) and a ROUTER on which the render clients deliver
// the tiles its screens show. Tiles are decoded on this thread straight into a NodeAssembly;
// a tile that comes before its frame's NodeFrame (it travels on another connection) waits in a
// bounded queue. What is presented, and how, is the caller's callback.
#include "codec.h"
#include "net.h"
#include "node_assembly.h"
#include "protocol.h"

#include <rtwall/cluster.h>

#include <zmq.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <thread>
#include <vector>

namespace rtwall {

using namespace cluster;

namespace {

// Tiles of frames this node has not begun yet: more are dropped (and the frame is then missed).
constexpr size_t kMaxEarlyTiles = 4096;

class DisplayNode {
public:
    explicit DisplayNode(const DisplayNodeRun& run) : run_(run) {}

    int operator()() {
        tiles_.set(zmq::sockopt::linger, 0);
        tiles_.set(zmq::sockopt::maxmsgsize, int64_t(kHeaderSize + 64 + maxEncodedTileBytes(2 * 1024, 1024)));
        tiles_.set(zmq::sockopt::rcvhwm, 100000);
        tiles_.bind(run_.bind);
        endpoint_ = tiles_.get(zmq::sockopt::last_endpoint);
        connect();
        double idleSince = nowSeconds();
        for (;;) {
            zmq::pollitem_t items[] = {{master_.handle(), 0, ZMQ_POLLIN, 0}, {tiles_.handle(), 0, ZMQ_POLLIN, 0}};
            try {
                zmq::poll(items, 2, std::chrono::milliseconds(10));
            } catch (const zmq::error_t& e) {
                // A signal (SIGTERM from `rtwall display`'s handler) interrupted the wait: the
                // stop flag is looked at below, as after any wait.
                if (e.num() != EINTR) throw;
                items[0].revents = items[1].revents = 0;
            }
            if (items[0].revents & ZMQ_POLLIN) {
                for (int i = 0; i < 256; ++i) {
                    zmq::message_t msg;
                    if (!master_.recv(msg, zmq::recv_flags::dontwait)) break;
                    if (discardRestOf(master_, msg) > 0) continue;
                    const std::optional<int> status = fromMaster(msg);
                    if (status) return *status;
                    lastHeard_ = idleSince = nowSeconds();
                }
            }
            if (items[1].revents & ZMQ_POLLIN) {
                for (int i = 0; i < 1024; ++i) {
                    zmq::message_t identity, msg;
                    if (!tiles_.recv(identity, zmq::recv_flags::dontwait)) break;
                    if (!identity.more() || !tiles_.recv(msg, zmq::recv_flags::dontwait)) continue;
                    if (discardRestOf(tiles_, msg) > 0) continue;
                    onTile(std::move(msg));
                }
            }
            if (run_.stop && run_.stop->load()) {
                if (session_) send(Goodbye{"display node '" + run_.name + "' stops"});
                return 0;
            }
            const double now = nowSeconds();
            if (session_ && now - lastSent_ > heartbeatMs_ * 1e-3) send(Heartbeat{});
            if (now - lastHeard_ > timeoutMs_ * 1e-3) {
                if (run_.exitAfterIdleMs > 0 && now - idleSince > run_.exitAfterIdleMs * 1e-3) {
                    std::fprintf(stderr, "rtwall display: no master at %s for %d ms, giving up\n", run_.connect.c_str(),
                                 run_.exitAfterIdleMs);
                    return 1;
                }
                // The master went silent: join again (a restarted master, or one that dropped us).
                connect();
            }
        }
    }

private:
    static double nowSeconds() {
        return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    }

    void connect() {
        master_ = zmq::socket_t(ctx_, zmq::socket_type::dealer);
        configureSocket(master_, int64_t(kHeaderSize + 64 + kMaxWallConfigBytes + (1 << 26)), 250, 3000);
        master_.set(zmq::sockopt::linger, 0);
        master_.connect(run_.connect);
        session_ = 0;
        routes_.clear();
        early_.clear();
        slots_[0].begun = slots_[1].begun = false;
        sendNow(master_, encodeMessage(Header{}, NodeHello{kProtocolVersion, run_.name, endpoint_, ""}));
        lastHeard_ = lastSent_ = nowSeconds();
    }

    template <class Msg> void send(const Msg& msg, uint32_t frame = 0) {
        Header h;
        h.session = session_;
        h.frame = frame;
        sendNow(master_, encodeMessage(h, msg));
        lastSent_ = nowSeconds();
    }

    std::optional<int> fromMaster(const zmq::message_t& msg) {
        const auto* bytes = static_cast<const uint8_t*>(msg.data());
        try {
            const Header h = decodeHeader(bytes, msg.size());
            const uint8_t* p = bytes + kHeaderSize;
            const size_t n = msg.size() - kHeaderSize;
            if (h.version != kProtocolVersion) {
                std::fprintf(stderr, "rtwall display: the master speaks protocol version %u, this node %u\n", unsigned(h.version),
                             unsigned(kProtocolVersion));
                return 1;
            }
            if (h.type == MsgType::Goodbye) {
                std::fprintf(stderr, "rtwall display: the master says goodbye: %s\n", decodePayload<Goodbye>(p, n).reason.c_str());
                return 0;
            }
            if (h.type == MsgType::NodeWelcome) {
                const NodeWelcome w = decodePayload<NodeWelcome>(p, n);
                session_ = h.session;
                index_ = w.node;
                heartbeatMs_ = int(std::max(10u, w.heartbeatMs));
                timeoutMs_ = int(std::max(w.timeoutMs, 2 * w.heartbeatMs));
                if (run_.onWall) run_.onWall(w.wall);
                std::fprintf(stderr, "rtwall display: node '%s' (%u) joined %s, tiles to %s\n", run_.name.c_str(), index_,
                             run_.connect.c_str(), endpoint_.c_str());
                return std::nullopt;
            }
            if (session_ == 0 || h.session != session_) return std::nullopt;  // another session, or before the welcome
            switch (h.type) {
            case MsgType::TileRoutes: {
                TileRoutes r = decodePayload<TileRoutes>(p, n);
                routes_[r.frame] = std::move(r.masks);
                while (routes_.size() > 2) routes_.erase(routes_.begin());
                break;
            }
            case MsgType::NodeFrame: onFrame(decodePayload<NodeFrame>(p, n)); break;
            case MsgType::NodeSwap: {
                const NodeSwap s = decodePayload<NodeSwap>(p, n);
                const Slot* slot = slotOf(s.frame);
                const bool held = slot && slot->assembly.complete();
                if (run_.present) run_.present(s.frame, held ? &slot->assembly.image() : nullptr, s.leftOut);
                send(NodeSwapped{s.frame}, s.frame);
                if (held && run_.frames > 0 && ++presented_ >= run_.frames) {
                    send(Goodbye{"display node '" + run_.name + "' presented its frames"});
                    return 0;
                }
                break;
            }
            default: break;  // heartbeats, and types a node never gets
            }
        } catch (const DecodeError& e) {
            std::fprintf(stderr, "rtwall display: dropped a malformed message from the master: %s\n", e.what());
        }
        return std::nullopt;
    }

    void onFrame(const NodeFrame& f) {
        auto r = routes_.upper_bound(f.frame);
        if (r == routes_.begin()) {
            std::fprintf(stderr, "rtwall display: frame %u came without its tile masks; it is skipped\n", f.frame);
            return;
        }
        // The newest frame goes into the older slot: the frame before may still be waiting for
        // its last tiles or its swap (the master begins frame N+1 on N's last ack, which can
        // overtake N's last tile on its way here, and N's NodeSwap comes after N+1 began).
        Slot& slot = slots_[current_ ^ 1];
        try {
            slot.assembly.beginFrame(f.frame, f.width, f.height, f.tileSize, std::prev(r)->second, index_);
        } catch (const std::invalid_argument& e) {
            std::fprintf(stderr, "rtwall display: frame %u is skipped: %s\n", f.frame, e.what());
            return;
        }
        current_ ^= 1;
        slot.begun = true;
        slot.pixels = f.pixels;
        slot.haveSent = false;
        // The tiles that came first.
        std::vector<zmq::message_t> early;
        early.swap(early_);
        for (zmq::message_t& m : early) onTile(std::move(m));
        reportIfComplete();
    }

    void onTile(zmq::message_t msg) {
        const auto* bytes = static_cast<const uint8_t*>(msg.data());
        TileResult r;
        try {
            const Header h = decodeHeader(bytes, msg.size());
            if (h.type != MsgType::TileResult || h.version != kProtocolVersion || session_ == 0 || h.session != session_) return;
            r = decodePayload<TileResult>(bytes + kHeaderSize, msg.size() - kHeaderSize);
        } catch (const DecodeError&) {
            return;
        }
        const Slot& newest = slots_[current_];
        if (!newest.begun || r.frame > newest.assembly.frame()) {
            if (early_.size() < kMaxEarlyTiles) early_.push_back(std::move(msg));
            return;
        }
        Slot* slot = slotOf(r.frame);
        if (!slot) return;  // stale
        NodeAssembly& assembly = slot->assembly;
        TileRect rect;
        TileView view;
        if (assembly.claim(r.frame, r.tile, rect, view) != NodeAssembly::Claim::Granted) return;
        try {
            if (r.format != slot->pixels) throw DecodeError("a tile in another pixel format than its frame's");
            if (r.format == TilePixels::LinearHalf) {
                // An accumulated frame's tile: shown as this frame's 8-bit pixels (the node does
                // not accumulate across frames).
                linear_.resize(size_t(rect.width()) * rect.height() * 3);
                decodeWideTile(r.codec, r.pixels.data(), r.pixels.size(), rect.width(), rect.height(), linear_.data(),
                               size_t(rect.width()) * 3, scratch_);
                for (int y = 0; y < rect.height(); ++y)
                    linearToSrgb8(linear_.data() + size_t(y) * rect.width() * 3, size_t(rect.width()) * 3, view.data + y * view.stride);
            } else {
                decodeTile(r.codec, r.pixels.data(), r.pixels.size(), rect.width(), rect.height(), view.data, view.stride);
            }
            assembly.commit(r.tile);
        } catch (const DecodeError& e) {
            assembly.release(r.tile);
            std::fprintf(stderr, "rtwall display: tile %u of frame %u did not decode: %s\n", r.tile, r.frame, e.what());
            return;
        }
        reportIfComplete();
    }

    // The older frame first: the barrier releases frames in order.
    void reportIfComplete() {
        for (int i : {current_ ^ 1, current_}) {
            Slot& slot = slots_[i];
            if (!slot.begun || slot.haveSent || !slot.assembly.complete()) continue;
            slot.haveSent = true;
            send(NodeHave{slot.assembly.frame()}, slot.assembly.frame());
        }
    }

    // The slot that holds `frame` (begun in this session), if any.
    struct Slot;
    Slot* slotOf(uint32_t frame) {
        for (Slot& slot : slots_)
            if (slot.begun && slot.assembly.frame() == frame) return &slot;
        return nullptr;
    }

    const DisplayNodeRun& run_;
    zmq::context_t ctx_{1};
    zmq::socket_t master_;
    zmq::socket_t tiles_{ctx_, zmq::socket_type::router};
    std::string endpoint_;
    uint64_t session_ = 0;
    uint32_t index_ = 0;
    int heartbeatMs_ = 250, timeoutMs_ = 3000;
    double lastHeard_ = 0, lastSent_ = 0;
    std::map<uint32_t, std::vector<uint64_t>> routes_;  // tile masks by their first frame
    // The newest frame (slots_[current_]) and the one before it.
    struct Slot {
        NodeAssembly assembly;
        bool begun = false;     // holds a frame begun in this session
        bool haveSent = false;  // its NodeHave went
        TilePixels pixels = TilePixels::Srgb8;
    };
    Slot slots_[2];
    int current_ = 0;
    std::vector<zmq::message_t> early_;
    std::vector<float> linear_;
    std::vector<uint8_t> scratch_;
    int presented_ = 0;
};

}  // namespace

int runDisplayNode(const DisplayNodeRun& run) {
    if (run.name.empty()) throw InputError("display node: no name (--node NAME)");
    DisplayNode node(run);
    return node();
}

}  // namespace rtwall
