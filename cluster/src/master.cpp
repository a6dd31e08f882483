// The display master (rtwall/cluster.h): its set-up, the application's waits and its counters.
// What the master does is in the files master_impl.h lists, one per job.
#include "master_impl.h"

#include <pthread.h>
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <stdexcept>

namespace rtwall {

Master::Master(const SceneDesc& scene, const ClusterSettings& settings) : impl_(std::make_unique<Impl>(scene, settings)) {
    Impl& s = *impl_;
    if (scene.cameras.empty()) throw InputError("the scene has no camera");
    if (settings.features > kFeatureAll || (settings.features && !settings.depth))
        throw InputError("features for the denoiser need depth with every tile (and bits 1 to 7)");
    if (settings.warpGrids.size() > kMaxWarpGrids)
        throw InputError(std::to_string(settings.warpGrids.size()) + " warp grids (at most " + std::to_string(kMaxWarpGrids) + ")");
    for (size_t i = 0; i < settings.warpGrids.size(); ++i) {
        const PixelWarp* g = settings.warpGrids[i].get();
        if (!g || g->width < 1 || g->height < 1 || g->width > int(kMaxWarpSide) || g->height > int(kMaxWarpSide) ||
            g->samples.size() != size_t(g->width) * size_t(g->height) || g->samples.size() > kMaxWarpSamples)
            throw InputError("warp grid " + std::to_string(i) + " is empty, too large or not its width times height samples");
    }
    s.app.camera = scene.cameras.front();
    std::random_device rd;
    s.session = (uint64_t(rd()) << 32) ^ rd();
    for (const MeshDesc& md : scene.meshes) s.app.meshRefs.push_back(meshRefOf(md));
    // Texture images and volume files: read once, sent to clients that do not have them.
    for (const Material& m : scene.materials)
        for (const std::string& path : filesNamedBy(m))
            if (!s.findAsset(path)) s.addAsset(readAsset(path, scene.files));
    s.frameState = snapshotOf(s.app.scene, s.app.meshRefs, s.app.assetRefs, s.app.seq);

    // The largest legitimate message a client sends is a result for the largest tile allowed,
    // with its depth.
    const int64_t maxResult = int64_t(maxTileResultBytes());
    if (settings.highWaterMark < 1) throw InputError("the high-water mark must be at least 1 message");
    configureSocket(s.link.router, maxResult, settings.heartbeatMs, settings.timeoutMs, settings.highWaterMark);
    s.link.router.set(zmq::sockopt::router_mandatory, 1);
    checkZmqVersion();
    if (!settings.keyFile.empty()) {
        const KeyPair keys = readKeyPair(settings.keyFile);
        std::vector<std::string> allowed;
        for (const auto& f : settings.clientKeys) allowed.push_back(readPublicKey(f));
        if (allowed.empty() && settings.localClients == 0)
            throw InputError(settings.keyFile.string() + ": a master key needs at least one client key");
        if (settings.localClients > 0 || !settings.displayNodes.names.empty()) {
            // Local clients (and display nodes the session starts on this PC) get a key pair of
            // their own, made for this session: a private directory only this user can enter,
            // removed with the master.
            std::string dir = (std::filesystem::temp_directory_path() / "rtwall-keys-XXXXXX").string();
            if (!mkdtemp(dir.data())) throw InputError(dir + ": cannot make a private directory for the local clients' keys");
            s.link.localKeyDir = dir;
            const KeyPair local = makeKeyPair();
            writeKeyFiles(local, s.link.localKeyDir / "local");
            writePublicKeyFile(keys.publicKey, s.link.localKeyDir / "master.pub");
            allowed.push_back(local.publicKey);
            s.link.localArgs = {"--key", (s.link.localKeyDir / "local.key").string(), "--server-key",
                           (s.link.localKeyDir / "master.pub").string()};
        }
        s.link.allowedKeys = allowed;
        s.link.zap = std::make_unique<ZapHandler>(s.link.ctx, allowed);
        s.link.router.set(zmq::sockopt::zap_domain, "rtwall");
        setCurveServer(s.link.router, keys.secretKey);
    } else {
        const std::string& b = settings.bind;
        const bool loopback = b.starts_with("tcp://127.") || b.starts_with("tcp://localhost:") || b.starts_with("tcp://[::1]:") ||
                              b.starts_with("inproc://") || b.starts_with("ipc://");
        if (!loopback && !settings.insecure)
            throw InputError("refusing to listen on " + b +
                             " without CURVE keys: give the master a key and the clients' public keys, or say --insecure");
        if (!loopback)
            std::fprintf(stderr, "rtwall master: WARNING: listening on %s WITHOUT authentication or encryption "
                                 "(--insecure): anyone who reaches this port can join and read the model\n", b.c_str());
    }
    // Connections that break off in the handshake are counted (MasterCounters::failedHandshakes).
    if (!s.link.monitor.start(s.link.ctx, s.link.router, "inproc://rtwall-master-monitor",
                         ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL))
        throw std::runtime_error(std::string("zmq_socket_monitor: ") + zmq_strerror(zmq_errno()));
    s.link.router.bind(settings.bind);
    s.link.boundEndpoint = s.link.router.get(zmq::sockopt::last_endpoint);
    const std::string wakeAddress = "inproc://rtwall-master-wake";
    s.link.wakeRecv.bind(wakeAddress);
    s.link.wakeSend.connect(wakeAddress);

    const int decodeThreads = std::clamp(int(std::thread::hardware_concurrency()) / 2, 1, 4);
    s.decoder = std::make_unique<DecodePool>(
        s.assembler, decodeThreads,
        [this] {
            impl_->frameDecoded = true;
            impl_->wake();
        },
        [this](uint32_t tile) {
            {
                std::lock_guard lock(impl_->failedMutex);
                impl_->failedTiles.push_back(tile);
            }
            impl_->wake();
        });
    s.net = std::thread([this] {
        pthread_setname_np(pthread_self(), "rtw-net");  // for rtwall bench cluster's CPU split
        try {
            impl_->loop();
        } catch (const std::exception& e) {
            // No thread dies silently: report and let waiting callers fail their timeouts.
            std::fprintf(stderr, "rtwall master: network thread stopped: %s\n", e.what());
        }
    });
}

Master::~Master() {
    Impl& s = *impl_;
    {
        std::lock_guard lock(s.m);
        s.commands.push_back(Command{.kind = Command::kStop});
    }
    s.wake();
    if (s.net.joinable()) s.net.join();
    for (auto& [peer, c] : s.clients)  // a client already gone needs no goodbye (nor a log line)
        sendToPeer(s.link.router, c.peer, encodeMessage(s.header(MsgType::Goodbye), Goodbye{"the master is shutting down"}));
    for (auto& [peer, n] : s.display.nodes)  // display nodes end with the wall instead of waiting for a master that is gone
        if (!n.deathReason) sendToPeer(s.link.router, n.peer, encodeMessage(s.header(MsgType::Goodbye), Goodbye{"the master is shutting down"}));
    s.decoder.reset();
    s.link.monitor.stop(s.link.router);
    s.link.router.close();
    s.link.zap.reset();
}

std::string Master::endpoint() const { return impl_->link.boundEndpoint; }

int Master::connectedClients() const {
    std::lock_guard lock(impl_->m);
    return impl_->readyClients;
}

namespace {

void throwIfStopped(const Master::Impl& s) {
    const std::atomic<bool>* flag = s.stopFlag.load();
    if (flag && flag->load()) throw Cancelled();
}

// Waits (under s.m) until `done` holds: false after timeoutMs without it. A stop flag set
// meanwhile throws Cancelled.
template <class Done> bool waitUntil(Master::Impl& s, int timeoutMs, Done done) {
    std::unique_lock lock(s.m);
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeoutMs);
    while (!done()) {
        throwIfStopped(s);
        const auto now = std::chrono::steady_clock::now();
        if (now >= end) return false;
        s.cv.wait_for(lock, std::min<std::chrono::steady_clock::duration>(end - now, std::chrono::milliseconds(100)));
    }
    return true;
}

}  // namespace

