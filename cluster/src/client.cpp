// A render client: one network thread (the caller's) owns the DEALER socket; render threads
// share one scene, take tiles from a local queue and hand encoded results back through inproc
// PUSH sockets, so only the network thread ever touches the master's connection.
#include "codec.h"
#include "net.h"
#include "protocol.h"
#include "scene_state.h"
#include "security.h"
#include "update_sequencer.h"

#include <rtwall/cluster.h>
#include <rtwall/cluster_testing.h>

#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <future>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <shared_mutex>
#include <thread>

namespace rtwall {

using namespace cluster;

namespace {

std::string hexOf(const Hash128& h) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", (unsigned long long)h[1], (unsigned long long)h[0]);
    return buf;
}

class ClientRuntime {
public:
    explicit ClientRuntime(const ClientSettings& s) : settings_(s), faults_(s.faults ? *s.faults : ClientFaults{}) {
        threads_ = s.threads > 0 ? s.threads : int(std::max(1u, std::thread::hardware_concurrency()));
        checkZmqVersion();
        if (!s.keyFile.empty()) {
            if (s.serverKeyFile.empty()) throw InputError("--key needs --server-key (the master's public key)");
            keys_ = readKeyPair(s.keyFile);
            serverKey_ = readPublicKey(s.serverKeyFile);
        }
    }

    int run() {
        results_.bind(kResultsAddress);
        slots_ = std::make_unique<Slot[]>(size_t(threads_));
        for (int i = 0; i < threads_; ++i) workers_.emplace_back([this, i] { workerLoop(slots_[size_t(i)]); });
        const int status = networkLoop();
        {
            std::lock_guard lock(workMutex_);
            stopping_ = true;
        }
        stopRequested_ = true;
        workCv_.notify_all();
        for (auto& t : workers_) t.join();
        return status;
    }

private:
    static constexpr const char* kResultsAddress = "inproc://rtwall-client-results";

    // A frame's views and tiling (FrameBegin::views: one view for a mono frame), shared by its
    // work items and never changed once made: a render thread reads it without a lock.
    struct FrameLayout {
        std::vector<CameraDesc> cameras;  // per view
        std::vector<ViewTile> tiles;
    };

    // A tile to render with everything the render thread needs from the network thread's state,
    // captured when the assignment arrives: render threads never read what that thread writes.
    struct Work {
        uint32_t frame = 0;
        uint32_t tile = 0;
        uint32_t stateSeq = 0;  // for the result's header
        CodecSettings codec;
        TilePixels pixels = TilePixels::Srgb8;
        std::shared_ptr<const FrameLayout> layout;  // its frame's
    };

    // What a render thread is rendering, for the network thread's stall watch. Written per tile
    // with two atomic stores (no lock on the render path); read consistently by checking that
    // the start time did not change around the read.
    struct Slot {
        std::atomic<uint64_t> job{0};      // frame << 32 | tile
        std::atomic<int64_t> startNs{0};   // 0: idle
        int64_t reportedStartNs = 0;       // network thread only: the stall already reported
    };

    // More tiles than any master gives a client (64 credits) are not queued: a master that
    // assigns without end must not fill this client's memory.
    static constexpr size_t kMaxQueuedTiles = 4096;

    static int64_t steadyNs() {
        return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
    }

    // ---- network thread -------------------------------------------------------------------

