// The display master's network side.
//
// One network thread owns the ROUTER socket, the TileScheduler and the FrameAssembler's claims;
// the application thread talks to it through a command queue and an inproc wake-up socket, so
// updates stream to the clients the moment they are made (asynchronous rendering). Tiles are
// decoded by a small pool of threads straight into the framebuffer.
#include "codec.h"
#include "net.h"
#include "protocol.h"
#include "scene_state.h"
#include "scheduler.h"
#include "security.h"
#include "swap_barrier.h"

#include <rtwall/cluster.h>
#include <rtwall/cluster_testing.h>

#include <pthread.h>
#include <stdlib.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <utility>

namespace rtwall {

using namespace cluster;

namespace {

struct ClientState {
    uint32_t id = 0;
    std::string peer;
    double lastSeen = 0;
    double lastSent = 0;
    bool ready = false;       // proved it holds the state at stateSeq
    bool stateInFlight = false;  // a state was sent and not yet proved: another resync request adds nothing
    std::set<Hash128> meshesSent;  // each mesh goes to a client once: repeated requests cannot pile up meshes in its queue
    std::set<Hash128> assetsSent;  // likewise each texture or volume file
    uint32_t stateSeq = 0;    // the snapshot it was sent; it also has every update after it
    Hash128 stateHash{};      // that snapshot's stateHash: its Ready must say exactly this
    uint32_t credits = 0;     // tiles it asked for and has not been given
    uint32_t window = 0;      // tiles it asked to keep in flight this frame (its TileRequest)
    uint32_t tilesAssigned = 0;  // tiles sent to it this frame: its idle heartbeat must have seen them all
    uint32_t frameBegun = 0;  // the frame whose FrameBegin reached its queue (a failed send is retried)
    bool needsState = false;  // a state message did not fit its queue: the state goes again
    bool needsWelcome = false;  // a codec change did not fit its queue
    double fullSince = 0;     // its queue has been full since then (0: not full); too long and it goes
    double retryAt = 0;       // with a full queue: optional sends wait until then
    uint64_t updatesSent = 0; // for fault injection
    uint32_t threads = 0;
    double busySeconds = 0;   // render time reported this frame
    uint64_t frameBytes = 0;  // encoded bytes of its results accepted this frame
    const char* deathReason = nullptr;  // set when it must go; reaped outside any iteration
    uint32_t routesFrame = UINT32_MAX;  // with display nodes: the TileRoutes it holds (their first frame)
};

// A display node on the master's ROUTER (issue 19): control only, its tiles come from the clients.
struct NodeState {
    uint32_t index = 0;  // its bit in the tile masks: its place in DisplayNodeSettings::names
    std::string name, endpoint, publicKey;
    std::string peer;
    double lastSeen = 0, lastSent = 0;
    uint32_t routesFrame = UINT32_MAX;  // the TileRoutes it holds
    uint32_t frameSent = 0;             // the last frame whose NodeFrame it was sent
    // It answered its welcome: it holds the client keys (its tile socket lets them in), so the
    // clients may now be told where it is; before, a client's handshake could be refused.
    bool answered = false;
    const char* deathReason = nullptr;
};

std::string hex(uint32_t v) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%x", v);
    return buf;
}

// How many of each kind of dropped message are logged (with the peer's address) before the
// rest are only counted: a flood must not flood the log too.
constexpr uint64_t kLoggedPerKind = 5;

// Decodes accepted tiles into the framebuffer on a few threads.
class DecodePool {
public:
    struct Job {
        std::vector<uint8_t> pixels;  // encoded
        TileCodec codec;
        uint32_t tile;
        TileRect rect;
        TileView view;
        TilePixels format = TilePixels::Srgb8;
        float* linear = nullptr;  // LinearHalf: the frame's linear buffer (image width x 3 floats a row)
        int imageWidth = 0;
    };

    DecodePool(FrameAssembler& assembler, int threads, std::function<void()> onComplete,
               std::function<void(uint32_t)> onFailure)
        : assembler_(assembler), onComplete_(std::move(onComplete)), onFailure_(std::move(onFailure)) {
        for (int i = 0; i < threads; ++i) workers_.emplace_back([this] {
            pthread_setname_np(pthread_self(), "rtw-decode");  // for rtwall bench cluster's CPU split
            run();
        });
    }
    ~DecodePool() {
        {
            std::lock_guard lock(m_);
            stop_ = true;
        }
        cv_.notify_all();
        for (auto& t : workers_) t.join();
    }
    void push(Job job) {
        {
            std::lock_guard lock(m_);
            jobs_.push_back(std::move(job));
        }
        cv_.notify_one();
    }
    uint64_t failures() const { return failures_.load(); }

private:
    void run() {
        std::vector<uint8_t> scratch;  // a linear tile's half floats, reused
        for (;;) {
            Job job;
            {
                std::unique_lock lock(m_);
                cv_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
                if (jobs_.empty()) return;
                job = std::move(jobs_.front());
                jobs_.pop_front();
            }
            try {
                if (job.format == TilePixels::LinearHalf) {
                    // Into the linear frame, and quantised into the 8-bit one for display.
                    const size_t stride = size_t(job.imageWidth) * 3;
                    float* dst = job.linear + size_t(job.rect.y0) * stride + size_t(job.rect.x0) * 3;
                    decodeWideTile(job.codec, job.pixels.data(), job.pixels.size(), job.rect.width(),
                                   job.rect.height(), dst, stride, scratch);
                    for (int y = 0; y < job.rect.height(); ++y)
                        linearToSrgb8(dst + size_t(y) * stride, size_t(job.rect.width()) * 3,
                                      job.view.data + size_t(y) * job.view.stride);
                } else {
                    decodeTile(job.codec, job.pixels.data(), job.pixels.size(), job.rect.width(), job.rect.height(),
                               job.view.data, job.view.stride);
                }
                assembler_.commit(job.tile);
                if (assembler_.complete()) onComplete_();
            } catch (const std::exception&) {
                // A result that does not decode is dropped: the tile becomes claimable again
                // and the network thread reopens it in the scheduler, so someone renders it.
                assembler_.release(job.tile);
                ++failures_;
                onFailure_(job.tile);
            }
        }
    }

    FrameAssembler& assembler_;
    std::function<void()> onComplete_;
    std::function<void(uint32_t)> onFailure_;
    std::mutex m_;
    std::condition_variable cv_;
    std::deque<Job> jobs_;
    bool stop_ = false;
    std::atomic<uint64_t> failures_{0};
    std::vector<std::thread> workers_;
};

using Asset = std::pair<AssetRef, FileBytes>;

// The files a material names: its texture image, alpha-mask image and volume.
std::vector<std::string> filesNamedBy(const Material& m) {
    std::vector<std::string> paths;
    if (m.texture.kind == TextureKind::Image && !m.texture.file.empty()) paths.push_back(m.texture.file);
    if (m.alpha.kind == TextureKind::Image && !m.alpha.file.empty()) paths.push_back(m.alpha.file);
    if (m.type == MaterialType::Volume && !m.volumeFile.empty()) paths.push_back(m.volumeFile);
    return paths;
}

// A file a material names, from `files` (SceneDesc::files) when they hold it, else from disk,
// with its hash. Throws InputError naming the file when it cannot be read or is too large.
Asset readAsset(const std::string& path, const decltype(SceneDesc::files)& files) {
    FileBytes bytes;
    if (auto it = files.find(path); it != files.end() && it->second) {
        bytes = it->second;
    } else {
        std::error_code ec;
        const auto size = std::filesystem::file_size(path, ec);
        if (ec) throw InputError(path + ": cannot read the file a material names (" + ec.message() + ")");
        if (size > kMaxAssetBytes)
            throw InputError(path + ": " + std::to_string(size) + " bytes is more than the cluster sends (" +
                             std::to_string(kMaxAssetBytes) + ")");
        std::ifstream in(path, std::ios::binary);
        auto v = std::make_shared<std::vector<uint8_t>>(size_t(size));
        if (!in.read(reinterpret_cast<char*>(v->data()), std::streamsize(size)))
            throw InputError(path + ": cannot read the file a material names");
        bytes = std::move(v);
    }
    if (bytes->size() > kMaxAssetBytes)
        throw InputError(path + ": more bytes than the cluster sends (" + std::to_string(kMaxAssetBytes) + ")");
    return {AssetRef{path, hashBytes(bytes->data(), bytes->size()), bytes->size()}, bytes};
}

// Tiles a client may be owed at once: bounds what a client (or a replay of its requests) can
// make the master queue for it.
constexpr uint32_t kMaxCredits = 64;

// Queued in sequence order: each is pushed while stateMutex is held, so a frame's command
// comes after every update it renders and before every later one.
struct Command {
    enum Kind { kUpdate, kBeginFrame, kStop, kCodec } kind;
    Update update{};            // kUpdate; for kBeginFrame only its seq: the state the frame renders
    uint32_t frame = 0;
    RenderSettings settings{};  // kBeginFrame: image and tile size at that state
    CodecSettings codec{};      // kCodec
    TilePixels pixels = TilePixels::Srgb8;  // kBeginFrame: how its tiles travel
    bool stochastic = false;    // kBeginFrame: its state renders stochastically
    std::vector<FrameView> views{};  // kBeginFrame: a multi-view frame's views (setViews)
    uint64_t viewsTag = 0;
    CameraDesc camera{};        // kBeginFrame without views: the mono frame's camera (setCamera)
    uint32_t shownSeq = 0;      // kBeginFrame: FrameReport::stateSeq (the state's seq and the camera's moves)
};

}  // namespace