bool Master::waitForClients(int count, int timeoutMs) {
    return waitUntil(*impl_, timeoutMs, [&] { return impl_->readyClients >= count; });
}

bool Master::waitForSwap(uint32_t frame, int timeoutMs) {
    return waitUntil(*impl_, timeoutMs, [&] { return impl_->swapReleased >= frame; });
}

void Master::presentPose(std::span<const CameraDesc> cameras, bool debug, std::optional<std::array<Float3, 2>> roomEyes) {
    if (!impl_->settings.displayNodes.reproject)
        throw std::logic_error("Master::presentPose on a master whose display nodes do not re-project");
    if (cameras.empty() || cameras.size() > kMaxViews)
        throw std::invalid_argument("Master::presentPose: " + std::to_string(cameras.size()) + " cameras (1 to " +
                                    std::to_string(kMaxViews) + ", one per view)");
    {
        std::lock_guard lock(impl_->poseMutex);
        PendingPose& p = impl_->pendingPose.emplace();
        p.cameras.assign(cameras.begin(), cameras.end());
        for (CameraDesc& c : p.cameras) c.name.clear();  // the nodes need the geometry only
        p.debug = debug;
        p.roomEyes = roomEyes;
        p.askedAt = nowSeconds();
    }
    impl_->wake();
}