    void connect() {
        // The old connection's unsent messages go with it: kept (zmq's default linger), its Hello
        // would reach a restarted master once the port answers again and be taken for another
        // client, one that never renders.
        if (dealer_) dealer_.set(zmq::sockopt::linger, 0);
        dealer_ = zmq::socket_t(ctx_, zmq::socket_type::dealer);
        // The largest legitimate message from the master is a mesh.
        configureSocket(dealer_, int64_t(kHeaderSize + 64 + kMaxMeshBytes), heartbeatMs_, timeoutMs());
        dealer_.set(zmq::sockopt::reconnect_ivl, 100);
        dealer_.set(zmq::sockopt::reconnect_ivl_max, std::max(100, settings_.maxReconnectMs));
        if (!settings_.keyFile.empty()) {
            dealer_.set(zmq::sockopt::curve_serverkey, serverKey_);
            dealer_.set(zmq::sockopt::curve_publickey, keys_.publicKey);
            dealer_.set(zmq::sockopt::curve_secretkey, keys_.secretKey);
        }
        // The handshake's outcome (a refused key, no CURVE on one side) is said in one line.
        const std::string monitorAddress = "inproc://rtwall-client-monitor-" + std::to_string(++monitorSeq_);
        if (zmq_socket_monitor(dealer_.handle(), monitorAddress.c_str(),
                               ZMQ_EVENT_HANDSHAKE_FAILED_AUTH | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                                   ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_SUCCEEDED) == 0) {
            monitor_ = zmq::socket_t(ctx_, zmq::socket_type::pair);
            monitor_.set(zmq::sockopt::linger, 0);
            monitor_.connect(monitorAddress);
        }
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

    // The master's peer timeout, from its Welcome (before the first Welcome: the default).
    int timeoutMs() const { return timeoutMs_; }

    Header header(MsgType type, uint32_t frame = 0) const { return header(type, frame, stateSeq_); }
    Header header(MsgType type, uint32_t frame, uint32_t stateSeq) const {
        Header h;
        h.type = type;
        h.session = session_.load();
        h.frame = frame;
        h.sceneVersion = stateSeq;
        return h;
    }

    template <class Msg> void send(const Msg& msg, uint32_t frame = 0) {
        sendNow(dealer_, encodeMessage(header(messageTypeOf(msg), frame), msg));
        lastSent_ = nowSeconds();
    }

    int networkLoop() {
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
    void forwardResults(int max) {
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


    // ---- display nodes (issue 19) ----------------------------------------------------------

    // One DEALER per node of the master's list (CURVE with the node's server key when this
    // client has keys); kept while the node's endpoint and key stay the same. ZMQ_IMMEDIATE: a
    // tile for a node that is not connected is dropped, never queued for a dead peer.
    void onNodeList(const NodeList& list) {
        std::map<uint32_t, NodeLink> next;
        for (const NodeEndpoint& e : list.nodes) {
            auto old = nodeLinks_.find(e.node);
            if (old != nodeLinks_.end() && old->second.endpoint == e.endpoint && old->second.serverKey == e.serverKey) {
                next.emplace(e.node, std::move(old->second));
                continue;
            }
            if (!settings_.keyFile.empty() && e.serverKey.empty()) {
                // Behind CURVE, pixels never go in the clear.
                std::fprintf(stderr, "rtwall client %u: display node '%s' at %s has no CURVE key: its tiles are not sent\n", id_,
                             e.name.c_str(), e.endpoint.c_str());
                continue;
            }
            NodeLink link{e.endpoint, e.serverKey, zmq::socket_t(ctx_, zmq::socket_type::dealer), e.name, {}, false};
            link.socket.set(zmq::sockopt::linger, 0);
            link.socket.set(zmq::sockopt::immediate, 1);
            link.socket.set(zmq::sockopt::sndhwm, 1000);
            link.socket.set(zmq::sockopt::reconnect_ivl, 100);
            if (!settings_.keyFile.empty() && !e.serverKey.empty()) {
                link.socket.set(zmq::sockopt::curve_serverkey, e.serverKey);
                link.socket.set(zmq::sockopt::curve_publickey, keys_.publicKey);
                link.socket.set(zmq::sockopt::curve_secretkey, keys_.secretKey);
                // A node that refuses this client's key is said once (readNodeMonitors).
                const std::string monitorAddress = "inproc://rtwall-client-node-monitor-" + std::to_string(++monitorSeq_);
                if (zmq_socket_monitor(link.socket.handle(), monitorAddress.c_str(),
                                       ZMQ_EVENT_HANDSHAKE_FAILED_AUTH | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                                           ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL) == 0) {
                    link.monitor = zmq::socket_t(ctx_, zmq::socket_type::pair);
                    link.monitor.set(zmq::sockopt::linger, 0);
                    link.monitor.connect(monitorAddress);
                }
            }
            try {
                link.socket.connect(e.endpoint);
            } catch (const zmq::error_t& err) {
                std::fprintf(stderr, "rtwall client %u: cannot connect to display node '%s' at %s: %s\n", id_, e.name.c_str(),
                             e.endpoint.c_str(), err.what());
                continue;
            }
            next.emplace(e.node, std::move(link));
        }
        nodeLinks_ = std::move(next);  // links of nodes no longer listed close here
    }

    // Handshake failures of the links to the nodes, each said once per link.
    void readNodeMonitors() {
        for (auto& [node, link] : nodeLinks_) {
            if (!link.monitor) continue;
            for (int i = 0; i < 8; ++i) {
                zmq::message_t event, address;
                if (!link.monitor.recv(event, zmq::recv_flags::dontwait)) break;
                if (!event.more() || !link.monitor.recv(address, zmq::recv_flags::dontwait) || event.size() < 6) continue;
                discardRestOf(link.monitor, address);
                uint16_t id;
                uint32_t value;
                std::memcpy(&id, event.data(), 2);
                std::memcpy(&value, static_cast<const uint8_t*>(event.data()) + 2, 4);
                if (settings_.counters) ++(id == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH ? settings_.counters->refusedHandshakes
                                                                                 : settings_.counters->failedHandshakes);
                if (link.said) continue;
                link.said = true;
                if (id == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH)
                    std::fprintf(stderr, "rtwall client %u: display node '%s' at %s refused this client's key %s (status %u): "
                                         "it takes the keys the master gives it\n",
                                 id_, link.name.c_str(), link.endpoint.c_str(), keys_.publicKey.c_str(), value);
                else
                    std::fprintf(stderr, "rtwall client %u: the CURVE handshake with display node '%s' at %s failed (event %u, "
                                         "value %u)\n", id_, link.name.c_str(), link.endpoint.c_str(), unsigned(id), value);
            }
        }
    }

    // The masks for frames from routes.frame on; the previous set stays for the results of
    // earlier frames still on their way (async frames overlap by one).
    void onTileRoutes(TileRoutes routes) {
        const uint32_t from = routes.frame;
        tileRoutes_[from] = std::move(routes.masks);
        while (tileRoutes_.size() > 2) tileRoutes_.erase(tileRoutes_.begin());
    }

    // A finished tile (an encoded TileResult) goes to every node of its mask, then a TileDone
    // to the master. Nothing blocks: a node whose queue is full or that is not connected misses
    // the tile (and is left out of that frame's swap).
    void sendToNodes(const zmq::message_t& msg) {
        const auto* bytes = static_cast<const uint8_t*>(msg.data());
        if (msg.size() < kHeaderSize) return;
        TileResultInfo info;
        try {
            info = peekTileResult(bytes + kHeaderSize, msg.size() - kHeaderSize);  // written by this client itself
        } catch (const DecodeError&) {
            return;
        }
        const uint32_t frame = info.frame, tile = info.tile;
        auto routes = tileRoutes_.upper_bound(frame);
        if (routes == tileRoutes_.begin()) return;  // no masks for a frame this old
        const std::vector<uint64_t>& masks = std::prev(routes)->second;
        if (tile >= masks.size()) return;
        for (auto& [node, link] : nodeLinks_) {
            if (!(masks[tile] >> node & 1)) continue;
            zmq::message_t copy(msg.data(), msg.size());
            if (!link.socket.send(copy, zmq::send_flags::dontwait)) ++lostResults_;
        }
        send(TileDone{frame, tile, info.renderMicros, info.pixelBytes}, frame);
    }

    // Returns an exit status when the client should stop.
    std::optional<int> handle(const zmq::message_t& msg) {
        const auto* bytes = static_cast<const uint8_t*>(msg.data());
        try {
            const Header h = decodeHeader(bytes, msg.size());
            const uint8_t* p = bytes + kHeaderSize;
            const size_t n = msg.size() - kHeaderSize;
            if (h.version != kProtocolVersion) {
                std::fprintf(stderr, "rtwall client: the master speaks protocol version %u, this client %u\n",
                             unsigned(h.version), unsigned(kProtocolVersion));
                return 1;
            }
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

    std::shared_ptr<const TriangleMesh> localMesh(const MeshRef& ref) {
        if (auto it = meshes_.find(ref.hash); it != meshes_.end()) return it->second;
        std::vector<std::filesystem::path> candidates;
        if (!ref.source.empty() && !ref.source.starts_with("shape:")) candidates.push_back(ref.source);
        if (!settings_.cacheDir.empty()) candidates.push_back(settings_.cacheDir / (hexOf(ref.hash) + ".rtmesh"));
        for (const auto& path : candidates) {
            std::error_code ec;
            if (!std::filesystem::is_regular_file(path, ec)) continue;
            try {
                std::vector<uint8_t> bytes;
                if (path.extension() == ".rtmesh") {
                    std::ifstream in(path, std::ios::binary);
                    bytes.assign(std::istreambuf_iterator<char>(in), {});
                } else {
                    bytes = encodeMesh(loadMesh(path));
                }
                if (hashBytes(bytes.data(), bytes.size()) != ref.hash) continue;  // a different file: not trusted
                auto mesh = std::make_shared<const TriangleMesh>(decodeMesh(bytes.data(), bytes.size()));
                meshes_[ref.hash] = mesh;
                return mesh;
            } catch (const std::exception&) {
                continue;  // unreadable or stale: fetch it from the master instead
            }
        }
        return nullptr;
    }

    // A texture or volume file by content hash: from memory, the material's path on this PC or
    // the cache, each used only when its bytes have the hash (another file of the same name is
    // not trusted).
    std::shared_ptr<const std::vector<uint8_t>> localAsset(const AssetRef& ref) {
        if (auto it = assets_.find(ref.hash); it != assets_.end()) return it->second;
        std::vector<std::filesystem::path> candidates{ref.path};
        if (!settings_.cacheDir.empty()) candidates.push_back(settings_.cacheDir / (hexOf(ref.hash) + ".rtasset"));
        for (const auto& path : candidates) {
            std::error_code ec;
            if (!std::filesystem::is_regular_file(path, ec)) continue;
            const auto size = std::filesystem::file_size(path, ec);
            if (ec || size != ref.bytes) continue;  // also bounds what is read (ref.bytes <= kMaxAssetBytes)
            auto bytes = std::make_shared<std::vector<uint8_t>>(size_t(size));
            std::ifstream in(path, std::ios::binary);
            if (!in.read(reinterpret_cast<char*>(bytes->data()), std::streamsize(size))) continue;
            if (hashBytes(bytes->data(), bytes->size()) != ref.hash) continue;
            assets_[ref.hash] = bytes;
            if (settings_.counters) ++settings_.counters->assetsLocal;
            return bytes;
        }
        return nullptr;
    }

    // Files that an update's material change names: fetched as soon as the update arrives (it
    // comes before the frame that needs it), unless this PC has the same bytes.
    void fetchFilesOf(const Update& u) {
        for (const Change& c : u.changes)
            if (auto* m = std::get_if<MaterialChange>(&c))
                for (const AssetRef& ref : m->files) {
                    if (assets_.count(ref.hash) || updateFiles_.count(ref.hash)) continue;
                    updateFiles_[ref.hash] = ref;
                    if (!localAsset(ref)) send(AssetRequest{ref.hash});
                }
    }
    // A new connection or session: files still on their way may never come (what arrived stays,
    // by hash).
    void forgetPendingFiles() {
        std::erase_if(updateFiles_, [&](const auto& e) { return !assets_.count(e.first); });
        deferredFrame_.reset();
        blockedFrame_.reset();
    }
    bool updateFilesMissing() const {
        for (const auto& [hash, ref] : updateFiles_)
            if (!assets_.count(hash)) return true;
        return false;
    }

    void onAssetData(AssetData ad) {
        const AssetRef* ref = nullptr;
        if (snapshot_)
            for (const AssetRef& a : snapshot_->assets)
                if (a.hash == ad.hash) ref = &a;
        if (auto it = updateFiles_.find(ad.hash); !ref && it != updateFiles_.end()) ref = &it->second;
        if (!ref || assets_.count(ad.hash)) {
            drop();  // not asked for by this state, or already here
            return;
        }
        if (ad.bytes.size() != ref->bytes || hashBytes(ad.bytes.data(), ad.bytes.size()) != ad.hash) {
            ++dropped_;
            if (settings_.counters) ++settings_.counters->rejectedAssets;
            std::fprintf(stderr, "rtwall client %u: %s: %zu bytes from the master do not match the file's hash %s: rejected\n",
                         id_, ref->path.c_str(), ad.bytes.size(), hexOf(ad.hash).c_str());
            return;
        }
        auto bytes = std::make_shared<const std::vector<uint8_t>>(std::move(ad.bytes));
        assets_[ad.hash] = bytes;
        if (settings_.counters) ++settings_.counters->assetsReceived;
        if (!settings_.cacheDir.empty()) {
            std::error_code ec;
            std::filesystem::create_directories(settings_.cacheDir, ec);
            const auto path = settings_.cacheDir / (hexOf(ad.hash) + ".rtasset");
            const auto tmp = path.string() + ".tmp";
            std::ofstream(tmp, std::ios::binary).write(reinterpret_cast<const char*>(bytes->data()), std::streamsize(bytes->size()));
            std::filesystem::rename(tmp, path, ec);
        }
        tryBuildScene();
        if (deferredFrame_ && !updateFilesMissing()) {  // the frame that waited for this file
            const FrameBegin fb = *deferredFrame_;
            deferredFrame_.reset();
            onFrameBegin(fb);
        }
    }

    void onSnapshot(SceneSnapshot snap) {
        // Within a session the master's states to one client never go back in time (it sends
        // the current frame's state): one older than what this client holds is a replay.
        if (snapshot_ && snap.updateSeq < stateSeq_) {
            drop();
            return;
        }
        dropWork();
        ready_ = false;
        ++buildGeneration_;
        snapshot_ = std::move(snap);
        updates_.reset(snapshot_->updateSeq);
        for (const MeshRef& ref : snapshot_->meshes)
            if (!localMesh(ref)) send(MeshRequest{ref.hash});
        for (const AssetRef& ref : snapshot_->assets)
            if (!localAsset(ref)) send(AssetRequest{ref.hash});
        tryBuildScene();
    }

    void onMeshData(MeshData md) {
        if (hashBytes(md.mesh.data(), md.mesh.size()) != md.hash) {
            drop();
            return;
        }
        meshes_[md.hash] = std::make_shared<const TriangleMesh>(decodeMesh(md.mesh.data(), md.mesh.size()));
        if (!settings_.cacheDir.empty()) {
            std::error_code ec;
            std::filesystem::create_directories(settings_.cacheDir, ec);
            const auto path = settings_.cacheDir / (hexOf(md.hash) + ".rtmesh");
            const auto tmp = path.string() + ".tmp";
            std::ofstream(tmp, std::ios::binary).write(reinterpret_cast<const char*>(md.mesh.data()), std::streamsize(md.mesh.size()));
            std::filesystem::rename(tmp, path, ec);
        }
        tryBuildScene();
    }

    // Builds the scene (Embree's BVH: seconds for millions of triangles on a slow PC) on its own
    // thread, so that this thread keeps reading and sending heartbeats: a joining client that
    // went silent for longer than the master's timeout would be dropped and, rejoining, build
    // again, never getting in.
    void tryBuildScene() {
        if (!snapshot_ || ready_ || building_.valid() || built_) return;  // a stale build is redone when it ends
        std::optional<SceneDesc> desc = sceneOf(*snapshot_, meshes_, assets_);
        if (!desc) return;  // still waiting for a mesh, texture or volume
        building_ = std::async(std::launch::async, [desc = std::move(*desc), delay = faults_.extraSceneBuildMs] {
            if (delay > 0) std::this_thread::sleep_for(std::chrono::milliseconds(delay));
            return std::make_unique<Scene>(desc);
        });
        buildingFor_ = buildGeneration_;
    }

    // Installs a finished build if it is still for the current snapshot, and proves the state.
    // The scene is swapped only while no render thread is inside the old one; one that is stuck
    // there must not block this thread, so the built scene waits and the swap is tried again.
    void finishBuild() {
        if (!built_) {
            if (!building_.valid() || building_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
            try {
                built_ = building_.get();
            } catch (const std::exception& e) {
                std::lock_guard lock(workMutex_);
                failure_ = std::string("cannot use the master's scene: ") + e.what();
                return;
            }
        }
        if (buildingFor_ != buildGeneration_ || !snapshot_) {  // another snapshot came meanwhile
            built_.reset();
            tryBuildScene();
            return;
        }
        std::unique_lock lock(sceneMutex_, std::chrono::milliseconds(20));
        if (!lock.owns_lock()) return;
        const Hash128 hash = stateHash(*snapshot_);
        scene_ = std::move(built_);
        setRenderSettings(snapshot_->settings);
        stateSeq_ = snapshot_->updateSeq;
        lock.unlock();
        ready_ = true;
        send(Ready{stateSeq_, hash});
    }

    // The master's settings plus what is this client's own (under sceneMutex_).
    void setRenderSettings(const RenderSettings& fromMaster) {
        renderSettings_ = fromMaster;
        renderSettings_.threads = 1;  // each render thread renders its own tiles
        trace_.clientId = id_;  // the id the master gave us, for the client false-colour view
        trace_.packetWidth = settings_.packetWidth;  // this PC's CPU decides
        trace_.fault = faults_.tileFault ? injectFault(*faults_.tileFault) : nullptr;
    }

    void requestResync() {
        ready_ = false;
        send(ResyncRequest{stateSeq_});
    }

    // Applies the buffered updates up to `seq`. CannotRender: an update is missing (a resync is
    // requested) or our state is already newer. Busy: a render thread is still inside the scene
    // (a stuck one holds it for good); the frame is tried again later, this thread never waits.
    enum class CatchUp { Done, CannotRender, Busy };
    CatchUp catchUp(uint32_t seq) {
        if (seq == updates_.state()) return CatchUp::Done;
        if (seq < updates_.state()) return CatchUp::CannotRender;
        std::unique_lock lock(sceneMutex_, std::chrono::milliseconds(20));
        if (!lock.owns_lock()) return CatchUp::Busy;
        std::vector<Update> ups;
        if (updates_.catchUp(seq, ups) != UpdateSequencer::CatchUp::Ready) {
            lock.unlock();
            requestResync();
            return CatchUp::CannotRender;
        }
        for (const Update& u : ups)
            for (const Change& c : u.changes) std::visit([this](const auto& change) { apply(change); }, c);
        scene_->commit();
        stateSeq_ = seq;
        return CatchUp::Done;
    }

    // A change to the engine scene (under sceneMutex_). What each change writes is
    // scene_state.h's; these are the engine's differential calls for it, one per kind of change
    // (a new kind fails to compile in catchUp's std::visit until it has one).
    void apply(const TransformChange& c) { scene_->setInstanceTransform(c.instance, c.transform); }
    void apply(const VisibilityChange& c) { scene_->setInstanceVisibility(c.instance, c.visibility); }
    void apply(const MaterialChange& c) {
        for (const AssetRef& ref : c.files) scene_->addFile(ref.path, assets_.at(ref.hash));
        scene_->setMaterial(c.material, c.value);
    }
    void apply(const LightChange& c) { scene_->setLight(c.light, c.value); }
    void apply(const SettingsChange& c) { setRenderSettings(c.settings); }
    void apply(const SectionChange& c) { scene_->setSection(c.section, c.value); }

    void onFrameBegin(const FrameBegin& fb) {
        // Frames only move forward. An older FrameBegin, or the one being rendered again, is a
        // replay: obeying it would throw away the work in progress. (The master repeats the
        // current frame's FrameBegin after a resync, when this client renders nothing.)
        if (fb.frame < lastFrameBegun_ || (fb.frame != 0 && fb.frame == frame_.load())) {
            drop();
            return;
        }
        dropWork();
        deferredFrame_.reset();
        blockedFrame_.reset();
        if (ready_ && updateFilesMissing()) {  // a changed material's file is on its way
            deferredFrame_ = fb;
            return;
        }
        if (!ready_) return;
        switch (catchUp(fb.updateSeq)) {
        case CatchUp::CannotRender: return;
        case CatchUp::Busy:
            blockedFrame_ = fb;
            if (blockedSince_ == 0) blockedSince_ = nowSeconds();
            return;
        case CatchUp::Done: break;
        }
        blockedSince_ = 0;
        blockedLogged_ = false;
        framePixels_ = fb.pixels;
        // At the state's resolution and tile size, which catchUp just brought to the frame's.
        auto layout = std::make_shared<FrameLayout>();
        for (const FrameView& v : fb.views) layout->cameras.push_back(v.camera);
        layout->tiles = viewTiles(fb.views, renderSettings_.width, renderSettings_.height, renderSettings_.tileSize);
        frameLayout_ = std::move(layout);
        frame_.store(fb.frame);
        lastFrameBegun_ = fb.frame;
        send(TileRequest{fb.frame, prefetch_}, fb.frame);
    }

    void onAssign(const TileAssign& a) {
        // Every tile the master sent for a frame counts as seen, used or not: the heartbeat's
        // tilesSeen tells the master that nothing it sent is still on its way.
        if (a.frame > assignFrame_) {
            assignFrame_ = a.frame;
            assignSeen_ = 0;
        }
        if (a.frame == assignFrame_) assignSeen_ += uint32_t(a.tiles.size());
        if (!ready_ || a.frame != frame_.load()) {
            drop();
            return;
        }
        size_t queued = 0;
        {
            std::lock_guard lock(workMutex_);
            for (uint32_t t : a.tiles) {
                if (work_.size() >= kMaxQueuedTiles) break;
                work_.push_back({a.frame, t, stateSeq_, codec_, framePixels_, frameLayout_});
                ++queued;
            }
            held_ += int64_t(queued);
        }
        if (queued < a.tiles.size() && settings_.counters) settings_.counters->droppedAssignments += a.tiles.size() - queued;
        workCv_.notify_all();
    }

    void dropWork() {
        std::lock_guard lock(workMutex_);
        held_ -= int64_t(work_.size());
        work_.clear();
        frame_.store(0);
    }

    void drop() {
        ++dropped_;
        if (settings_.counters) ++settings_.counters->droppedMessages;
    }

    // A render thread far past its expected time on a tile of the current frame is reported
    // (once per tile): the master hands the tile to another client, or to this one's other
    // threads. "Expected": 16 times this client's mean tile time, at least minStallMs.
    void watchStalls() {
        const uint64_t timed = tilesTimed_.load();
        const double meanNs = timed ? double(tileNs_.load()) / double(timed) : 0.0;
        const int64_t threshold = std::max<int64_t>(int64_t(settings_.minStallMs) * 1'000'000, int64_t(16.0 * meanNs));
        const int64_t now = steadyNs();
        for (int i = 0; i < threads_; ++i) {
            Slot& slot = slots_[size_t(i)];
            const int64_t start = slot.startNs.load();
            if (start == 0 || start == slot.reportedStartNs || now - start < threshold) continue;
            const uint64_t job = slot.job.load();
            if (slot.startNs.load() != start) continue;  // it moved on meanwhile
            slot.reportedStartNs = start;
            const uint32_t frame = uint32_t(job >> 32), tile = uint32_t(job);
            const uint32_t ms = uint32_t(std::min<int64_t>((now - start) / 1'000'000, UINT32_MAX));
            std::fprintf(stderr, "rtwall client %u: render thread %d has been on frame %u, tile %u for %u ms (mean tile %.1f ms): "
                         "reported to the master\n", id_, i, frame, tile, ms, meanNs * 1e-6);
            if (settings_.counters) ++settings_.counters->stalledTiles;
            if (session_.load()) send(TileStalled{frame, tile, ms});
        }
    }

    // Handshake events of the connection to the master: a refusal is said, not just "no master".
    void readMonitor() {
        for (int i = 0; i < 16; ++i) {
            zmq::message_t event, address;
            if (!monitor_.recv(event, zmq::recv_flags::dontwait)) return;
            if (!event.more() || !monitor_.recv(address, zmq::recv_flags::dontwait) || event.size() < 6) continue;
            discardRestOf(monitor_, address);
            uint16_t id;
            uint32_t value;
            std::memcpy(&id, event.data(), 2);
            std::memcpy(&value, static_cast<const uint8_t*>(event.data()) + 2, 4);
            std::string why;
            if (id == ZMQ_EVENT_HANDSHAKE_SUCCEEDED) {
                handshakeTrouble_.clear();
                handshakeFailures_ = 0;
                continue;
            }
            if (id == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) {
                if (settings_.counters) ++settings_.counters->refusedHandshakes;
                why = "the master refused this client's key (status " + std::to_string(value) + "): is " +
                      (keys_.publicKey.empty() ? std::string("its key") : keys_.publicKey) + " in the master's client_keys?";
            } else {
                if (settings_.counters) ++settings_.counters->failedHandshakes;
                if (id == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL && value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH)
                    why = "the master and this client disagree on security: one uses CURVE keys, the other not";
                else if (id == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL)
                    why = "the handshake failed (ZMTP protocol error " + std::to_string(value) + ")";
                else
                    // The master closes the connection as soon as it sees the other mechanism, and
                    // its greeting may be lost with the reset: keyless, this is the likely cause.
                    why = settings_.keyFile.empty()
                              ? "the master broke off the handshake: do the master and this client disagree on security "
                                "(a master with CURVE keys needs --key and --server-key here)?"
                              : "the master broke off the CURVE handshake: is --server-key its public key?";
            }
            if (why != handshakeTrouble_)
                std::fprintf(stderr, "rtwall client: %s: %s\n", settings_.connect.c_str(), why.c_str());
            handshakeTrouble_ = why;
            ++handshakeFailures_;
        }
    }

    std::string handshakeNote() const {
        if (handshakeTrouble_.empty()) return {};
        return " (" + handshakeTrouble_ + "; " + std::to_string(handshakeFailures_) + " failed handshake" +
               (handshakeFailures_ == 1 ? "" : "s") + ")";
    }

    // Replay mode (benchmarks of the master and the link): a tile rendered once is sent again
    // from memory, so the client costs next to nothing. Valid only while the view is still.
    bool replaySend(zmq::socket_t& out, const Work& w) {
        TileResult result;
        {
            std::lock_guard lock(replayMutex_);
            auto it = replay_.find(w.tile);
            if (it == replay_.end()) return false;
            result.codec = it->second.first;
            result.pixels = it->second.second;  // renderMicros stays 0: a replay costs no rendering
        }
        result.frame = w.frame;
        result.tile = w.tile;
        const std::vector<uint8_t> bytes = encodeMessage(header(MsgType::TileResult, w.frame, w.stateSeq), result);
        sendResult(out, bytes);
        return true;
    }

    // Render threads hand results to the network thread without blocking either: with its queue
    // full (the master reads slowly and the network thread's own queue is full too) the result
    // is dropped and counted, and the master re-issues the tile as a straggler.
    void sendResult(zmq::socket_t& out, const std::vector<uint8_t>& bytes) {
        if (!sendNow(out, bytes)) {
            ++droppedResults_;
            --held_;
        }
    }

    // The injected stall (ClientFaults::stallMs): once, cut short when the client stops.
    void maybeStall(uint32_t frame) {
        if (faults_.stallMs <= 0 || frame < faults_.stallFrame || stallInjected_.exchange(true)) return;
        const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(faults_.stallMs);
        while (std::chrono::steady_clock::now() < end && !stopRequested_.load())
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }

    std::string failure() {
        std::lock_guard lock(workMutex_);
        return failure_;
    }
    std::optional<TileFailed> failedTile() {
        std::lock_guard lock(workMutex_);
        return failedTile_;
    }

    // ---- render threads -------------------------------------------------------------------

    void workerLoop(Slot& slot) {
        pthread_setname_np(pthread_self(), "rtw-render");  // rtwall bench cluster attributes CPU time by thread name
        zmq::socket_t out(ctx_, zmq::socket_type::push);
        out.set(zmq::sockopt::linger, 0);
        out.connect(kResultsAddress);
        std::vector<uint8_t> pixels, scratch;
        std::vector<float> linear;
        for (;;) {
            Work w;
            {
                std::unique_lock lock(workMutex_);
                workCv_.wait(lock, [&] { return stopping_ || !work_.empty(); });
                if (stopping_) return;
                w = work_.front();
                work_.pop_front();
            }
            const CodecSettings& codec = w.codec;
            const bool wide = w.pixels == TilePixels::LinearHalf;
            try {
                std::shared_lock lock(sceneMutex_);
                if (w.frame != frame_.load() || !scene_ || !w.layout || w.tile >= w.layout->tiles.size()) {  // stale or bogus
                    --held_;
                    continue;
                }
                if (settings_.replay && !wide && replaySend(out, w)) continue;
                // A view's tile renders as it would in a frame of that view's camera alone.
                const TileRect r = w.layout->tiles[w.tile].rect;
                const CameraDesc& cameraDesc = w.layout->cameras[w.layout->tiles[w.tile].view];
                const auto t0 = std::chrono::steady_clock::now();
                // For the stall watch (watchStalls): this thread is on this tile since now.
                slot.job.store(uint64_t(w.frame) << 32 | w.tile);
                slot.startNs.store(steadyNs());
                const Camera camera(cameraDesc, renderSettings_.width, renderSettings_.height);
                if (wide) {
                    // Part of an accumulation: linear, before the 8-bit quantisation.
                    linear.resize(size_t(r.width()) * r.height() * 3);
                    renderTileLinear(*scene_, camera, r, w.frame, renderSettings_, linear.data(), size_t(r.width()) * 3, trace_);
                } else {
                    pixels.resize(size_t(r.width()) * r.height() * 3);
                    renderTile(*scene_, camera, r, w.frame, renderSettings_, {pixels.data(), size_t(r.width()) * 3}, trace_);
                }
                if (faults_.extraTileDelayMs > 0)
                    std::this_thread::sleep_for(std::chrono::milliseconds(faults_.extraTileDelayMs));
                maybeStall(w.frame);
                slot.startNs.store(0);
                const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                tileNs_ += uint64_t(seconds * 1e9);
                ++tilesTimed_;
                TileResult result;
                result.frame = w.frame;
                result.tile = w.tile;
                result.renderMicros = uint32_t(std::min(seconds * 1e6, 4e9));
                if (wide) {
                    result.codec = wideCodec(codec.codec);
                    result.format = TilePixels::LinearHalf;
                    encodeWideTile(codec, linear.data(), r.width(), r.height(), size_t(r.width()) * 3, scratch, result.pixels);
                } else {
                    result.codec = codec.codec;
                    encodeTile(codec, pixels.data(), r.width(), r.height(), size_t(r.width()) * 3, result.pixels);
                }
                if (settings_.replay && !wide) {
                    std::lock_guard replayLock(replayMutex_);
                    replay_[w.tile] = {codec.codec, result.pixels};
                }
                const std::vector<uint8_t> bytes = encodeMessage(header(MsgType::TileResult, w.frame, w.stateSeq), result);
                sendResult(out, bytes);
            } catch (const TileError& e) {
                // Tell the master why before going away (the network thread sends it): the
                // frame, the tile's number and pixels, and what went wrong.
                const TileRect& r = e.rect();
                std::lock_guard lock(workMutex_);
                if (failure_.empty()) {
                    failure_ = "frame " + std::to_string(e.frame()) + ", tile " + std::to_string(w.tile) + " (pixels " +
                               std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.x1) + "," +
                               std::to_string(r.y1) + "): " + e.reason();
                    // The width this thread traced with (0 asks for this CPU's widest).
                    const int width = settings_.packetWidth != 0 ? settings_.packetWidth : packetWidth();
                    failedTile_ = TileFailed{e.frame(), w.tile, r, width, e.reason().substr(0, kMaxStringBytes)};
                }
                return;
            } catch (const std::exception& e) {
                std::lock_guard lock(workMutex_);
                if (failure_.empty())
                    failure_ = "frame " + std::to_string(w.frame) + ", tile " + std::to_string(w.tile) + ": " + e.what();
                return;
            }
        }
    }

    ClientSettings settings_;
    const ClientFaults faults_;  // none outside tests
    KeyPair keys_;
    std::string serverKey_;
    int threads_ = 1;
    zmq::context_t ctx_{1};
    zmq::socket_t dealer_;
    zmq::socket_t results_{ctx_, zmq::socket_type::pull};

    std::atomic<uint64_t> session_{0};  // read by render threads when they write results
    uint32_t id_ = 0;
    CodecSettings codec_;  // network thread only (Master::setCodec changes it mid-session); copied into each Work
    TilePixels framePixels_ = TilePixels::Srgb8;  // the current frame's tile format, copied into each Work
    uint32_t prefetch_ = 4;
    int heartbeatMs_ = 250;
    int timeoutMs_ = 3000;
    uint32_t lastFrameBegun_ = 0;  // this session's newest FrameBegin
    double lastHeard_ = 0, lastSent_ = 0;
    bool reconnectRequested_ = false;
    int backoffMs_ = 100;  // next reconnection pause (jittered), doubled up to maxReconnectMs
    uint64_t dropped_ = 0;
    std::atomic<uint64_t> droppedResults_{0};
    uint64_t lostResults_ = 0;  // results the connection did not take (its queue to the master full)
    uint64_t resultsOut_ = 0;   // for ClientFaults::dropEveryNthResult
    // Tiles this client holds: queued, being rendered, or rendered and not yet handed to the
    // master's connection. 0 = idle (Heartbeat::idle).
    std::atomic<int64_t> held_{0};
    uint32_t assignFrame_ = 0;  // the newest frame it was assigned tiles for
    uint32_t assignSeen_ = 0;   // tiles of that frame's assignments that arrived
    zmq::socket_t monitor_;     // handshake events of dealer_
    struct NodeLink {
        std::string endpoint, serverKey;
        zmq::socket_t socket;
        std::string name;
        zmq::socket_t monitor;  // handshake events of socket (with CURVE)
        bool said = false;      // its handshake trouble was said
    };
    std::map<uint32_t, NodeLink> nodeLinks_;  // display nodes by index (bit in the tile masks)
    std::map<uint32_t, std::vector<uint64_t>> tileRoutes_;  // tile masks by their first frame; empty: no nodes
    uint64_t monitorSeq_ = 0;
    std::string handshakeTrouble_;  // the last failed handshake, said when giving up
    uint64_t handshakeFailures_ = 0;
    std::unique_ptr<Slot[]> slots_;  // one per render thread
    std::atomic<uint64_t> tileNs_{0}, tilesTimed_{0};  // render time of this client's tiles, for "expected"
    std::atomic<bool> stallInjected_{false};
    std::atomic<bool> stopRequested_{false};
    std::string failure_;  // guarded by workMutex_
    std::optional<TileFailed> failedTile_;  // the tile behind failure_, when the engine said which (workMutex_)

    std::optional<SceneSnapshot> snapshot_;
    std::future<std::unique_ptr<Scene>> building_;  // the scene for a snapshot, being built
    uint64_t buildGeneration_ = 0;  // bumped by every snapshot (and reconnect): older builds are stale
    uint64_t buildingFor_ = 0;
    std::map<Hash128, std::shared_ptr<const TriangleMesh>> meshes_;
    std::map<Hash128, std::shared_ptr<const std::vector<uint8_t>>> assets_;  // texture and volume files
    std::map<Hash128, AssetRef> updateFiles_;  // files named by updates' material changes
    std::shared_ptr<const FrameLayout> frameLayout_;  // the current frame's (network thread)
    std::optional<FrameBegin> deferredFrame_;  // a frame waiting for one of them
    std::optional<FrameBegin> blockedFrame_;   // a frame whose updates wait for the render threads to leave the scene
    double blockedSince_ = 0;
    bool blockedLogged_ = false;
    std::unique_ptr<Scene> built_;             // a finished build waiting for the same
    UpdateSequencer updates_;
    bool ready_ = false;
    uint32_t stateSeq_ = 0;  // network thread only; render threads get it in each Work

    // Shared with the render threads.
    std::shared_timed_mutex sceneMutex_;  // render threads read; the network thread changes the scene (never waiting long)
    std::unique_ptr<Scene> scene_;
    RenderSettings renderSettings_;
    TraceOptions trace_;  // this client's own: packet width, id, injected fault
    std::atomic<uint32_t> frame_{0};

    std::mutex replayMutex_;
    std::map<uint32_t, std::pair<TileCodec, std::vector<uint8_t>>> replay_;  // tile -> codec, encoded bytes

    std::mutex workMutex_;
    std::condition_variable workCv_;
    std::deque<Work> work_;
    bool stopping_ = false;
    std::vector<std::thread> workers_;
};

}  // namespace

void writeNewKeyPair(const std::filesystem::path& stem) { writeKeyFiles(makeKeyPair(), stem); }

int runClient(const ClientSettings& settings) {
    if (settings.packetWidth != 0 && settings.packetWidth != 4 && settings.packetWidth != 8 && settings.packetWidth != 16)
        throw InputError("packet width " + std::to_string(settings.packetWidth) + ": expected 0 (this CPU's widest), 4, 8 or 16");
    ClientRuntime client(settings);
    return client.run();
}

}  // namespace rtwall
