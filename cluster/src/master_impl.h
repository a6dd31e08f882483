// The master's inside (Master::Impl), shared by the files that do its jobs. The network thread
// owns the ROUTER socket, the TileScheduler and the FrameAssembler's claims; the application
// thread talks to it through a command queue and an inproc wake-up socket, so updates stream to
// the clients the moment they are made (asynchronous rendering). Tiles are decoded by a small
// pool of threads straight into the framebuffer.
//
//   master.cpp         the public Master: set-up of the router and its keys, waits, counters
//   master_link.cpp    the network thread's loop: receive, dispatch, send, count, the router's monitor
//   master_peers.cpp   render clients: hello and welcome, proving their state, timeouts, leaving
//   master_scene.cpp   scene state: the application's changes, snapshots, updates, meshes and files
//   master_frames.cpp  frame sequencing: the command queue, beginning and finishing a frame
//   master_tiles.cpp   tile scheduling: hand-outs, results, acks, lost and stuck tiles, failures
//   master_nodes.cpp   display nodes: hello, tile routes, the swap barrier
//   decode_pool.cpp    decoding accepted tiles into the frame
#pragma once

#include "decode_pool.h"
#include "link_socket.h"
#include "net.h"
#include "protocol.h"
#include "scene_state.h"
#include "scheduler.h"
#include "security.h"
#include "swap_barrier.h"

#include <rtwall/cluster.h>
#include <rtwall/cluster_testing.h>
#include <rtwall/image_box.h>

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

namespace rtwall::cluster {

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
    bool needsWarps = false;    // the wall's warp grids did not fit its queue (they go before its state)
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

// A pose Master::presentPose asked for, not yet sent to the nodes.
struct PendingPose {
    std::vector<CameraDesc> cameras;
    bool debug = false;
    std::optional<std::array<Float3, 2>> roomEyes;
    double askedAt = 0;  // nowSeconds()
};

// How many of each kind of dropped message are logged (with the peer's address) before the
// rest are only counted: a flood must not flood the log too.
constexpr uint64_t kLoggedPerKind = 5;

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
    std::optional<std::array<Float3, 2>> roomEyes{};  // kBeginFrame: the views' eyes in the room (setViews)
    CameraDesc camera{};        // kBeginFrame without views: the mono frame's camera (setCamera)
    uint32_t shownSeq = 0;      // kBeginFrame: FrameReport::stateSeq (the state's seq and the camera's moves)
    DenoiseSettings denoise{};  // kBeginFrame: how display nodes denoise it (setDenoise)
    int denoiseRing = 0;
};

using Asset = std::pair<AssetRef, FileBytes>;

// The files a material names: its texture image, alpha-mask image and volume.
std::vector<std::string> filesNamedBy(const Material& m);

// A file a material names, from `files` (SceneDesc::files) when they hold it, else from disk,
// with its hash. Throws InputError naming the file when it cannot be read or is too large.
Asset readAsset(const std::string& path, const decltype(SceneDesc::files)& files);

}  // namespace rtwall::cluster

namespace rtwall {

using namespace cluster;

struct Master::Impl {
    ClusterSettings settings;

    // The application's state, at sequence number seq: the application thread changes it (set*),
    // O(1) per change; clients get the network thread's copy (frameState). stateMutex guards it,
    // seq, the stochastic flag, and the order of the commands it queues (held while queueing).
    struct AppState {
        explicit AppState(const SceneDesc& s) : scene(s) {}
        SceneDesc scene;  // geometry once, shared with nobody
        // The mono frames' camera (setCamera). Not scene state: each frame carries it to the
        // clients in its FrameBegin. Its moves are counted, so that a frame's report says when its
        // camera changed as it says when its state did (accumulation restarts).
        CameraDesc camera;
        uint32_t cameraMoves = 0;
        std::vector<MeshRef> meshRefs;    // constant once the network thread runs, which reads it
        std::vector<AssetRef> assetRefs;  // texture and volume files, read once: clients fetch them by hash
        std::map<Hash128, std::shared_ptr<const std::vector<uint8_t>>> assetBytes;
        mutable std::mutex stateMutex;
        uint32_t seq = 0;              // state sequence number
        std::vector<FrameView> views;  // setViews: what the next frame begun renders
        uint64_t viewsTag = 0;
        std::optional<std::array<Float3, 2>> roomEyes;
        DenoiseSettings denoise;       // setDenoise: how display nodes denoise the next frames
        int denoiseRing = 0;
        // rendersStochastically(scene), recomputed (O(instances)) only after a change that can
        // alter it: a material, light or settings change (it reads which materials instances
        // use, never their transforms).
        bool stateStochastic = false;
        bool stochasticStale = true;
    } app;
    uint64_t session = 0;