std::vector<NodeRefreshDelay> Master::takeNodeRefreshes() {
    std::lock_guard lock(impl_->poseMutex);
    std::vector<NodeRefreshDelay> out(impl_->nodeRefreshes.begin(), impl_->nodeRefreshes.end());
    impl_->nodeRefreshes.clear();
    return out;
}

int Master::awaitClients(int wanted, int timeoutMs, int settleMs) {
    Impl& s = *impl_;
    std::unique_lock lock(s.m);
    const auto start = std::chrono::steady_clock::now(), end = start + std::chrono::milliseconds(timeoutMs);
    int seen = s.readyClients;
    auto lastJoin = start;
    while (s.readyClients < wanted) {
        throwIfStopped(s);
        const auto now = std::chrono::steady_clock::now();
        if (s.readyClients != seen) {
            seen = s.readyClients;
            lastJoin = now;
        }
        if (now >= end || (seen > 0 && now - lastJoin >= std::chrono::milliseconds(settleMs))) break;
        s.cv.wait_for(lock, std::chrono::milliseconds(100));
    }
    return s.readyClients;
}

std::vector<std::string> Master::displayNodesPresent() const {
    std::lock_guard lock(impl_->m);
    return impl_->presentNodes;
}

bool Master::waitForDisplayNodes(int timeoutMs) {
    const Impl& s = *impl_;
    return waitUntil(*impl_, timeoutMs, [&] { return s.presentNodes.size() >= s.settings.displayNodes.names.size(); });
}

void Master::setStopFlag(const std::atomic<bool>* flag) { impl_->stopFlag = flag; }

std::vector<std::string> Master::localClientArgs() const { return impl_->link.localArgs; }

std::vector<TileFailure> Master::takeTileFailures() {
    std::lock_guard lock(impl_->failuresMutex);
    std::vector<TileFailure> out(std::make_move_iterator(impl_->tileFailures.begin()),
                                 std::make_move_iterator(impl_->tileFailures.end()));
    impl_->tileFailures.clear();
    return out;
}

MasterCounters Master::counters() const { return impl_->countersNow(); }
uint64_t Master::droppedMessages() const { return counters().dropped(); }
uint64_t Master::resyncs() const { return impl_->resyncCount.load(); }
uint64_t Master::failedSends() const { return counters().failedSends; }
uint64_t Master::injectedUpdateLosses() const { return impl_->injectedLosses.load(); }
uint64_t Master::refusedConnections() const { return impl_->link.zap ? impl_->link.zap->denied() : 0; }

MasterCounters operator-(MasterCounters a, const MasterCounters& b) {
    a.malformed -= b.malformed;
    a.unknownPeer -= b.unknownPeer;
    a.stale -= b.stale;
    a.replayed -= b.replayed;
    a.unexpected -= b.unexpected;
    a.undecodableTiles -= b.undecodableTiles;
    a.refused -= b.refused;
    a.failedHandshakes -= b.failedHandshakes;
    a.failedSends -= b.failedSends;
    a.lostHandOuts -= b.lostHandOuts;
    a.stalledTiles -= b.stalledTiles;
    a.clientsDropped -= b.clientsDropped;
    return a;
}

std::string describeCounters(const MasterCounters& c) {
    std::string out;
    auto part = [](std::string& s, uint64_t n, const char* what) {
        if (n == 0) return;
        if (!s.empty()) s += ", ";
        s += std::to_string(n) + " " + what;
    };
    std::string dropped;
    part(dropped, c.malformed, "malformed");
    part(dropped, c.unknownPeer, "from unknown peers");
    part(dropped, c.stale, "stale");
    part(dropped, c.replayed, "repeated");
    part(dropped, c.unexpected, "unexpected");
    part(dropped, c.undecodableTiles, "undecodable tiles");
    if (!dropped.empty()) out = "dropped " + std::to_string(c.dropped()) + " messages (" + dropped + ")";
    part(out, c.refused, "handshakes refused");
    part(out, c.failedHandshakes, "handshakes broken off");
    part(out, c.failedSends, "sends failed");
    part(out, c.lostHandOuts, "lost tiles handed out again");
    part(out, c.stalledTiles, "stuck tiles reported");
    part(out, c.clientsDropped, "clients left");
    return out.empty() ? "nothing dropped, refused or lost" : out;
}

}  // namespace rtwall