struct Master::Impl {
    ClusterSettings settings;
    // The application's state, at sequence number seq: the application thread changes it (set*),
    // O(1) per change; clients get the network thread's copy (frameState). stateMutex guards it,
    // seq, the stochastic flag, and the order of the commands it queues (held while queueing).
    SceneDesc scene;       // geometry once, shared with nobody
    // The mono frames' camera (setCamera). Not scene state: each frame carries it to the clients
    // in its FrameBegin. Its moves are counted, so that a frame's report says when its camera
    // changed as it says when its state did (accumulation restarts).
    CameraDesc camera;
    uint32_t cameraMoves = 0;
    std::vector<MeshRef> meshRefs;    // constant once the network thread runs, which reads it
    std::vector<AssetRef> assetRefs;  // texture and volume files, read once: clients fetch them by hash
    std::map<Hash128, std::shared_ptr<const std::vector<uint8_t>>> assetBytes;
    mutable std::mutex stateMutex;
    uint32_t seq = 0;      // state sequence number
    std::vector<FrameView> views;  // setViews: what the next frame begun renders
    uint64_t viewsTag = 0;
    // rendersStochastically(scene), recomputed (O(instances)) only after a change that can alter
    // it: a material, light or settings change (it reads which materials instances use, never
    // their transforms).
    bool stateStochastic = false;
    bool stochasticStale = true;
    uint64_t session = 0;

    zmq::context_t ctx{1};
    std::unique_ptr<ZapHandler> zap;  // before the router: it must answer the first handshake
    std::vector<std::string> allowedKeys;  // with CURVE: the client keys (Z85) let in, which display nodes take too
    zmq::socket_t router{ctx, zmq::socket_type::router};
    zmq::socket_t monitor{ctx, zmq::socket_type::pair};  // the router's failed handshakes
    zmq::socket_t wakeSend{ctx, zmq::socket_type::pair};
    zmq::socket_t wakeRecv{ctx, zmq::socket_type::pair};
    std::string boundEndpoint;
    std::filesystem::path localKeyDir;  // the local clients' session key pair (removed with the master)
    std::vector<std::string> localArgs;

    std::mutex m;                 // guards commands, the frame hand-over and counters below
    std::condition_variable cv;
    std::deque<Command> commands;
    std::mutex wakeMutex;         // zmq sockets are not thread-safe: one writer at a time
    uint32_t completedFrame = 0;
    std::vector<std::string> presentNodes;  // display nodes there now, in the wall's order (Master::displayNodesPresent)
    std::vector<Image> completedImages;  // one per view
    FrameReport completedReport;
    std::vector<std::vector<float>> completedLinear;  // the completed frame's linear pixels per view, when it had linear tiles
    int readyClients = 0;
    uint32_t swapReleased = 0;    // with display nodes: the newest frame the swap barrier released
    std::atomic<const std::atomic<bool>*> stopFlag{nullptr};

    // Network-thread state.
    std::map<std::string, ClientState> clients;  // by ZMQ peer identity
    uint32_t nextClientId = 1;
    TileScheduler scheduler;
    FrameAssembler assembler;
    std::unique_ptr<DecodePool> decoder;
    uint32_t currentFrame = 0;
    uint32_t frameSeq = 0;        // state the current frame renders
    // That state in full (before the first frame: the initial state), kept by applying the
    // updates sent since when a frame begins: O(changes), not a copy of the state per frame.
    // A joining client gets it, and the updates sent since, so that it can help at once.
    SceneSnapshot frameState;
    std::optional<EncodedSnapshot> frameStateMessage;  // frameState encoded and hashed, once per frame that needs it
    MergedUpdate sentSince;       // the updates sent since frameState, merged, for joiners
    // The camera and settings of the last frames begun: a client's failed tile is reported a
    // little after its frame may have ended.
    struct FrameRecord {
        uint32_t frame;
        CameraDesc camera;
        RenderSettings settings;
        std::vector<FrameView> views;
    };
    static constexpr size_t kRecentFrames = 8;
    std::deque<FrameRecord> recentFrames;
    std::mutex failuresMutex;
    std::deque<TileFailure> tileFailures;  // for takeTileFailures (failuresMutex)
    TilePixels framePixels = TilePixels::Srgb8;  // how the current frame's tiles travel
    bool frameStochastic = false;
    std::vector<std::vector<float>> linear;  // the current frame in linear RGB (LinearHalf frames), per view
    std::vector<FrameView> frameViews;  // the current frame's views (none: a mono frame of frameCamera)
    uint64_t frameViewsTag = 0;
    // What every FrameBegin of the current frame carries: frameViews, or the mono frame's one view.
    std::vector<FrameView> beginViews;
    uint32_t shownSeq = 0;  // FrameReport::stateSeq and NodeFrame::stateSeq of the current frame
    bool frameActive = false;
    double frameStart = 0;
    uint64_t frameBytes = 0;
    std::atomic<bool> frameDecoded{false};
    std::mutex failedMutex;
    std::vector<uint32_t> failedTiles;  // accepted results of the current frame that did not decode
    // Display nodes (settings.displayNodes.names non-empty): by peer identity. The frame's tile
    // masks are recomputed when the tiling changes (size, tile size, views) and sent to every
    // client and node once, as TileRoutes, before the first frame that uses them.
    std::map<std::string, NodeState> nodes;
    SwapBarrier barrier;
    std::vector<uint64_t> routes;
    uint32_t routesFrame = UINT32_MAX;  // the first frame `routes` apply to
    std::tuple<int, int, int, std::vector<FrameView>> routesKey;
    size_t tilesDone = 0;  // with nodes: tiles of the current frame acknowledged (TileDone)
    bool withNodes() const { return !settings.displayNodes.names.empty(); }
    std::atomic<uint64_t> resyncCount{0};
    std::atomic<uint64_t> injectedLosses{0};

    // Counters by kind (MasterCounters); the network thread writes, anyone reads.
    mutable std::mutex countersMutex;
    MasterCounters counts;
    // The message being handled, for the peer's address in a log line.
    const zmq::message_t* current = nullptr;
    const ClientState* currentClient = nullptr;

    uint32_t lastBegun = 0;       // application side
    bool inFlight = false;
    std::thread net;

    Impl(const SceneDesc& s, const ClusterSettings& cs)
        : settings(cs), scene(s), scheduler(SchedulerOptions{cs.affinity, cs.stragglerFactor, 0.05, 1}),
          barrier(cs.displayNodes.stallSeconds) {}

    ~Impl() {
        if (!localKeyDir.empty()) {
            std::error_code ec;
            std::filesystem::remove_all(localKeyDir, ec);
        }
    }

    MasterCounters countersNow() const {
        MasterCounters c;
        {
            std::lock_guard lock(countersMutex);
            c = counts;
        }
        if (zap) c.refused += zap->denied();
        return c;
    }

    // "client 3 at 127.0.0.1" or "127.0.0.1 (not a client)", for log lines.
    std::string who() const {
        std::string s;
        if (currentClient) s = "client " + std::to_string(currentClient->id) + " at ";
        s += current ? peerAddressOf(*current) : std::string("?");
        if (!currentClient) s += " (not a client)";
        return s;
    }

    // Counts one event of a kind; the first few are logged with what and from whom.
    void count(uint64_t MasterCounters::*kind, const char* kindName, const std::string& what) {
        uint64_t n;
        {
            std::lock_guard lock(countersMutex);
            n = ++(counts.*kind);
        }
        if (n <= kLoggedPerKind)
            std::fprintf(stderr, "rtwall master: %s from %s: %s%s\n", kindName, who().c_str(), what.c_str(),
                         n == kLoggedPerKind ? " (more of this kind are counted, not logged)" : "");
    }
    void malformed(const std::string& what) { count(&MasterCounters::malformed, "dropped a malformed message", what); }
    void stale(const std::string& what) { count(&MasterCounters::stale, "dropped a stale message", what); }
    void replayed(const std::string& what) { count(&MasterCounters::replayed, "dropped a repeated message", what); }
    void unexpected(const std::string& what) { count(&MasterCounters::unexpected, "dropped an unexpected message", what); }
    void add(uint64_t MasterCounters::*kind, uint64_t n) {
        std::lock_guard lock(countersMutex);
        counts.*kind += n;
    }

    // A file of the state by the path materials use (under stateMutex once the network runs).
    // A path is read once per session: later changes to the file on disk are not seen.
    const AssetRef* findAsset(const std::string& path) const {
        for (const AssetRef& a : assetRefs)
            if (a.path == path) return &a;
        return nullptr;
    }
    void addAsset(Asset asset) {
        assetBytes[asset.first.hash] = std::move(asset.second);
        assetRefs.push_back(std::move(asset.first));
    }

    Header header(MsgType type, uint32_t frame = 0) const {
        Header h;
        h.type = type;
        h.session = session;
        h.frame = frame;
        h.sceneVersion = frameSeq;
        return h;
    }