    // The sockets and keys (set up by the Master's constructor).
    struct Link {
        zmq::context_t ctx{1};
        std::unique_ptr<ZapHandler> zap;  // before the router: it must answer the first handshake
        std::vector<std::string> allowedKeys;  // with CURVE: the client keys (Z85) let in, which display nodes take too
        zmq::socket_t router{ctx, zmq::socket_type::router};
        SocketMonitor monitor;  // the router's failed handshakes
        zmq::socket_t wakeSend{ctx, zmq::socket_type::pair};
        zmq::socket_t wakeRecv{ctx, zmq::socket_type::pair};
        std::mutex wakeMutex;  // zmq sockets are not thread-safe: one writer at a time
        std::string boundEndpoint;
        std::filesystem::path localKeyDir;  // the local clients' session key pair (removed with the master)
        std::vector<std::string> localArgs;
    } link;

    // The hand-over between the application thread and the network thread.
    std::mutex m;                 // guards commands, the frame hand-over and counters below
    std::condition_variable cv;
    std::deque<Command> commands;
    uint32_t completedFrame = 0;
    std::vector<std::string> presentNodes;  // display nodes there now, in the wall's order (Master::displayNodesPresent)
    std::vector<Image> completedImages;  // one per view
    FrameReport completedReport;
    std::vector<std::vector<float>> completedLinear;  // the completed frame's linear pixels per view, when it had linear tiles
    std::vector<std::vector<float>> completedDepth;   // its depth per view, when its tiles came with depth
    std::vector<FeatureImages> completedFeatures;     // its features per view, when its tiles came with them
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
    uint8_t frameFeatures = 0;  // the current frame's tiles carry these features (linear frames only)
    std::optional<NodeDenoise> frameDenoise;  // with display nodes: how they denoise the current frame
    std::vector<FrameView> frameViews;  // the current frame's views (none: a mono frame of frameCamera)
    uint64_t frameViewsTag = 0;
    std::optional<std::array<Float3, 2>> frameRoomEyes;  // the current frame's views' eyes (setViews)
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
    struct DisplayNodes {
        explicit DisplayNodes(double stallSeconds) : barrier(stallSeconds) {}
        std::map<std::string, NodeState> nodes;
        SwapBarrier barrier;
        std::vector<uint64_t> routes;
        uint32_t routesFrame = UINT32_MAX;  // the first frame `routes` apply to
        std::tuple<int, int, int, std::vector<FrameView>> routesKey;
        size_t tilesDone = 0;  // with nodes: tiles of the current frame acknowledged (TileDone)
        // Re-projection (presentPose): the refreshes sent, and when each was asked for (a ring:
        // an answer older than kPoseRing refreshes is not timed).
        uint32_t refreshes = 0;
        static constexpr size_t kPoseRing = 256;
        std::array<double, kPoseRing> poseAskedAt{};
        // The newest frames begun on the nodes and their sizes: a picture's part must be of one.
        struct FrameSize {
            uint32_t frame = 0;
            int width = 0, height = 0;
        };
        static constexpr size_t kFrameSizes = 64;
        std::deque<FrameSize> frameSizes;
    } display;
    // The newest pose presentPose asked for and the network thread has not sent (newest wins),
    // and the answers for takeNodeRefreshes; both under poseMutex.
    std::mutex poseMutex;
    std::optional<PendingPose> pendingPose;
    std::deque<NodeRefreshDelay> nodeRefreshes;
    // Pictures of what the nodes show (nodePicture, issue 31): asked by the application's
    // threads, sent and collected by the network thread; all under pictureMutex.
    struct PictureEye {
        BoxGrid grid;
        bool direct = false;          // one cell a pixel: the values go straight into `image`
        std::vector<uint32_t> sums;   // otherwise 4 per cell, added over the answers
        Image image;
    };
    struct PictureTake {
        int32_t width = 0;
        bool sent = false;
        uint64_t asked = 0, answered = 0, refused = 0;  // node bits
        uint64_t blank = 0;                             // answered that it presented nothing yet
        int32_t srcWidth = 0, srcHeight = 0;            // the first answer's frame size: every other must match
        PictureEye eyes[2];
        bool stereo = false;
        uint32_t oldest = UINT32_MAX, newest = 0;       // frames of the answers with pixels
    };
    std::mutex pictureMutex;
    std::condition_variable pictureCv;
    std::map<uint32_t, PictureTake> pictures;
    uint32_t nextPicture = 0;
    std::vector<uint8_t> pictureScratch;  // the network thread's
    void sendPictureAsks();
    void onNodePreview(NodeState& n, const NodePreview& part);
    void pictureNodeGone(uint32_t node);  // it left, or sent a malformed part
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
        : settings(cs), app(s), scheduler(SchedulerOptions{cs.affinity, cs.stragglerFactor, 0.05, 1}),
          display(cs.displayNodes.stallSeconds) {}

