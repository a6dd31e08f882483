// A render client (runClient): one network thread (the caller's) owns the DEALER socket to the
// master; render threads share one scene, take tiles from a local queue and hand encoded results
// back through inproc PUSH sockets, so only the network thread ever touches the master's
// connection. ClientRuntime's jobs are in one file each:
//
//   client.cpp         runClient, the runtime's start and stop
//   client_link.cpp    the link to the master: connecting, the network loop, what comes in
//   client_nodes.cpp   display nodes: a link to each, tiles sent straight to them
//   client_scene.cpp   the scene cache: meshes and files by hash, snapshots, updates, the build
//   client_render.cpp  render work: frames, assignments, the render threads, stalls, replay
#pragma once

#include "codec.h"
#include "link_socket.h"
#include "net.h"
#include "protocol.h"
#include "scene_state.h"
#include "security.h"
#include "update_sequencer.h"

#include <rtwall/cluster.h>
#include <rtwall/cluster_testing.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <thread>
#include <vector>

namespace rtwall::cluster {

class ClientRuntime {
public:
    explicit ClientRuntime(const ClientSettings& s);
    int run();

private:
    static constexpr const char* kResultsAddress = "inproc://rtwall-client-results";

    // A frame's views and tiling (FrameBegin::views: one view for a mono frame), shared by its
    // work items and never changed once made: a render thread reads it without a lock.
    struct FrameLayout {
        std::vector<Camera> cameras;  // per view, at the frame's resolution, with its warps: made once per frame
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
        bool depth = false;  // its frame asked for depth (FrameBegin::depth)
        uint8_t features = 0;  // and these features (FrameBegin::features)
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

    // Applies the buffered updates up to `seq`. CannotRender: an update is missing (a resync is
    // requested) or our state is already newer. Busy: a render thread is still inside the scene
    // (a stuck one holds it for good); the frame is tried again later, this thread never waits.
    enum class CatchUp { Done, CannotRender, Busy };

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

    std::string failure() {
        std::lock_guard lock(workMutex_);
        return failure_;
    }
    std::optional<TileFailed> failedTile() {
        std::lock_guard lock(workMutex_);
        return failedTile_;
    }

    // The link to the master (client_link.cpp): connecting, the network loop, what comes in.
    void connect();
    int networkLoop();
    void forwardResults(int max);
    std::optional<int> handle(const zmq::message_t& msg);
    void drop();
    void readMonitor();
    std::string handshakeNote() const;

    // Display nodes (client_nodes.cpp): a link to each, tiles sent straight to them.
    void onNodeList(const NodeList& list);
    void readNodeMonitors();
    void onTileRoutes(TileRoutes routes);
    void sendToNodes(const zmq::message_t& msg);

    // The scene cache (client_scene.cpp): meshes and files by hash, snapshots, updates, the build.
    std::shared_ptr<const TriangleMesh> localMesh(const MeshRef& ref);
    std::shared_ptr<const std::vector<uint8_t>> localAsset(const AssetRef& ref);
    void fetchFilesOf(const Update& u);
    void forgetPendingFiles();
    bool updateFilesMissing() const;
    void onAssetData(AssetData ad);
    void onSnapshot(SceneSnapshot snap);
    void onMeshData(MeshData md);
    void tryBuildScene();
    void finishBuild();
    void setRenderSettings(const RenderSettings& fromMaster);
    void requestResync();
    CatchUp catchUp(uint32_t seq);

    // Render work (client_render.cpp): frames, assignments, the render threads, stalls.
    void onFrameBegin(const FrameBegin& fb);
    void onAssign(const TileAssign& a);
    void dropWork();
    void watchStalls();
    bool replaySend(zmq::socket_t& out, const Work& w);
    void sendResult(zmq::socket_t& out, const std::vector<uint8_t>& bytes);
    void maybeStall(uint32_t frame);
    void encodeResult(const Work& w, const TileRect& r, const std::vector<uint8_t>& pixels, const std::vector<float>& linear,
                      const std::vector<float>& depth, const FeatureView& features, std::vector<uint8_t>& scratch,
                      TileResult& result);
    void workerLoop(Slot& slot);

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
    bool frameDepth_ = false;  // the current frame asked for depth, copied into each Work
    uint8_t frameFeatures_ = 0;  // and these features
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
    std::atomic<uint64_t> depthsOut_{0};  // for ClientFaults::corruptEveryNthDepth
    // Tiles this client holds: queued, being rendered, or rendered and not yet handed to the
    // master's connection. 0 = idle (Heartbeat::idle).
    std::atomic<int64_t> held_{0};
    uint32_t assignFrame_ = 0;  // the newest frame it was assigned tiles for
    uint32_t assignSeen_ = 0;   // tiles of that frame's assignments that arrived
    SocketMonitor monitor_;     // handshake events of dealer_
    struct NodeLink {
        std::string endpoint, serverKey;
        zmq::socket_t socket;
        std::string name;
        SocketMonitor monitor;  // handshake events of socket (with CURVE)
        bool said = false;      // its handshake trouble was said
    };
    std::map<uint32_t, NodeLink> nodeLinks_;  // display nodes by index (bit in the tile masks)
    std::map<uint32_t, std::vector<uint64_t>> tileRoutes_;  // tile masks by their first frame; empty: no nodes
    uint64_t monitorSeq_ = 0;
    MasterHandshakeWatch handshakes_{"client", "rtwall client"};  // the last failed handshake, said when giving up
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
    std::vector<std::shared_ptr<const PixelWarp>> warpGrids_;  // the master's WarpGrids (network thread)
    bool saidWarpGrid_ = false;  // a frame naming a grid this client lacks was said once
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

    // A tile's encoded result as replay mode sends it again.
    struct Replayed {
        TileCodec codec = TileCodec::Raw;
        std::vector<uint8_t> pixels, depth;  // depth: empty when its frame did not ask for it
    };
    std::mutex replayMutex_;
    std::map<uint32_t, Replayed> replay_;  // by tile

    std::mutex workMutex_;
    std::condition_variable workCv_;
    std::deque<Work> work_;
    bool stopping_ = false;
    std::vector<std::thread> workers_;
};

}  // namespace rtwall::cluster