    // A send never blocks. A full queue is not death (a live client can be busy for a moment):
    // the caller repairs what was lost, optional sends pause for 10 ms, and only a queue full
    // for longer than the timeout drops the client. A closed connection does.
    template <class Msg> SendResult send(ClientState& c, const Msg& msg, uint32_t frame = 0) {
        return sendBytes(c, messageTypeOf(msg), encodeMessage(header(messageTypeOf(msg), frame), msg));
    }
    SendResult sendBytes(ClientState& c, MsgType type, const std::vector<uint8_t>& bytes) {
        const SendResult r = sendToPeerResult(router, c.peer, bytes);
        const double now = nowSeconds();
        if (r == SendResult::Sent) {
            c.lastSent = now;
            c.fullSince = 0;
            return r;
        }
        uint64_t n;
        {
            std::lock_guard lock(countersMutex);
            n = ++counts.failedSends;
        }
        if (n <= kLoggedPerKind)
            std::fprintf(stderr, "rtwall master: could not send a message (type %d) to client %u: %s%s\n",
                         int(type), c.id, r == SendResult::Full ? "its queue is full" : "it is gone",
                         n == kLoggedPerKind ? " (more failed sends are counted, not logged)" : "");
        if (r == SendResult::Gone) {
            markDead(c, "its connection is gone");
        } else {
            if (c.fullSince == 0) c.fullSince = now;
            c.retryAt = now + 0.01;
        }
        return r;
    }

    void wake() {
        std::lock_guard lock(wakeMutex);
        const uint8_t one = 1;
        wakeSend.send(zmq::const_buffer(&one, 1), zmq::send_flags::dontwait);
    }

    // Marks a client for removal; reap() removes it outside any loop over the clients.
    void markDead(ClientState& c, const char* why) {
        if (!c.deathReason) c.deathReason = why;
    }

    void reap() {
        bool any = false;
        for (auto it = clients.begin(); it != clients.end();) {
            if (!it->second.deathReason) {
                ++it;
                continue;
            }
            std::fprintf(stderr, "rtwall master: client %u leaves: %s\n", it->second.id, it->second.deathReason);
            scheduler.removeClient(it->second.id);  // its tiles go back to the shared queue
            if (it->second.ready) {
                std::lock_guard lock(m);
                --readyClients;
            }
            it = clients.erase(it);
            add(&MasterCounters::clientsDropped, 1);
            any = true;
        }
        if (any) serveAll();
    }

    void serve(ClientState& c) {
        if (!frameActive || !c.ready || c.credits == 0 || c.stateSeq > frameSeq || c.deathReason) return;
        const double now = nowSeconds();
        if (now < c.retryAt) return;
        TileAssign assign;
        assign.frame = currentFrame;
        assign.tiles = scheduler.request(c.id, c.credits, now);
        if (assign.tiles.empty()) return;
        if (send(c, assign, currentFrame) == SendResult::Sent) {
            c.credits -= uint32_t(assign.tiles.size());
            c.tilesAssigned += uint32_t(assign.tiles.size());
            return;
        }
        // They never reached it: back to the queue for whoever asks next (this client too, later).
        for (uint32_t t : assign.tiles) scheduler.release(c.id, currentFrame, t, false);
    }

    void serveAll() {
        for (auto& [peer, c] : clients)
            if (!c.deathReason) serve(c);
    }

    Welcome welcomeFor(const ClientState& c) const {
        return Welcome{c.id, settings.codec, uint32_t(settings.prefetch), uint32_t(settings.heartbeatMs),
                       uint32_t(settings.timeoutMs)};
    }

    // A joining or resyncing client gets the state of the frame being rendered (so that it can
    // help with it at once) and then the updates sent since, exactly as the others got them.
    // What does not fit its queue is sent again, whole, by retryPending. The state is encoded
    // and hashed here, once per frame state however many clients need it, not at every update:
    // a client proves the state it was sent (Ready), and only that one.
    void sendState(ClientState& c) {
        if (!frameStateMessage) frameStateMessage = encodeSnapshot(header(MsgType::SceneSnapshot), frameState);
        c.needsState = false;
        c.stateSeq = frameState.updateSeq;
        c.stateHash = frameStateMessage->stateHash;
        if (sendBytes(c, MsgType::SceneSnapshot, frameStateMessage->message) != SendResult::Sent) {
            c.needsState = !c.deathReason;
            return;
        }
        c.stateInFlight = true;
        // The history since the snapshot, merged into one message whatever its length.
        if (!sentSince.empty() && send(c, sentSince.update()) != SendResult::Sent) c.needsState = !c.deathReason;
    }

    void sendFrameBegin(ClientState& c) {
        if (withNodes() && c.routesFrame != routesFrame) {
            if (send(c, TileRoutes{routesFrame, routes}, currentFrame) != SendResult::Sent) return;
            c.routesFrame = routesFrame;
        }
        if (send(c, FrameBegin{currentFrame, frameSeq, framePixels, beginViews}, currentFrame) == SendResult::Sent)
            c.frameBegun = currentFrame;
    }

    // Messages that did not fit a client's queue and that it cannot do without: a codec change,
    // its state, the current frame's FrameBegin. Tried again every 10 ms while the queue is full.
    void retryPending() {
        const double now = nowSeconds();
        for (auto& [peer, c] : clients) {
            if (c.deathReason || now < c.retryAt) continue;
            if (c.needsWelcome) {
                if (send(c, welcomeFor(c)) != SendResult::Sent) continue;
                c.needsWelcome = false;
            }
            if (c.needsState) {
                sendState(c);
                if (c.needsState) continue;
            }
            if (frameActive && c.ready && c.frameBegun != currentFrame && c.stateSeq <= frameSeq) sendFrameBegin(c);
        }
    }

    void beginFrame(Command&& cmd) {
        const uint32_t frame = cmd.frame, stateSeq = cmd.update.seq;
        const RenderSettings& rs = cmd.settings;
        const TilePixels pixels = cmd.pixels;
        currentFrame = frame;
        framePixels = pixels;
        frameStochastic = cmd.stochastic;
        frameViews = std::move(cmd.views);
        frameViewsTag = cmd.viewsTag;
        shownSeq = cmd.shownSeq;
        // The views are the frame's only camera on the wire (protocol 13): a mono frame is one
        // view of the whole image, whose tiling is makeTiles'.
        if (frameViews.empty()) beginViews.assign(1, FrameView{cmd.camera, {}, 0, 0});
        else beginViews = frameViews;
        // Every tile writes its part; no clearing. (Swapped with the completed frame's buffer,
        // so a still view allocates nothing.)
        if (pixels == TilePixels::LinearHalf) {
            linear.resize(std::max<size_t>(1, frameViews.size()));
            for (std::vector<float>& l : linear) l.resize(size_t(rs.width) * size_t(rs.height) * 3);
        }
        frameSeq = stateSeq;
        // The frame's state: the last one and every update up to stateSeq, which were all sent
        // before this frame began (runCommands flushes first) and no later one was (commands
        // come in sequence order).
        if (!sentSince.empty() || frameState.updateSeq != stateSeq) {
            const Update since = sentSince.take();
            if (since.seq != stateSeq || since.baseSeq != frameState.updateSeq) {
                // An invariant, not an input: going on would hand out tiles of a state nobody holds.
                std::fprintf(stderr, "rtwall master: internal error: frame %u renders state %u, but the updates sent "
                                     "since state %u cover %u to %u\n",
                             frame, stateSeq, frameState.updateSeq, since.baseSeq, since.seq);
                std::abort();
            }
            for (const Change& change : since.changes) applyChange(frameState, change);
            frameState.updateSeq = stateSeq;
            frameStateMessage.reset();
        }
        // What a client's failed tile of this frame is replayed with (onTileFailed).
        recentFrames.push_back({frame, beginViews.front().camera, frameState.settings, frameViews});
        if (recentFrames.size() > kRecentFrames) recentFrames.pop_front();
        frameActive = true;
        frameStart = nowSeconds();
        frameBytes = 0;
        frameDecoded = false;
        if (frameViews.empty()) assembler.beginFrame(frame, rs.width, rs.height, rs.tileSize);
        else assembler.beginFrame(frame, rs.width, rs.height, viewTiles(frameViews, rs.width, rs.height, rs.tileSize),
                                  uint32_t(frameViews.size()));
        scheduler.beginFrame(frame, uint32_t(assembler.tiles().size()));
        if (withNodes()) beginNodeFrame(rs);
        for (auto& [peer, c] : clients) {
            c.credits = 0;
            c.window = 0;
            c.tilesAssigned = 0;
            c.busySeconds = 0;
            c.frameBytes = 0;
            if (c.ready && c.stateSeq <= frameSeq && !c.deathReason) sendFrameBegin(c);
        }
    }

    void finishFrameIfDone() {
        if (!frameActive) return;
        if (withNodes() ? tilesDone < scheduler.tileCount() : !frameDecoded.load()) return;
        frameActive = false;
        const double seconds = nowSeconds() - frameStart;
        FrameReport r;
        r.frame = currentFrame;
        r.stateSeq = shownSeq;
        r.seconds = seconds;
        r.bytes = frameBytes;
        const SchedulerStats& st = scheduler.stats();
        r.tilesStolen = st.stolen;
        r.tilesReissued = st.reissued;
        r.duplicatesDropped = st.duplicates;
        r.staleDropped = st.stale;
        r.affinityHits = st.affinityHits;
        r.tileOwners.assign(scheduler.owners().begin(), scheduler.owners().end());
        r.stochastic = frameStochastic;
        r.linear = framePixels == TilePixels::LinearHalf;
        r.views = frameViews.size();
        r.viewsTag = frameViewsTag;
        r.counters = countersNow();
        if (withNodes()) {
            const SwapBarrierStats& b = barrier.stats();
            r.displayNodes = nodes.size();
            r.swapsReleased = b.released;
            r.nodesLeftOut = b.leftOut;
            r.lastSwapSkew = b.lastSkew;
            r.maxSwapSkew = b.maxSkew;
        }
        const std::vector<double>& lat = scheduler.latencies();
        double sum = 0;
        for (double l : lat) sum += l;
        r.meanTileLatency = lat.empty() ? 0.0 : sum / double(lat.size());
        for (const auto& [peer, c] : clients) {
            ClientReport cr;
            cr.id = c.id;
            auto done = st.completedBy.find(c.id);
            cr.tiles = done == st.completedBy.end() ? 0 : done->second;
            auto stolen = st.stolenBy.find(c.id);
            cr.stolen = stolen == st.stolenBy.end() ? 0 : stolen->second;
            cr.bytes = c.frameBytes;
            cr.busyFraction = seconds > 0 ? c.busySeconds / (seconds * std::max(1u, c.threads)) : 0;
            r.clients.push_back(cr);
        }
        {
            std::lock_guard lock(m);
            // With nodes the pixels are on the nodes: empty images, one per view.
            if (withNodes()) completedImages.assign(std::max<size_t>(1, frameViews.size()), Image{});
            else completedImages = std::exchange(assembler.images(), std::vector<Image>(1));  // the assembler starts the next frame afresh
            if (framePixels == TilePixels::LinearHalf) completedLinear.swap(linear);
            else completedLinear.clear();
            completedReport = std::move(r);
            completedFrame = currentFrame;
        }
        cv.notify_all();
    }