    ~Impl() {
        if (!link.localKeyDir.empty()) {
            std::error_code ec;
            std::filesystem::remove_all(link.localKeyDir, ec);
        }
    }

    void malformed(const std::string& what) { count(&MasterCounters::malformed, "dropped a malformed message", what); }
    void stale(const std::string& what) { count(&MasterCounters::stale, "dropped a stale message", what); }
    void replayed(const std::string& what) { count(&MasterCounters::replayed, "dropped a repeated message", what); }
    void unexpected(const std::string& what) { count(&MasterCounters::unexpected, "dropped an unexpected message", what); }

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

    // Marks a client for removal; reap() removes it outside any loop over the clients.
    void markDead(ClientState& c, const char* why) {
        if (!c.deathReason) c.deathReason = why;
    }

    template <class Msg> bool sendNode(NodeState& n, const Msg& msg, uint32_t frame = 0) {
        const SendResult r = sendToPeerResult(link.router, n.peer, encodeMessage(header(messageTypeOf(msg), frame), msg));
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

    // Updates are merged and sent at most every kUpdateIntervalSeconds (and always before a
    // frame begins), so a burst of application calls (a script, a dragged object) costs a few
    // messages instead of filling every queue.
    static constexpr double kUpdateIntervalSeconds = 0.002;
    MergedUpdate unsent;         // merged updates not sent yet
    double lastUpdateSent = 0;

    // The link (master_link.cpp): counting and logging what is dropped, sending, the receive loop.
    MasterCounters countersNow() const;
    std::string who() const;
    void count(uint64_t MasterCounters::*kind, const char* kindName, const std::string& what);
    void add(uint64_t MasterCounters::*kind, uint64_t n);
    SendResult sendBytes(ClientState& c, MsgType type, const std::vector<uint8_t>& bytes);
    void wake();
    void handle(zmq::message_t& identity, zmq::message_t& msg);
    void readMonitor();
    void loop();

    // Render clients (master_peers.cpp).
    void reap();
    Welcome welcomeFor(const ClientState& c) const;
    SendResult sendWarpGrids(ClientState& c);
    void sendFrameBegin(ClientState& c);
    void retryPending();
    void onHello(const std::string& peer, const Header& h, const uint8_t* data, size_t size);
    void onReady(ClientState& c, const uint8_t* data, size_t size);
    void checkTimeouts();

    // Scene state on its way to the clients (master_scene.cpp).
    const AssetRef* findAsset(const std::string& path) const;
    void addAsset(Asset asset);
    void sendState(ClientState& c);
    void onMeshRequest(ClientState& c, const uint8_t* data, size_t size);
    void onAssetRequest(ClientState& c, const uint8_t* data, size_t size);
    void onResyncRequest(ClientState& c, const uint8_t* data, size_t size);
    void sendUpdate(const Update& update);
    void flushUpdates();

    // Frame sequencing (master_frames.cpp).
    void beginFrame(Command&& cmd);
    void finishFrameIfDone();
    void reopenFailedTiles();
    bool runCommands();

    // Tile scheduling (master_tiles.cpp).
    void serve(ClientState& c);
    void serveAll();
    void onTileDone(ClientState& c, const Header& h, const TileDone& d);
    void onTileResult(ClientState& c, const Header& h, const uint8_t* data, size_t size);
    void onHeartbeat(ClientState& c, const Heartbeat& hb);
    void onTileStalled(ClientState& c, const TileStalled& st);
    void onTileFailed(ClientState& c, const TileFailed& f);

    // Display nodes (master_nodes.cpp).
    NodeList nodeList() const;
    void sendNodeListToClients();
    void beginNodeFrame(const RenderSettings& rs);
    void sendNodeFrame(NodeState& n, const RenderSettings& rs);
    void onNodeHello(const std::string& peer, const Header& h, const uint8_t* data, size_t size);
    void releaseSwap(std::optional<uint32_t> frame);
    void handleNode(NodeState& n, const Header& h, const uint8_t* payload, size_t payloadSize);
    void reapNodes();
    void publishNodes();
    void nodeHousekeeping();
    void sendPendingPose();
};

// Queues a command under stateMutex (the caller holds it), so that commands are in sequence order.
inline void queueLocked(Master::Impl& s, Command&& cmd) {
    std::lock_guard lock(s.m);
    s.commands.push_back(std::move(cmd));
}

}  // namespace rtwall
