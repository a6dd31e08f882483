// A render client's link to the master: connecting (and again after a silence, with a jittered
// back-off), the network loop, and what each message from the master does.
#include "client_runtime.h"

#include <unistd.h>

#include <cstdio>
#include <limits>
#include <random>

namespace rtwall::cluster {

void ClientRuntime::connect() {
    // The old connection's unsent messages go with it: kept (zmq's default linger), its Hello
    // would reach a restarted master once the port answers again and be taken for another
    // client, one that never renders.
    if (dealer_) dealer_.set(zmq::sockopt::linger, 0);
    dealer_ = zmq::socket_t(ctx_, zmq::socket_type::dealer);
    // The largest legitimate message from the master is a mesh.
    configureSocket(dealer_, int64_t(kHeaderSize + 64 + kMaxMeshBytes), heartbeatMs_, timeoutMs());
    dealer_.set(zmq::sockopt::reconnect_ivl, 100);
    dealer_.set(zmq::sockopt::reconnect_ivl_max, std::max(100, settings_.maxReconnectMs));
    if (!settings_.keyFile.empty()) setCurveClient(dealer_, serverKey_, keys_);
    // The handshake's outcome (a refused key, no CURVE on one side) is said in one line.
    monitor_.start(ctx_, dealer_, "inproc://rtwall-client-monitor-" + std::to_string(++monitorSeq_), kMasterLinkEvents);
    dealer_.connect(settings_.connect);
    session_ = 0;
    assignFrame_ = 0;
    assignSeen_ = 0;
    ready_ = false;
    snapshot_.reset();
    forgetPendingFiles();
    ++buildGeneration_;
    lastFrameBegun_ = 0;
    nodeLinks_.clear();  // the master sends its node list again
    tileRoutes_.clear();
    Hello hello;
    hello.threads = uint32_t(threads_);
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    hello.host = host;
    sendNow(dealer_, encodeMessage(header(MsgType::Hello), hello));
    lastHeard_ = nowSeconds();
}

int ClientRuntime::networkLoop() {
    connect();
    double idleSince = nowSeconds();
    std::mt19937 jitter(std::random_device{}());
    for (;;) {
        zmq::pollitem_t items[] = {{dealer_.handle(), 0, ZMQ_POLLIN, 0},
                                   {results_.handle(), 0, ZMQ_POLLIN, 0},
                                   {monitor_.handle(), 0, ZMQ_POLLIN, 0}};
        zmq::poll(items, monitor_ ? 3 : 2, std::chrono::milliseconds(20));
        if (items[0].revents & ZMQ_POLLIN) {
            for (int i = 0; i < 256; ++i) {
                zmq::message_t msg;
                if (!dealer_.recv(msg, zmq::recv_flags::dontwait)) break;
                // One frame per message: a multi-frame one goes whole (each part read once).
                if (discardRestOf(dealer_, msg) > 0) {
                    drop();
                    continue;
                }
                // Only messages this client can use count as the master being there: a
                // peer that sends garbage does not keep it waiting for ever.
                const uint64_t droppedBefore = dropped_;
                if (auto status = handle(msg)) return *status;
                if (dropped_ == droppedBefore) lastHeard_ = idleSince = nowSeconds();
            }
        }
        if (items[1].revents & ZMQ_POLLIN) forwardResults(256);
        if (monitor_ && (items[2].revents & ZMQ_POLLIN)) readMonitor();
        readNodeMonitors();
        finishBuild();
        watchStalls();
        if (blockedFrame_) {
            const FrameBegin fb = *blockedFrame_;
            onFrameBegin(fb);
            if (blockedFrame_ && !blockedLogged_ && nowSeconds() - blockedSince_ > settings_.minStallMs * 1e-3) {
                blockedLogged_ = true;
                std::fprintf(stderr, "rtwall client %u: frame %u waits: a render thread is still inside the scene\n", id_, fb.frame);
            }
        }
        if (std::string why = failure(); !why.empty()) {
            // The tiles rendered before the failure go first: they are not lost with it.
            forwardResults(std::numeric_limits<int>::max());
            if (std::optional<TileFailed> tile = failedTile()) send(*tile);  // which tile, for its replay
            send(Goodbye{why});
            std::fprintf(stderr, "rtwall client: %s\n", why.c_str());
            return 1;
        }
        const double now = nowSeconds();
        // The heartbeat says what this client holds, so that the master can tell a lost
        // hand-out from a slow one.
        if (session_.load() && now - lastSent_ > heartbeatMs_ * 1e-3)
            send(Heartbeat{assignFrame_, assignSeen_, held_.load() == 0});
        if (reconnectRequested_ || now - lastHeard_ > timeoutMs() * 1e-3) {
            // The master went silent or away: start over with a fresh connection after an
            // exponentially growing, jittered pause, so that a restarted master is not hit by
            // every client in the same millisecond.
            if (settings_.exitAfterIdleMs > 0 && now - idleSince > settings_.exitAfterIdleMs * 1e-3) {
                std::fprintf(stderr, "rtwall client: no master at %s for %d ms, giving up%s\n",
                             settings_.connect.c_str(), settings_.exitAfterIdleMs, handshakeNote().c_str());
                return 1;
            }
            reconnectRequested_ = false;
            dropWork();
            const int pause = std::uniform_int_distribution<int>(backoffMs_ / 2, backoffMs_)(jitter);
            backoffMs_ = std::min(std::max(100, settings_.maxReconnectMs), backoffMs_ * 2);
            std::this_thread::sleep_for(std::chrono::milliseconds(pause));
            connect();
        }
    }
}

// Hands up to `max` finished tiles from the render threads to the master's connection.
void ClientRuntime::forwardResults(int max) {
    for (int i = 0; i < max; ++i) {
        zmq::message_t msg;
        if (!results_.recv(msg, zmq::recv_flags::dontwait)) break;
        // Lost if its queue is full: the master hands the tile out again when this
        // client is idle without it (its heartbeat says so).
        const int n = faults_.dropEveryNthResult;
        if (n > 0 && ++resultsOut_ % uint64_t(n) == 0) {
            // Injected loss.
        } else if (!tileRoutes_.empty()) {
            sendToNodes(msg);
        } else if (!dealer_.send(msg, zmq::send_flags::dontwait)) {
            ++lostResults_;
        }
        --held_;
        lastSent_ = nowSeconds();
    }
}

// Returns an exit status when the client should stop.
std::optional<int> ClientRuntime::handle(const zmq::message_t& msg) {
    const auto* bytes = static_cast<const uint8_t*>(msg.data());
    try {
        const Header h = decodeHeader(bytes, msg.size());
        const uint8_t* p = bytes + kHeaderSize;
        const size_t n = msg.size() - kHeaderSize;
        if (refuseOtherVersion(h, "rtwall client", "client")) return 1;
        if (h.type == MsgType::Welcome) {
            const Welcome w = decodePayload<Welcome>(p, n);
            if (h.session != session_.load()) {  // a new master session: nothing of the old one counts
                assignFrame_ = 0;
                assignSeen_ = 0;
                snapshot_.reset();
                forgetPendingFiles();
                ++buildGeneration_;
                ready_ = false;
                lastFrameBegun_ = 0;
                nodeLinks_.clear();
                tileRoutes_.clear();
                warpGrids_.clear();
                saidWarpGrid_ = false;
            }
            session_ = h.session;
            id_ = w.clientId;
            backoffMs_ = 100;
            // A Welcome within the session changes the codec (Master::setCodec) for tiles
            // assigned from now on; replayed bytes of the old one go.
            if (!(w.codec == codec_)) {
                std::lock_guard replayLock(replayMutex_);
                replay_.clear();
            }
            codec_ = w.codec;
            prefetch_ = std::max(1u, w.prefetch);
            heartbeatMs_ = int(std::max(10u, w.heartbeatMs));
            timeoutMs_ = int(std::max(std::max(50u, w.timeoutMs), 2 * uint32_t(heartbeatMs_)));
            return std::nullopt;
        }
        if (h.session != session_.load() || session_.load() == 0) {
            drop();  // from another master session, or before the handshake
            return std::nullopt;
        }
        switch (h.type) {
        case MsgType::SceneSnapshot: onSnapshot(decodePayload<SceneSnapshot>(p, n)); break;
        case MsgType::MeshData: onMeshData(decodePayload<MeshData>(p, n)); break;
        case MsgType::AssetData: onAssetData(decodePayload<AssetData>(p, n)); break;
        case MsgType::Update: {
            Update u = decodePayload<Update>(p, n);
            fetchFilesOf(u);
            if (!updates_.add(std::move(u))) requestResync();
            break;
        }
        case MsgType::FrameBegin: onFrameBegin(decodePayload<FrameBegin>(p, n)); break;
        case MsgType::TileAssign: onAssign(decodePayload<TileAssign>(p, n)); break;
        case MsgType::Heartbeat: decodePayload<Heartbeat>(p, n); break;
        case MsgType::NodeList: onNodeList(decodePayload<NodeList>(p, n)); break;
        case MsgType::TileRoutes: onTileRoutes(decodePayload<TileRoutes>(p, n)); break;
        case MsgType::WarpGrids: {
            WarpGrids g = decodePayload<WarpGrids>(p, n);
            warpGrids_.clear();
            for (PixelWarp& w : g.grids) warpGrids_.push_back(std::make_shared<const PixelWarp>(std::move(w)));
            break;
        }
        case MsgType::Goodbye: {
            const Goodbye bye = decodePayload<Goodbye>(p, n);
            std::fprintf(stderr, "rtwall client %u: the master says goodbye: %s\n", id_, bye.reason.c_str());
            if (settings_.exitAfterIdleMs > 0) return 0;
            reconnectRequested_ = true;  // a master that restarts finds this client waiting
            break;
        }
        default: drop(); break;  // a type only clients send
        }
    } catch (const DecodeError&) {
        drop();
    } catch (const std::exception& e) {
        std::lock_guard lock(workMutex_);
        failure_ = std::string("cannot use the master's scene: ") + e.what();
    }
    return std::nullopt;
}

void ClientRuntime::drop() {
    ++dropped_;
    if (settings_.counters) ++settings_.counters->droppedMessages;
}

// Handshake events of the connection to the master: a refusal is said, not just "no master".
void ClientRuntime::readMonitor() {
    monitor_.read(16, [&](const MonitorEvent& e) {
        handshakes_.onEvent(e, settings_.connect, keys_.publicKey, settings_.counters ? &settings_.counters->refusedHandshakes : nullptr,
                            settings_.counters ? &settings_.counters->failedHandshakes : nullptr);
    });
}

std::string ClientRuntime::handshakeNote() const {
    if (handshakes_.trouble().empty()) return {};
    return " (" + handshakes_.trouble() + "; " + std::to_string(handshakes_.failures()) + " failed handshake" +
           (handshakes_.failures() == 1 ? "" : "s") + ")";
}

}  // namespace rtwall::cluster