    // -- Display nodes ---------------------------------------------------------------------------

    template <class Msg> bool sendNode(NodeState& n, const Msg& msg, uint32_t frame = 0) {
        const SendResult r = sendToPeerResult(router, n.peer, encodeMessage(header(messageTypeOf(msg), frame), msg));
        if (r == SendResult::Sent) {
            n.lastSent = nowSeconds();
            return true;
        }
        add(&MasterCounters::failedSends, 1);
        // A node that cannot take control messages cannot keep up with the wall: it goes, and
        // rejoins with a new hello (its screens are dark meanwhile).
        if (!n.deathReason) n.deathReason = r == SendResult::Full ? "its queue is full" : "its connection is gone";
        return false;
    }

    NodeList nodeList() const {
        NodeList list;
        for (const auto& [peer, n] : nodes)
            if (!n.deathReason && n.answered) list.nodes.push_back({n.index, n.name, n.endpoint, n.publicKey});
        std::sort(list.nodes.begin(), list.nodes.end(), [](const NodeEndpoint& a, const NodeEndpoint& b) { return a.node < b.node; });
        return list;
    }

    void sendNodeListToClients() {
        const NodeList list = nodeList();
        for (auto& [peer, c] : clients)
            if (!c.deathReason) send(c, list);
    }

    // The frame's tile masks (recomputed only when the tiling changes) and its NodeFrame.
    void beginNodeFrame(const RenderSettings& rs) {
        tilesDone = 0;
        auto key = std::make_tuple(rs.width, rs.height, rs.tileSize, frameViews);
        if (routesFrame == UINT32_MAX || key != routesKey) {
            // Without a routing (or when it cannot route this frame) every node gets every tile:
            // more traffic, the same screens.
            std::vector<uint64_t> masks(scheduler.tileCount(), ~uint64_t(0));
            if (settings.displayNodes.routes) {
                try {
                    masks = settings.displayNodes.routes(rs.width, rs.height, rs.tileSize, frameViews);
                } catch (const std::exception& e) {
                    std::fprintf(stderr, "rtwall master: cannot route the tiles of frame %u to the display nodes (%s): every "
                                         "node gets every tile\n", currentFrame, e.what());
                }
            }
            if (masks.size() != scheduler.tileCount()) {
                // An invariant of the wall library's routing, not an input.
                std::fprintf(stderr, "rtwall master: internal error: %zu tile masks for a frame of %u tiles\n", masks.size(),
                             scheduler.tileCount());
                std::abort();
            }
            routes = std::move(masks);
            routesKey = std::move(key);
            routesFrame = currentFrame;
        }
        for (auto& [peer, n] : nodes) sendNodeFrame(n, rs);
    }

    void sendNodeFrame(NodeState& n, const RenderSettings& rs) {
        if (n.deathReason) return;
        if (n.routesFrame != routesFrame) {
            if (!sendNode(n, TileRoutes{routesFrame, routes}, currentFrame)) return;
            n.routesFrame = routesFrame;
        }
        NodeFrame f{currentFrame, rs.width, rs.height, rs.tileSize, framePixels, frameViews, {}, frameStochastic, shownSeq};
        const std::vector<int>& eyes = settings.displayNodes.viewEyes;
        for (size_t v = 0; v < frameViews.size(); ++v) f.eyes.push_back(int8_t(v < eyes.size() && eyes[v] >= 0 && eyes[v] <= 1 ? eyes[v] : -1));
        if (sendNode(n, f, currentFrame)) n.frameSent = currentFrame;
    }

    void onNodeHello(const std::string& peer, const Header& h, const uint8_t* data, size_t size) {
        const NodeHello hello = decodePayload<NodeHello>(data, size);
        auto refuse = [&](const std::string& why) {
            if (!sendToPeer(router, peer, encodeMessage(header(MsgType::Goodbye), Goodbye{why}))) add(&MasterCounters::failedSends, 1);
            count(&MasterCounters::refused, "refused a display node", why);
        };
        if (h.version != kProtocolVersion || hello.protocolVersion != kProtocolVersion) {
            const unsigned theirs = h.version != kProtocolVersion ? h.version : hello.protocolVersion;
            refuse("protocol version " + std::to_string(theirs) + " is not the master's " + std::to_string(kProtocolVersion));
            return;
        }
        const std::vector<std::string>& names = settings.displayNodes.names;
        const auto at = std::find(names.begin(), names.end(), hello.name);
        if (at == names.end()) {
            refuse(names.empty() ? "this wall has no display nodes (node '" + hello.name + "')"
                                 : "the wall has no display node '" + hello.name + "'");
            return;
        }
        // Behind CURVE the tiles must be too: a node reached over an authenticated link whose
        // tile socket has no key would take pixels in the clear.
        if (zap && hello.publicKey.empty()) {
            refuse("display node '" + hello.name + "' has no tile key, and this master uses CURVE keys");
            return;
        }
        // A node of that name on another connection (a restarted node) is replaced.
        for (auto& [otherPeer, other] : nodes)
            if (other.name == hello.name && !other.deathReason) other.deathReason = "another node of its name said hello";
        reapNodes();
        NodeState n;
        n.index = uint32_t(at - names.begin());
        n.name = hello.name;
        n.endpoint = hello.endpoint;
        n.publicKey = hello.publicKey;
        n.peer = peer;
        n.lastSeen = nowSeconds();
        NodeState& ref = nodes[peer] = n;
        if (!sendNode(ref, NodeWelcome{ref.index, uint32_t(settings.heartbeatMs), uint32_t(settings.timeoutMs),
                                       settings.displayNodes.wallText, allowedKeys})) {
            reapNodes();
            return;
        }
        std::fprintf(stderr, "rtwall master: display node '%s' (%u) joins, tiles to %s\n", ref.name.c_str(), ref.index,
                     ref.endpoint.c_str());
        barrier.join(ref.index);
        publishNodes();
        if (frameActive) sendNodeFrame(ref, frameState.settings);
    }

    void releaseSwap(std::optional<uint32_t> frame) {
        if (!frame) return;
        {
            std::lock_guard lock(m);
            swapReleased = std::max(swapReleased, *frame);
        }
        cv.notify_all();
        // Every node of the wall that does not take part: stalled, gone, or never came.
        NodeSwap swap{*frame, {}};
        const std::vector<NodeId> joined = barrier.nodes(), stalled = barrier.leftOut();
        const std::vector<std::string>& names = settings.displayNodes.names;
        for (NodeId i = 0; i < names.size(); ++i)
            if (std::find(joined.begin(), joined.end(), i) == joined.end() ||
                std::find(stalled.begin(), stalled.end(), i) != stalled.end())
                swap.leftOut.push_back(names[i]);
        for (auto& [peer, n] : nodes)
            if (!n.deathReason) sendNode(n, swap, *frame);
    }

    void handleNode(NodeState& n, const Header& h, const uint8_t* payload, size_t payloadSize) {
        n.lastSeen = nowSeconds();
        if (!n.answered) {
            // Its first message after the welcome (it sends a heartbeat at once): the clients learn of it now.
            n.answered = true;
            sendNodeListToClients();
        }
        switch (h.type) {
        case MsgType::NodeHave: {
            const NodeHave have = decodePayload<NodeHave>(payload, payloadSize);
            if (have.frame > currentFrame || have.frame <= barrier.lastReleased()) {
                stale("display node '" + n.name + "' holds frame " + std::to_string(have.frame) + ", which is not waiting for a swap");
                return;
            }
            releaseSwap(barrier.have(n.index, have.frame, nowSeconds()));
            break;
        }
        case MsgType::NodeSwapped: barrier.swapped(n.index, decodePayload<NodeSwapped>(payload, payloadSize).frame, nowSeconds()); break;
        case MsgType::Heartbeat: decodePayload<Heartbeat>(payload, payloadSize); break;
        case MsgType::Goodbye: {
            const Goodbye bye = decodePayload<Goodbye>(payload, payloadSize);
            std::fprintf(stderr, "rtwall master: display node '%s' says goodbye: %s\n", n.name.c_str(), bye.reason.c_str());
            if (!n.deathReason) n.deathReason = "it said goodbye";
            break;
        }
        default: unexpected("a message of type " + std::to_string(int(h.type)) + " from display node '" + n.name + "'"); break;
        }
    }

    void reapNodes() {
        bool any = false;
        for (auto it = nodes.begin(); it != nodes.end();) {
            if (!it->second.deathReason) {
                ++it;
                continue;
            }
            std::fprintf(stderr, "rtwall master: display node '%s' leaves: %s\n", it->second.name.c_str(), it->second.deathReason);
            // Leaving the barrier may complete a frame the others all hold.
            barrier.leave(it->second.index);
            it = nodes.erase(it);
            any = true;
        }
        if (any) {
            publishNodes();
            sendNodeListToClients();
            releaseSwap(barrier.poll(nowSeconds()));
        }
    }

    // For the application's thread (displayNodesPresent, waitForDisplayNodes).
    void publishNodes() {
        std::vector<std::string> present;
        for (const std::string& name : settings.displayNodes.names)
            for (const auto& [peer, n] : nodes)
                if (n.name == name && !n.deathReason) {
                    present.push_back(name);
                    break;
                }
        {
            std::lock_guard lock(m);
            presentNodes = std::move(present);
        }
        cv.notify_all();
    }

    void nodeHousekeeping() {
        const double now = nowSeconds();
        const double timeout = settings.timeoutMs * 1e-3, beat = settings.heartbeatMs * 1e-3;
        for (auto& [peer, n] : nodes) {
            if (n.deathReason) continue;
            if (now - n.lastSeen > timeout) n.deathReason = "heartbeat timeout";
            else if (now - n.lastSent > beat) sendNode(n, Heartbeat{});
        }
        reapNodes();
        releaseSwap(barrier.poll(now));
    }

    // A client sent a tile to its nodes: the scheduler completes it as it would a TileResult.
    void onTileDone(ClientState& c, const Header& h, const TileDone& d) {
        c.busySeconds += d.renderMicros * 1e-6;
        if (!withNodes()) {
            unexpected("a tile ack, but this wall has no display nodes");
            return;
        }
        if (!frameActive || h.frame != currentFrame || d.frame != currentFrame) {
            stale("a tile ack for frame " + std::to_string(d.frame) + ", which is not being rendered");
            return;
        }
        const auto result = scheduler.complete(c.id, d.frame, d.tile, nowSeconds());
        if (result == TileScheduler::Result::Unexpected) {
            unexpected("a tile ack for tile " + std::to_string(d.tile) + ", which it was not given");
            return;
        }
        c.credits = std::min<uint32_t>(c.credits + 1, kMaxCredits);
        if (result == TileScheduler::Result::Accepted) {
            ++tilesDone;
            const uint64_t sent = uint64_t(d.bytes) * uint64_t(std::popcount(routes[d.tile]));
            frameBytes += sent;
            c.frameBytes += sent;
        }
        serve(c);
    }

    void onHello(const std::string& peer, const Header& h, const uint8_t* data, size_t size) {
        const Hello hello = decodePayload<Hello>(data, size);
        if (h.version != kProtocolVersion || hello.protocolVersion != kProtocolVersion) {
            const unsigned theirs = h.version != kProtocolVersion ? h.version : hello.protocolVersion;
            Goodbye bye{"protocol version " + std::to_string(theirs) + " is not the master's " + std::to_string(kProtocolVersion)};
            if (!sendToPeer(router, peer, encodeMessage(header(MsgType::Goodbye), bye))) add(&MasterCounters::failedSends, 1);
            count(&MasterCounters::refused, "refused a client",
                  "it speaks protocol version " + std::to_string(theirs) + " (master: " + std::to_string(kProtocolVersion) + ")");
            return;
        }
        if (auto old = clients.find(peer); old != clients.end()) {
            markDead(old->second, "said hello again");
            currentClient = nullptr;
            reap();
        }
        ClientState c;
        c.id = nextClientId++;
        c.peer = peer;
        c.lastSeen = nowSeconds();
        c.threads = std::max(1u, hello.threads);
        auto& ref = clients[peer] = c;
        const SendResult r = send(ref, welcomeFor(ref));
        if (r == SendResult::Gone) return;
        if (r == SendResult::Sent && withNodes()) send(ref, nodeList());
        if (r == SendResult::Full) {
            // Both again, in this order: a state before its Welcome would be thrown away.
            ref.needsWelcome = ref.needsState = true;
            return;
        }
        sendState(ref);
    }

    void onReady(ClientState& c, const uint8_t* data, size_t size) {
        const Ready r = decodePayload<Ready>(data, size);
        if (!c.stateInFlight) {
            // Nothing to prove: a replayed or repeated Ready. Answering it with the state again
            // would let one message cost a whole snapshot.
            replayed("a Ready with no state on its way to the client");
            return;
        }
        if (r.updateSeq != c.stateSeq || r.stateHash != c.stateHash) {
            // It does not hold the state we sent: never accept its tiles; send the state again.
            unexpected("a Ready for state " + std::to_string(r.updateSeq) + " that is not the state it was sent (" +
                       std::to_string(c.stateSeq) + ")");
            sendState(c);
            return;
        }
        c.stateInFlight = false;
        // In the scheduler from its first proof on: a peer that never proves a state is no
        // client the scheduler waits for (a stuck tile avoids its client only while another
        // client could render it).
        scheduler.addClient(c.id);
        if (!c.ready) {
            c.ready = true;
            {
                std::lock_guard lock(m);
                ++readyClients;
            }
            cv.notify_all();
        }
        if (frameActive && c.stateSeq <= frameSeq) sendFrameBegin(c);
    }

    void onMeshRequest(ClientState& c, const uint8_t* data, size_t size) {
        const MeshRequest req = decodePayload<MeshRequest>(data, size);
        size_t i = 0;
        while (i < meshRefs.size() && meshRefs[i].hash != req.hash) ++i;
        if (i == meshRefs.size()) {
            unexpected("a request for a mesh this scene does not have");
            return;
        }
        if (!c.meshesSent.insert(req.hash).second) {
            // Asked before: it has it, or it is replaying requests to fill its queue.
            replayed("a request for a mesh it was sent before");
            return;
        }
        MeshData md{req.hash, encodeMesh(*scene.meshes[i].mesh)};
        if (send(c, md) == SendResult::Full) {
            // It asks again when the state comes again.
            c.meshesSent.erase(req.hash);
            c.needsState = true;
        }
    }

    void onAssetRequest(ClientState& c, const uint8_t* data, size_t size) {
        const AssetRequest req = decodePayload<AssetRequest>(data, size);
        FileBytes bytes;
        {
            std::lock_guard lock(stateMutex);  // Master::setMaterial may add files meanwhile
            if (auto it = assetBytes.find(req.hash); it != assetBytes.end()) bytes = it->second;
        }
        if (!bytes) {
            unexpected("a request for a file this scene does not have");
            return;
        }
        if (!c.assetsSent.insert(req.hash).second) {
            replayed("a request for a file it was sent before");
            return;
        }
        if (send(c, AssetData{req.hash, *bytes}) == SendResult::Full) {
            c.assetsSent.erase(req.hash);
            c.needsState = true;
        }
    }

    void onTileResult(ClientState& c, const Header& h, const uint8_t* data, size_t size) {
        TileResult r = decodePayload<TileResult>(data, size);
        if (withNodes()) {
            // The master never takes pixels of a wall with display nodes: the frame ends on acks.
            unexpected("a tile's pixels, but this wall's tiles go to its display nodes");
            return;
        }
        c.busySeconds += r.renderMicros * 1e-6;
        if (!frameActive || h.frame != currentFrame || r.frame != currentFrame) {
            stale("a result for frame " + std::to_string(r.frame) + ", which is not being rendered");
            return;
        }
        if (r.format != framePixels) {
            unexpected("a result in another pixel format than the frame's");
            return;
        }
        const auto result = scheduler.complete(c.id, r.frame, r.tile, nowSeconds());
        if (result == TileScheduler::Result::Unexpected) {
            // A tile never handed to this client (replayed from another frame's hand-outs, or made up).
            unexpected("a result for tile " + std::to_string(r.tile) + ", which it was not given");
            return;
        }
        // A result for a tile it was given is also a request for the next tile; a duplicate
        // (the tile was done by a re-issue, or the result was replayed) is counted in the report.
        c.credits = std::min<uint32_t>(c.credits + 1, kMaxCredits);
        if (result == TileScheduler::Result::Accepted) {
            TileRect rect;
            TileView view;
            if (assembler.claim(r.frame, r.tile, rect, view) == FrameAssembler::Claim::Granted) {
                frameBytes += r.pixels.size();
                c.frameBytes += r.pixels.size();
                const uint32_t v = assembler.viewOf(r.tile);
                decoder->push({std::move(r.pixels), r.codec, r.tile, rect, view, r.format,
                               r.format == TilePixels::LinearHalf ? linear[v].data() : nullptr, assembler.image(v).width});
            }
        }
        serve(c);
    }

    // An idle client that has seen every tile it was sent this frame holds none of its
    // hand-outs: those still awaiting a result are lost (dropped on the way, or never rendered)
    // and go to the next client that asks, this one included. This is what recovers a lost
    // result when it is the only client.
    void onHeartbeat(ClientState& c, const Heartbeat& hb) {
        if (!hb.idle || !frameActive || hb.frame != currentFrame || hb.tilesSeen != c.tilesAssigned ||
            c.frameBegun != currentFrame)
            return;
        const size_t lost = scheduler.release(c.id);
        // Everything it asked for is free again, also credits of results that were lost.
        c.credits = std::min(kMaxCredits, std::max(c.credits, c.window));
        if (lost == 0) {
            serve(c);
            return;
        }
        uint64_t n;
        {
            std::lock_guard lock(countersMutex);
            n = (counts.lostHandOuts += lost);
        }
        if (n - lost < kLoggedPerKind)
            std::fprintf(stderr, "rtwall master: client %u is idle without %zu tile%s of frame %u it was given: handed out again\n",
                         c.id, lost, lost == 1 ? "" : "s", currentFrame);
        serveAll();
    }

    // A render thread of this client is stuck on a tile: the tile goes to another client, or
    // to another thread of this one when it is the only client (it still renders tiles on its
    // other threads, so its stuck slot is given back as a credit).
    // A report for a tile that is done already (a straggler re-issue finished it, or the frame
    // completed) is still counted and logged: the operator should know about a stuck thread.
    void onTileStalled(ClientState& c, const TileStalled& st) {
        const bool outstanding = frameActive && st.frame == currentFrame && scheduler.release(c.id, st.frame, st.tile, true);
        count(&MasterCounters::stalledTiles, "a stuck render thread",
              "frame " + std::to_string(st.frame) + ", tile " + std::to_string(st.tile) + " has been rendering for " +
                  std::to_string(st.elapsedMs) + " ms" + (outstanding ? ": handed out again" : " (done by another)"));
        if (!outstanding) return;
        c.credits = std::min<uint32_t>(c.credits + 1, kMaxCredits);
        serveAll();
    }

    // A client's tile threw (it says goodbye next): kept, with the camera and settings of its
    // frame, for the application to say how to replay it. A report that does not match a tile
    // of a recent frame is dropped: it could not be replayed.
    void onTileFailed(ClientState& c, const TileFailed& f) {
        auto rec = std::find_if(recentFrames.begin(), recentFrames.end(), [&](const FrameRecord& r) { return r.frame == f.frame; });
        if (rec == recentFrames.end()) {
            unexpected("a failed tile of frame " + std::to_string(f.frame) + ", which is not a recent frame");
            return;
        }
        std::vector<TileRect> tiles;
        CameraDesc replayCamera = rec->camera;
        if (rec->views.empty()) {
            tiles = makeTiles(rec->settings.width, rec->settings.height, rec->settings.tileSize);
        } else {
            // A multi-view frame's tile is replayed with its view's camera.
            const std::vector<ViewTile> vt = viewTiles(rec->views, rec->settings.width, rec->settings.height, rec->settings.tileSize);
            for (const ViewTile& t : vt) tiles.push_back(t.rect);
            if (f.tile < vt.size()) replayCamera = rec->views[vt[f.tile].view].camera;
        }
        const TileRect& r = f.rect;
        if (f.tile >= tiles.size() || tiles[f.tile].x0 != r.x0 || tiles[f.tile].y0 != r.y0 || tiles[f.tile].x1 != r.x1 ||
            tiles[f.tile].y1 != r.y1) {
            unexpected("a failed tile " + std::to_string(f.tile) + " whose pixels are not that tile's in frame " +
                       std::to_string(f.frame));
            return;
        }
        std::lock_guard lock(failuresMutex);
        tileFailures.push_back({c.id, f.frame, f.tile, r, f.reason, replayCamera, rec->settings, f.packetWidth});
        if (tileFailures.size() > 64) tileFailures.pop_front();
    }

    void onResyncRequest(ClientState& c, const uint8_t* data, size_t size) {
        decodePayload<ResyncRequest>(data, size);
        if (c.stateInFlight) {
            replayed("a resync request while its state is on its way");  // or the request is a replay
            return;
        }
        ++resyncCount;
        if (c.ready) {
            c.ready = false;
            std::lock_guard lock(m);
            --readyClients;
        }
        // It drops its work when the state arrives: what it was given goes to whoever asks.
        const size_t lost = scheduler.release(c.id);
        add(&MasterCounters::lostHandOuts, lost);
        c.credits = 0;
        c.window = 0;
        sendState(c);
        if (lost > 0) serveAll();
    }

    void handle(zmq::message_t& identity, zmq::message_t& msg) {
        const std::string peer(static_cast<const char*>(identity.data()), identity.size());
        const auto* bytes = static_cast<const uint8_t*>(msg.data());
        auto known = clients.find(peer);
        currentClient = known == clients.end() ? nullptr : &known->second;
        Header h;
        try {
            h = decodeHeader(bytes, msg.size());
        } catch (const DecodeError& e) {
            malformed(e.what());
            return;
        }
        const uint8_t* payload = bytes + kHeaderSize;
        const size_t payloadSize = msg.size() - kHeaderSize;
        try {
            if (h.type == MsgType::Hello) {
                onHello(peer, h, payload, payloadSize);
                return;
            }
            if (h.type == MsgType::NodeHello) {
                onNodeHello(peer, h, payload, payloadSize);
                return;
            }
            if (auto node = nodes.find(peer); node != nodes.end()) {
                if (h.session != session || h.version != kProtocolVersion) {
                    count(&MasterCounters::unknownPeer, "dropped a message", "another session or protocol version");
                    return;
                }
                handleNode(node->second, h, payload, payloadSize);
                return;
            }
            if (known == clients.end() || h.session != session || h.version != kProtocolVersion) {
                // Not (or no longer) one of ours.
                count(&MasterCounters::unknownPeer, "dropped a message",
                      known == clients.end() ? "it is not a client (no hello, or dropped)" : "another session or protocol version");
                return;
            }
            ClientState& c = known->second;
            c.lastSeen = nowSeconds();
            switch (h.type) {
            case MsgType::Ready: onReady(c, payload, payloadSize); break;
            case MsgType::MeshRequest: onMeshRequest(c, payload, payloadSize); break;
            case MsgType::AssetRequest: onAssetRequest(c, payload, payloadSize); break;
            case MsgType::TileRequest: {
                const TileRequest req = decodePayload<TileRequest>(payload, payloadSize);
                if (frameActive && req.frame == currentFrame) {
                    c.credits = std::min<uint32_t>(c.credits + req.count, kMaxCredits);
                    c.window = std::max(c.window, std::min<uint32_t>(req.count, kMaxCredits));
                    serve(c);
                } else {
                    stale("a tile request for frame " + std::to_string(req.frame) + ", which is not being rendered");
                }
                break;
            }
            case MsgType::TileResult: onTileResult(c, h, payload, payloadSize); break;
            case MsgType::TileDone: onTileDone(c, h, decodePayload<TileDone>(payload, payloadSize)); break;
            case MsgType::Heartbeat: onHeartbeat(c, decodePayload<Heartbeat>(payload, payloadSize)); break;
            case MsgType::TileStalled: onTileStalled(c, decodePayload<TileStalled>(payload, payloadSize)); break;
            case MsgType::TileFailed: onTileFailed(c, decodePayload<TileFailed>(payload, payloadSize)); break;
            case MsgType::ResyncRequest: onResyncRequest(c, payload, payloadSize); break;
            case MsgType::Goodbye: {
                const Goodbye bye = decodePayload<Goodbye>(payload, payloadSize);
                std::fprintf(stderr, "rtwall master: client %u says goodbye: %s\n", c.id, bye.reason.c_str());
                markDead(c, "it said goodbye");
                break;
            }
            default:  // a master-to-client type from a client
                unexpected("a message of type " + std::to_string(int(h.type)) + ", which only the master sends");
                break;
            }
        } catch (const DecodeError& e) {
            malformed(std::string("message type ") + std::to_string(int(h.type)) + ": " + e.what());
        }
    }

    void reopenFailedTiles() {
        std::vector<uint32_t> failed;
        {
            std::lock_guard lock(failedMutex);
            failed.swap(failedTiles);
        }
        if (failed.empty()) return;
        add(&MasterCounters::undecodableTiles, failed.size());
        for (uint32_t t : failed) scheduler.reopen(currentFrame, t);
        serveAll();
    }

    // An update that does not fit a client's queue is lost to it like a dropped packet: the
    // client sees the gap when a frame needs the update and asks for a resync.
    void sendUpdate(const Update& update) {
        for (auto& [peer, c] : clients) {
            if (c.deathReason) continue;
            const int n = settings.faults ? settings.faults->dropEveryNthUpdate : 0;
            if (n > 0 && ++c.updatesSent % uint64_t(n) == 0) {  // injected loss
                ++injectedLosses;
                continue;
            }
            send(c, update);
        }
        sentSince.add(Update(update));
    }

    // Updates are merged and sent at most every kUpdateIntervalSeconds (and always before a
    // frame begins), so a burst of application calls (a script, a dragged object) costs a few
    // messages instead of filling every queue.
    static constexpr double kUpdateIntervalSeconds = 0.002;
    MergedUpdate unsent;         // merged updates not sent yet
    double lastUpdateSent = 0;

    void flushUpdates() {
        if (unsent.empty()) return;
        sendUpdate(unsent.take());
        lastUpdateSent = nowSeconds();
    }

    // Runs the queued commands; false when one of them is kStop (the loop then ends). The stop
    // is seen in the list taken here: checking the shared queue first and taking it afterwards
    // could swallow a stop queued in between, and the destructor would wait forever.
    bool runCommands() {
        std::deque<Command> pending;
        {
            std::lock_guard lock(m);
            pending.swap(commands);
        }
        for (const Command& cmd : pending)
            if (cmd.kind == Command::kStop) return false;
        for (Command& cmd : pending) {
            if (cmd.kind == Command::kUpdate) {
                unsent.add(std::move(cmd.update));
                continue;
            }
            // Never merge across a frame: a frame's state must be a point in the sequence.
            flushUpdates();
            if (cmd.kind == Command::kBeginFrame)
                beginFrame(std::move(cmd));
            if (cmd.kind == Command::kCodec) {
                settings.codec = cmd.codec;  // for clients that join later
                for (auto& [peer, c] : clients)
                    if (!c.deathReason) c.needsWelcome = send(c, welcomeFor(c)) == SendResult::Full;
                // The state's sequence number moves on (an update without changes), so frames
                // after the switch are seen as another state and an accumulation restarts.
                unsent.add(std::move(cmd.update));
            }
        }
        if (nowSeconds() - lastUpdateSent > kUpdateIntervalSeconds) flushUpdates();
        return true;
    }

    void checkTimeouts() {
        const double now = nowSeconds();
        const double timeout = settings.timeoutMs * 1e-3, beat = settings.heartbeatMs * 1e-3;
        for (auto& [peer, c] : clients) {
            if (c.deathReason) continue;
            if (now - c.lastSeen > timeout) markDead(c, "heartbeat timeout");
            else if (c.fullSince != 0 && now - c.fullSince > timeout) markDead(c, "its queue has been full for longer than the timeout");
            else if (now - c.lastSent > beat && now >= c.retryAt) send(c, Heartbeat{});
        }
    }

    // Connections that broke off in the handshake (the router's monitor): ZMTP garbage, a peer
    // without CURVE or with another server key. Key refusals are the ZAP handler's to count.
    void readMonitor() {
        for (int i = 0; i < 64; ++i) {
            zmq::message_t event, address;
            if (!monitor.recv(event, zmq::recv_flags::dontwait)) return;
            if (!event.more() || !monitor.recv(address, zmq::recv_flags::dontwait) || event.size() < 6) continue;
            discardRestOf(monitor, address);
            uint16_t id;
            uint32_t value;
            std::memcpy(&id, event.data(), 2);
            std::memcpy(&value, static_cast<const uint8_t*>(event.data()) + 2, 4);
            uint64_t n;
            {
                std::lock_guard lock(countersMutex);
                n = ++counts.failedHandshakes;
            }
            if (n > kLoggedPerKind) continue;
            // The monitor names the listening endpoint, not the peer.
            std::string why;
            if (id != ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL) why = "it broke off (error " + std::to_string(value) + ")";
            else if (value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH) why = "the peer uses another security mechanism (no CURVE key?)";
            else if (value == ZMQ_PROTOCOL_ERROR_ZMTP_CRYPTOGRAPHIC) why = "CURVE failed (a client with another server key?)";
            else why = "ZMTP protocol error 0x" + hex(value) + " (not a ZeroMQ peer?)";
            std::fprintf(stderr, "rtwall master: a connection to %s failed its handshake: %s%s\n", address.to_string().c_str(),
                         why.c_str(), n == kLoggedPerKind ? " (more are counted, not logged)" : "");
        }
    }

    void loop() {
        zmq::pollitem_t items[] = {{router.handle(), 0, ZMQ_POLLIN, 0},
                                   {wakeRecv.handle(), 0, ZMQ_POLLIN, 0},
                                   {monitor.handle(), 0, ZMQ_POLLIN, 0}};
        double lastHousekeeping = 0;
        for (;;) {
            zmq::poll(items, 3, std::chrono::milliseconds(frameActive ? 2 : 20));
            if (items[1].revents & ZMQ_POLLIN) {
                zmq::message_t ignored;
                while (wakeRecv.recv(ignored, zmq::recv_flags::dontwait)) {
                }
                if (!runCommands()) return;
                reopenFailedTiles();
            }
            if (items[2].revents & ZMQ_POLLIN) readMonitor();
            // Drain what is queued, bounded so commands and timers are not starved.
            for (int i = 0; i < 256 && (items[0].revents & ZMQ_POLLIN); ++i) {
                zmq::message_t identity, msg;
                if (!router.recv(identity, zmq::recv_flags::dontwait)) break;
                current = &identity;
                currentClient = nullptr;
                if (!identity.more()) {
                    malformed("a frame without a routing id");
                    continue;
                }
                if (!router.recv(msg, zmq::recv_flags::dontwait)) break;
                current = &msg;
                // rtwall messages are one frame: the extra frames of a message that has more go
                // with it (each recv here reads the next part, not the first part's flag again).
                if (const size_t extra = discardRestOf(router, msg); extra > 0) {
                    auto known = clients.find(identity.to_string());
                    currentClient = known == clients.end() ? nullptr : &known->second;
                    malformed("a message of " + std::to_string(extra + 1) + " frames (rtwall messages are one frame)");
                    continue;
                }
                handle(identity, msg);
                current = nullptr;
                currentClient = nullptr;
                if (settings.faults && settings.faults->consumeDelayUs > 0)
                    std::this_thread::sleep_for(std::chrono::microseconds(settings.faults->consumeDelayUs));
            }
            current = nullptr;
            currentClient = nullptr;
            reap();
            finishFrameIfDone();
            const double now = nowSeconds();
            if (now - lastHousekeeping > 0.002) {
                lastHousekeeping = now;
                flushUpdates();
                checkTimeouts();
                reap();
                retryPending();
                if (withNodes()) nodeHousekeeping();
                serveAll();  // re-queued tiles of departed clients, stragglers
            }
        }
    }
};


Master::Master(const SceneDesc& scene, const ClusterSettings& settings) : impl_(std::make_unique<Impl>(scene, settings)) {
    Impl& s = *impl_;
    if (scene.cameras.empty()) throw InputError("the scene has no camera");
    s.camera = scene.cameras.front();
    std::random_device rd;
    s.session = (uint64_t(rd()) << 32) ^ rd();
    for (const MeshDesc& md : scene.meshes) s.meshRefs.push_back(meshRefOf(md));
    // Texture images and volume files: read once, sent to clients that do not have them.
    for (const Material& m : scene.materials)
        for (const std::string& path : filesNamedBy(m))
            if (!s.findAsset(path)) s.addAsset(readAsset(path, scene.files));
    s.frameState = snapshotOf(s.scene, s.meshRefs, s.assetRefs, s.seq);

    // The largest legitimate message a client sends is a result for the largest tile allowed.
    // (A linear tile is encoded as an 8-bit tile twice as wide.)
    const int64_t maxResult = int64_t(kHeaderSize + 64 + maxEncodedTileBytes(2048, 1024));
    if (settings.highWaterMark < 1) throw InputError("the high-water mark must be at least 1 message");
    configureSocket(s.router, maxResult, settings.heartbeatMs, settings.timeoutMs, settings.highWaterMark);
    s.router.set(zmq::sockopt::router_mandatory, 1);
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
            s.localKeyDir = dir;
            const KeyPair local = makeKeyPair();
            writeKeyFiles(local, s.localKeyDir / "local");
            writePublicKeyFile(keys.publicKey, s.localKeyDir / "master.pub");
            allowed.push_back(local.publicKey);
            s.localArgs = {"--key", (s.localKeyDir / "local.key").string(), "--server-key",
                           (s.localKeyDir / "master.pub").string()};
        }
        s.allowedKeys = allowed;
        s.zap = std::make_unique<ZapHandler>(s.ctx, allowed);
        s.router.set(zmq::sockopt::zap_domain, "rtwall");
        s.router.set(zmq::sockopt::curve_server, 1);
        s.router.set(zmq::sockopt::curve_secretkey, keys.secretKey);
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
    s.monitor.set(zmq::sockopt::linger, 0);
    if (zmq_socket_monitor(s.router.handle(), "inproc://rtwall-master-monitor",
                           ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL) != 0)
        throw std::runtime_error(std::string("zmq_socket_monitor: ") + zmq_strerror(zmq_errno()));
    s.monitor.connect("inproc://rtwall-master-monitor");
    s.router.bind(settings.bind);
    s.boundEndpoint = s.router.get(zmq::sockopt::last_endpoint);
    const std::string wakeAddress = "inproc://rtwall-master-wake";
    s.wakeRecv.bind(wakeAddress);
    s.wakeSend.connect(wakeAddress);

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
        sendToPeer(s.router, c.peer, encodeMessage(s.header(MsgType::Goodbye), Goodbye{"the master is shutting down"}));
    for (auto& [peer, n] : s.nodes)  // display nodes end with the wall instead of waiting for a master that is gone
        if (!n.deathReason) sendToPeer(s.router, n.peer, encodeMessage(s.header(MsgType::Goodbye), Goodbye{"the master is shutting down"}));
    s.decoder.reset();
    zmq_socket_monitor(s.router.handle(), nullptr, 0);
    s.monitor.close();
    s.router.close();
    s.zap.reset();
}

std::string Master::endpoint() const { return impl_->boundEndpoint; }

int Master::connectedClients() const {
    std::lock_guard lock(impl_->m);
    return impl_->readyClients;
}

namespace {

void throwIfStopped(const Master::Impl& s) {
    const std::atomic<bool>* flag = s.stopFlag.load();
    if (flag && flag->load()) throw Cancelled();
}

}  // namespace

bool Master::waitForClients(int count, int timeoutMs) {
    Impl& s = *impl_;
    std::unique_lock lock(s.m);
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeoutMs);
    while (s.readyClients < count) {
        throwIfStopped(s);
        const auto now = std::chrono::steady_clock::now();
        if (now >= end) return false;
        s.cv.wait_for(lock, std::min<std::chrono::steady_clock::duration>(end - now, std::chrono::milliseconds(100)));
    }
    return true;
}

bool Master::waitForSwap(uint32_t frame, int timeoutMs) {
    Impl& s = *impl_;
    std::unique_lock lock(s.m);
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeoutMs);
    while (s.swapReleased < frame) {
        throwIfStopped(s);
        const auto now = std::chrono::steady_clock::now();
        if (now >= end) return false;
        s.cv.wait_for(lock, std::min<std::chrono::steady_clock::duration>(end - now, std::chrono::milliseconds(100)));
    }
    return true;
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
    Impl& s = *impl_;
    std::unique_lock lock(s.m);
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeoutMs);
    while (s.presentNodes.size() < s.settings.displayNodes.names.size()) {
        throwIfStopped(s);
        const auto now = std::chrono::steady_clock::now();
        if (now >= end) return false;
        s.cv.wait_for(lock, std::min<std::chrono::steady_clock::duration>(end - now, std::chrono::milliseconds(100)));
    }
    return true;
}

void Master::setStopFlag(const std::atomic<bool>* flag) { impl_->stopFlag = flag; }

std::vector<std::string> Master::localClientArgs() const { return impl_->localArgs; }

std::vector<TileFailure> Master::takeTileFailures() {
    std::lock_guard lock(impl_->failuresMutex);
    std::vector<TileFailure> out(std::make_move_iterator(impl_->tileFailures.begin()),
                                 std::make_move_iterator(impl_->tileFailures.end()));
    impl_->tileFailures.clear();
    return out;
}

namespace {

// Queues a command under stateMutex (the caller holds it), so that commands are in sequence order.
void queueLocked(Master::Impl& s, Command&& cmd) {
    std::lock_guard lock(s.m);
    s.commands.push_back(std::move(cmd));
}

// O(1) in the size of the scene: the change is applied to the application's state and queued;
// nothing is copied, serialised or hashed whole.
// `files`: ones the change names that the state does not hold yet; they join it with the change.
void pushUpdate(Master::Impl& s, Change change, std::vector<Asset> files = {}) {
    {
        std::lock_guard lock(s.stateMutex);
        applyChange(s.scene, change);  // throws for an index out of range, before anything changed
        for (Asset& file : files)
            if (!s.findAsset(file.first.path)) s.addAsset(std::move(file));
        if (!std::holds_alternative<TransformChange>(change))
            s.stochasticStale = true;
        ++s.seq;
        Command cmd{.kind = Command::kUpdate};
        cmd.update.seq = s.seq;
        cmd.update.baseSeq = s.seq - 1;
        cmd.update.changes.push_back(std::move(change));
        queueLocked(s, std::move(cmd));
    }
    s.wake();
}

}  // namespace

// The next mono frame's view, not an update: it reaches the clients in that frame's FrameBegin.
void Master::setCamera(const CameraDesc& camera) {
    std::lock_guard lock(impl_->stateMutex);
    impl_->camera = camera;
    ++impl_->cameraMoves;
}
void Master::setInstanceTransform(uint32_t instance, const Transform& t) { pushUpdate(*impl_, TransformChange{instance, t}); }
void Master::setInstanceVisibility(uint32_t instance, Visibility v) { pushUpdate(*impl_, VisibilityChange{instance, v}); }
void Master::setMaterial(uint32_t material, const Material& value) {
    // The change names its files by hash. One the scene did not load is read now (an unreadable
    // file throws here, before anything changed) and travels like the snapshot's: each client
    // fetches it by hash unless it has the same bytes already.
    Impl& s = *impl_;
    MaterialChange change{material, value, {}};
    std::vector<Asset> fresh;
    for (const std::string& path : filesNamedBy(value)) {
        std::optional<AssetRef> known;
        {
            std::lock_guard lock(s.stateMutex);
            if (const AssetRef* a = s.findAsset(path)) known = *a;
        }
        if (known) {
            change.files.push_back(*known);
        } else {
            auto asset = readAsset(path, s.scene.files);
            change.files.push_back(asset.first);
            fresh.push_back(std::move(asset));
        }
    }
    pushUpdate(s, std::move(change), std::move(fresh));
}
void Master::setLight(uint32_t light, const Light& value) { pushUpdate(*impl_, LightChange{light, value}); }
void Master::setRenderSettings(const RenderSettings& settings) { pushUpdate(*impl_, SettingsChange{settings}); }
void Master::setSection(uint32_t section, const SectionPlane& plane) {
    // What the clients' decoders would refuse is refused here, before anything changed.
    const Float3 &p = plane.point, &n = plane.normal, &c = plane.capColor;
    for (float v : {p.x, p.y, p.z, n.x, n.y, n.z})
        if (!std::isfinite(v)) throw std::invalid_argument("section " + std::to_string(section) + " is not finite");
    if (!(n.x * n.x + n.y * n.y + n.z * n.z > 0.0f))
        throw std::invalid_argument("section " + std::to_string(section) + " has a zero normal");
    for (float v : {c.x, c.y, c.z})
        if (!(v >= 0.0f && v <= 1.0f))
            throw std::invalid_argument("section " + std::to_string(section) + ": cap colour outside [0, 1]");
    pushUpdate(*impl_, SectionChange{section, plane});
}

void Master::setCodec(const CodecSettings& codec) {
    Impl& s = *impl_;
    {
        std::lock_guard lock(s.stateMutex);
        ++s.seq;
        Command cmd{.kind = Command::kCodec, .codec = codec};
        cmd.update.seq = s.seq;
        cmd.update.baseSeq = s.seq - 1;
        queueLocked(s, std::move(cmd));
    }
    s.wake();
}

void Master::setViews(std::vector<FrameView> views, uint64_t tag) {
    if (views.size() > kMaxViews) throw InputError("a frame has at most " + std::to_string(kMaxViews) + " views");
    Impl& s = *impl_;
    std::lock_guard lock(s.stateMutex);
    s.views = std::move(views);
    s.viewsTag = tag;
}

Image Master::renderFrame(FrameReport* report, std::vector<float>* linear) {
    std::vector<std::vector<float>> views;
    if (linear) views.emplace_back().swap(*linear);  // the caller's buffer goes round for a later frame
    std::vector<Image> images = renderViews(report, linear ? &views : nullptr);
    if (linear) {
        linear->clear();
        if (!views.empty()) linear->swap(views.front());
    }
    return std::move(images.front());
}

std::vector<Image> Master::renderViews(FrameReport* report, std::vector<std::vector<float>>* linear) {
    Impl& s = *impl_;
    auto begin = [&] {
        const uint32_t frame = ++s.lastBegun;
        {
            // The frame renders the state as it is now; later updates belong to later frames.
            // O(1): the network thread brings its copy of the state up to this sequence number.
            std::lock_guard lock(s.stateMutex);
            Command cmd{.kind = Command::kBeginFrame, .frame = frame, .settings = s.scene.settings};
            cmd.update.seq = s.seq;
            if (s.stochasticStale) {
                s.stateStochastic = rendersStochastically(s.scene);
                s.stochasticStale = false;
            }
            cmd.stochastic = s.stateStochastic;
            cmd.views = s.views;
            cmd.viewsTag = s.viewsTag;
            cmd.camera = s.camera;
            // Each update and each camera move once: the sequence numbers reports gave when the
            // camera was an update (frames of one state and one camera accumulate).
            cmd.shownSeq = s.seq + s.cameraMoves;
            if (cmd.stochastic && s.settings.wideAccumulation) cmd.pixels = TilePixels::LinearHalf;
            queueLocked(s, std::move(cmd));
        }
        s.wake();
        s.inFlight = true;
        return frame;
    };
    auto wait = [&](uint32_t frame) {
        std::unique_lock lock(s.m);
        // Never a silent hang: with no render client at all for a while, the frame cannot end.
        const auto patience = std::chrono::milliseconds(std::max(5000, 2 * s.settings.timeoutMs));
        auto lastSeenClients = std::chrono::steady_clock::now();
        while (!s.cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return s.completedFrame >= frame; })) {
            if (const std::atomic<bool>* flag = s.stopFlag.load(); flag && flag->load()) {
                std::fprintf(stderr, "rtwall master: stopped while frame %u was rendering (%d clients ready)\n", frame,
                             s.readyClients);
                throw Cancelled();
            }
            const auto now = std::chrono::steady_clock::now();
            if (s.readyClients > 0) lastSeenClients = now;
            else if (now - lastSeenClients > patience)
                throw std::runtime_error("frame " + std::to_string(frame) + " cannot finish: no render client is connected");
        }
        s.inFlight = false;
        if (report) *report = s.completedReport;
        if (linear) {
            for (std::vector<float>& l : *linear) l.clear();
            linear->swap(s.completedLinear);  // the caller's buffers come back for a later frame
        }
        return std::move(s.completedImages);
    };
    if (!s.settings.async) return wait(begin());
    // Asynchronous: finish the frame in flight, start the next at once (it carries every update
    // made so far), and return the finished one while the clients already render its successor.
    const uint32_t waitFor = s.inFlight ? s.lastBegun : begin();
    std::vector<Image> img = wait(waitFor);
    begin();
    return img;
}

MasterCounters Master::counters() const { return impl_->countersNow(); }
uint64_t Master::droppedMessages() const { return counters().dropped(); }
uint64_t Master::resyncs() const { return impl_->resyncCount.load(); }
uint64_t Master::failedSends() const { return counters().failedSends; }
uint64_t Master::injectedUpdateLosses() const { return impl_->injectedLosses.load(); }
uint64_t Master::refusedConnections() const { return impl_->zap ? impl_->zap->denied() : 0; }

}  // namespace rtwall

namespace rtwall {

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
