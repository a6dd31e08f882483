// rtwall cluster: the one public header.
//
// A Master owns the scene state and the wall's framebuffer; render clients (other processes,
// on this PC or others) connect over ZeroMQ, ask for tiles, render them with the engine's
// renderTile() and send the pixels back. Scheduling and frame assembly are plain classes
// (cluster/src/scheduler.h; FrameAssembler in rtwall/frame.h) that never see a socket.
#pragma once

#include <rtwall/engine.h>
#include <rtwall/frame.h>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace rtwall {

// Test hooks, null outside tests: rtwall/cluster_testing.h.
struct MasterFaults;
struct ClientFaults;

enum class TileCodec : uint8_t { Raw = 0, Lz4 = 1, Zstd = 2, Jpeg = 3 };

// "raw", "lz4", "zstd", "jpeg" and back; an unknown name is an InputError.
TileCodec tileCodecFromName(const std::string& name);
const char* tileCodecName(TileCodec codec);

struct CodecSettings {
    TileCodec codec = TileCodec::Lz4;
    int jpegQuality = 90;         // 1..100
    bool jpegSubsample = false;   // 4:2:0 chroma subsampling (else 4:4:4)
    int zstdLevel = 1;            // 1..19
    bool operator==(const CodecSettings&) const = default;
};

// A wall on several display PCs (issue 19): render clients send each tile straight to the
// display nodes whose screens show it; the master carries only control and a small ack per
// tile, and releases frame N to every node at once (a swap barrier). No names: the master is the
// only display, as before.
struct DisplayNodeSettings {
    std::vector<std::string> names;  // the wall's nodes (WallConfig::nodes()); bit i of a tile mask is names[i]
    std::string wallText;            // the wall config each node is sent (it presents its own screens)
    // The node mask of every tile of a width x height frame in tiles of tileSize (makeTiles
    // order; with views, viewTiles order). The wall library builds it from TileRouting: the
    // cluster knows nothing of screens.
    std::function<std::vector<uint64_t>(int width, int height, int tileSize, const std::vector<FrameView>& views)> routes;
    // The eye of each view of a multi-view frame (-1 mono, 0 left, 1 right), in setViews' order:
    // a node composes its eyes' images from the views as the single-PC wall does. A view beyond
    // the list is taken as mono (the node's left image).
    std::vector<int> viewEyes;
    double stallSeconds = 0.5;  // a node this late for a frame the others hold is left out of it (SwapBarrier)
    // Re-projection (issue 27): the nodes show frames at every Master::presentPose, each warped
    // to that pose, instead of at their swaps. Frames then need depth (ClusterSettings::depth).
    bool reproject = false;
};

// One refresh of a re-projecting wall on display nodes, as the master saw it answered
// (Master::takeNodeRefreshes).
struct NodeRefreshDelay {
    uint32_t refresh = 0;
    std::string node;
    double askedAt = 0;  // when Master::presentPose was called: steady_clock seconds since its epoch
    // From Master::presentPose to the node's NodeShown: the pose's way to the node, its warp and
    // presentation, and one hop back.
    double milliseconds = 0;
};

// What the display nodes show, as one picture (Master::nodePicture; the operator console's
// thumbnail and screenshot of a wall on nodes, issue 31).
inline constexpr int kNodePictureEveryPixel = 16384;  // the largest width asked: at least any frame's, so every pixel
struct NodePicture {
    uint32_t frame = 0;     // the newest frame among the answers (0: no node presented one yet)
    bool oneFrame = true;   // every node that answered with pixels presented that frame
    Image left, right;      // each eye box-filtered to the width asked (rtwall/image_box.h); right empty: mono
    // The wall's nodes not in it: not there, presented nothing yet, did not answer in time, or
    // answered wrong (a part dropped: their pixels black or partly there).
    std::vector<std::string> missing;
};

struct ClusterSettings {
    std::string bind = "tcp://127.0.0.1:0";  // master endpoint; port 0 picks a free port
    int localClients = 2;                     // client processes `rtwall run` spawns on this PC
    int threadsPerClient = 1;                 // render threads per client (0 = hardware threads)
    int prefetch = 4;                         // tiles each client keeps in flight
    bool affinity = true;                     // same tiles to the same client next frame
    bool async = true;                        // specify frame N+1 while N renders
    CodecSettings codec;
    int heartbeatMs = 250;                    // both directions
    int timeoutMs = 3000;                     // a silent peer is dead after this (clients learn it in Welcome)
    int highWaterMark = 1000;                 // messages queued per peer and direction; a peer whose queue is full is dropped
    double stragglerFactor = 4.0;             // re-issue tiles outstanding this many median tile times
    // Frames of a stochastic scene (rendersStochastically: GI, area lights, ...) travel as linear
    // half-float tiles, so that averaging them (progressive refinement) has no 8-bit bias and
    // equals one machine's Accumulator::addLinear exactly. They cost about twice the bytes of
    // 8-bit tiles (JPEG is replaced by LZ4 for them); off: 8-bit tiles, accumulated as 8-bit.
    bool wideAccumulation = true;
    // Depth with every tile (issue 27), for re-projection on the display side: the clients send
    // each tile's depth (distance along the primary ray, 16-bit log code, zstd; about 0.5 MB per
    // 1600x1200 frame of the demo scene, docs/benchmarks.md) and renderViews/renderFrame give it per
    // view, as do display nodes. Off: nothing changes, the same bytes on the wire and images.
    bool depth = false;
    // The denoiser's features with every tile of a linear frame (issue 28; FeatureBits of
    // rtwall/feature_codec.h, featureBitsFor the denoise mode; needs depth): renderViews gives
    // each view's (FeatureImages), for the compositor's denoiser. 0: none, nothing changes.
    uint8_t features = 0;
    // Security: with a key pair every link is CURVE-encrypted and only the listed client public
    // keys get in. Without keys the master listens on loopback only, unless `insecure`.
    std::filesystem::path keyFile;                  // the master's key pair (rtwall keys)
    std::vector<std::filesystem::path> clientKeys;  // public key files of the clients allowed in
    bool insecure = false;
    DisplayNodeSettings displayNodes;
    // A calibrated wall's projector grids (issue 30): each client gets them once, right after its
    // Welcome; the views' warps (FrameView::warps) name them by index.
    std::vector<std::shared_ptr<const PixelWarp>> warpGrids;
    std::shared_ptr<const MasterFaults> faults;  // null outside tests (rtwall/cluster_testing.h)
};

// What the master dropped, refused or could not send, by kind, since it started
// (Master::counters, FrameReport::counters). Every message a peer sends that the master does not
// use is counted exactly once, in one of the first six kinds; the first few of each kind are
// logged with the peer's address.
struct MasterCounters {
    uint64_t malformed = 0;         // not an rtwall message: bad header or payload, or more than one frame
    uint64_t unknownPeer = 0;       // well-formed, but from a peer that is not a client (no hello, dropped, another session)
    uint64_t stale = 0;             // for a frame that is no longer current (late results after a fault or a re-issue)
    uint64_t replayed = 0;          // a repeat of what the client sent before (Ready, mesh, file and resync requests)
    uint64_t unexpected = 0;        // a type clients never send, a result for a tile never handed to that client, ...
    uint64_t undecodableTiles = 0;  // results whose pixels did not decode (the tile is rendered again)
    uint64_t refused = 0;           // handshakes refused: keys not in the config (ZAP), other protocol versions
    uint64_t failedHandshakes = 0;  // connections that broke off in the ZMTP handshake (garbage, wrong mechanism or server key)
    uint64_t failedSends = 0;       // messages not sent: a peer's queue was full, or it was gone
    uint64_t lostHandOuts = 0;      // tiles whose result will never come (the client holds none of them): handed out again
    uint64_t stalledTiles = 0;      // tiles a client reported stuck on a render thread: handed out again
    uint64_t clientsDropped = 0;    // clients that left or were dropped (goodbye, timeout, gone, queue full too long)
    uint64_t dropped() const { return malformed + unknownPeer + stale + replayed + unexpected + undecodableTiles; }
};
// What was counted between two readings (later - earlier), member by member.
MasterCounters operator-(MasterCounters later, const MasterCounters& earlier);
// One line for an operator: "dropped 12 messages (3 malformed, 9 from unknown peers), ..." or
// "nothing dropped, refused or lost".
std::string describeCounters(const MasterCounters& c);

// Frames of several views (FrameView, ViewTile, viewTiles): rtwall/frame.h.

struct ClientReport {
    uint32_t id = 0;
    uint64_t tiles = 0;         // results accepted this frame
    uint64_t stolen = 0;        // of which taken from another client's queue
    uint64_t bytes = 0;         // encoded tile bytes of its accepted results
    double busyFraction = 0;    // render time / frame time
};

struct FrameReport {
    uint32_t frame = 0;
    uint32_t stateSeq = 0;          // the scene state and camera the frame shows: changes with every update and setCamera
    uint32_t sceneSeq = 0;          // the scene state alone: changes with every update, not with a camera move
    double seconds = 0;             // from frame begin to the last tile
    uint64_t bytes = 0;             // encoded tile bytes received
    uint64_t tilesStolen = 0;
    uint64_t tilesReissued = 0;     // straggler re-issues
    uint64_t duplicatesDropped = 0; // results for tiles already done
    uint64_t staleDropped = 0;      // results for an older frame
    uint64_t affinityHits = 0;      // tiles rendered by last frame's client
    double meanTileLatency = 0;     // seconds from assignment to result
    std::vector<ClientReport> clients;
    std::vector<uint32_t> tileOwners;  // client id that rendered each tile (makeTiles order; of a multi-view frame: viewTiles order); UINT32_MAX: none
    bool stochastic = false;        // the frame's state renders stochastically: frames of one state refine by averaging
    bool linear = false;            // its tiles came as linear half floats (renderFrame can give them)
    bool depth = false;             // its tiles came with depth (ClusterSettings::depth; renderFrame gives it)
    uint8_t features = 0;           // and these features (ClusterSettings::features, on linear frames only)
    CameraDesc camera;              // the camera of its first view (of a mono frame: its camera)
    size_t views = 0;               // images of a multi-view frame (0: one, the state's camera)
    uint64_t viewsTag = 0;          // the tag of the setViews the frame was rendered with
    MasterCounters counters;        // the master's counters when the frame completed
    // With display nodes: the frame's pixels went to the nodes (renderViews' images are empty),
    // `bytes` counts what the clients sent to them, and the swap barrier's figures so far.
    size_t displayNodes = 0;        // nodes connected when the frame completed
    uint64_t swapsReleased = 0;     // frames the barrier released to the nodes
    uint64_t nodesLeftOut = 0;      // times a node was left out of a frame for stalling
    double lastSwapSkew = 0;        // seconds between the first and last node's swap of the newest swapped frame
    double maxSwapSkew = 0;
};

// The differential updates that turn scene `before` into `after` (a scene file edited while the
// wall runs: `rtwall run --watch`). Objects are compared as they travel to the clients, so a
// change counts exactly when it would change what they render. What updates cannot express is
// listed in `refused`, one line each: other meshes or mesh contents, other numbers of materials,
// lights or instances, an instance's mesh or material, the BVH settings, the origin.
struct SceneEdit {
    std::vector<std::pair<uint32_t, Material>> materials;
    std::vector<std::pair<uint32_t, Light>> lights;
    std::vector<std::pair<uint32_t, Transform>> transforms;
    std::vector<std::pair<uint32_t, Visibility>> visibility;  // [parts] edits
    std::optional<RenderSettings> settings;
    std::optional<CameraDesc> camera;  // the first camera, when it changed
    std::vector<std::pair<uint32_t, SectionPlane>> sections;  // slots whose plane changed
    std::optional<DenoiseSettings> denoise;  // the display side's denoiser: applied there, never sent
    std::vector<std::string> refused;
    bool empty() const {
        return materials.empty() && lights.empty() && transforms.empty() && visibility.empty() && !settings && !camera &&
               sections.empty() && !denoise &&
               refused.empty();
    }
};
SceneEdit diffScenes(const SceneDesc& before, const SceneDesc& after);

// The display master: owns the scene state, hands out tiles, assembles frames.
// A tile a render client could not render (its engine threw a TileError; the client left after
// saying so), with what decides the tile's pixels as the master knows it: the state of the frame
// (its camera and render settings) and the client's packet width. Everything a replay needs
// (replayCommand) but where the scene came from, which the application knows.
struct TileFailure {
    uint32_t client = 0;      // its id (the client view's colour)
    uint32_t frame = 0;
    uint32_t tile = 0;        // index in the frame's tiling (makeTiles)
    TileRect rect;
    std::string reason;       // the engine's (TileError::reason)
    CameraDesc camera;        // the frame's
    RenderSettings settings;  // the frame's
    int packetWidth = 0;      // the client's rays per Embree packet
};

class Master {
public:
    Master(const SceneDesc& scene, const ClusterSettings& settings);
    ~Master();
    Master(const Master&) = delete;
    Master& operator=(const Master&) = delete;

    std::string endpoint() const;  // where clients connect, with the bound port
    int connectedClients() const;  // clients that hold the current scene state
    bool waitForClients(int count, int timeoutMs);
    // Waits for `wanted` clients, but goes on with fewer once at least one is there and no other
    // joined for `settleMs` (a local client that died or froze while starting must not keep the
    // wall dark). Returns how many are there (0 when none came within timeoutMs).
    int awaitClients(int wanted, int timeoutMs, int settleMs);

    // While *flag is true, renderFrame, waitForClients and awaitClients give up within 100 ms by
    // throwing Cancelled (a signal handler sets the flag: Ctrl-C during a frame that cannot
    // finish). The flag must outlive the master.
    void setStopFlag(const std::atomic<bool>* flag);

    // Display nodes (ClusterSettings::displayNodes): the names of those there now (joined and
    // not gone), in the wall's order; and a wait until every node of the wall is there (false
    // after timeoutMs; Cancelled when the stop flag is set, as awaitClients).
    std::vector<std::string> displayNodesPresent() const;
    bool waitForDisplayNodes(int timeoutMs);

    // Arguments for `rtwall client` processes this master starts on its own PC
    // (ClusterSettings::localClients): with keys, a key pair made for this session (in a private
    // temporary directory, removed with the master; its public key is allowed) and the master's
    // public key. Empty without keys.
    std::vector<std::string> localClientArgs() const;

    // Tiles that clients failed since the last call, oldest first (the 64 newest are kept).
    std::vector<TileFailure> takeTileFailures();

    // The camera of the mono frames (those without setViews' views): the next frame begun
    // carries it to the clients in its FrameBegin, as a multi-view frame carries its views. Not
    // an update, but FrameReport::stateSeq moves on with it as with one (an accumulation of a
    // still view restarts).
    void setCamera(const CameraDesc& camera);
    // Differential scene updates: only what changes is sent to the clients. They take effect
    // in the next frame that begins after the call. Each costs the same whatever the scene's
    // size: nothing is copied, serialised or hashed whole (a state is hashed when it is sent).
    void setInstanceTransform(uint32_t instance, const Transform& transform);
    void setInstanceVisibility(uint32_t instance, Visibility visibility);  // hide, show, highlight
    void setMaterial(uint32_t material, const Material& value);
    void setLight(uint32_t light, const Light& value);
    void setRenderSettings(const RenderSettings& settings);
    // Section plane slot `section`: throws for a slot >= kMaxSections and (std::invalid_argument)
    // for a plane that is not finite, has a zero normal or a cap colour outside [0, 1].
    void setSection(uint32_t section, const SectionPlane& plane);
    // Changes the tile codec of every client from their next tile on (a Welcome within the
    // session carries it); results in flight keep their own codec, which each result names.
    // It counts as a state change (FrameReport::stateSeq moves on): with a lossy codec the
    // frames change, so an accumulation must restart.
    void setCodec(const CodecSettings& codec);

    // Renders one frame with the current state and returns it. With async on, the next
    // frame's updates already stream to the clients while this one renders. When the frame came
    // as linear tiles (report->linear), `linear` receives it in linear RGB (3 floats a pixel,
    // each exactly a half float), for Accumulator::addLinear; otherwise it is emptied. With
    // ClusterSettings::depth, `depth` receives the frame's depth (width * height floats,
    // row-major: each pixel's decodeDepth(encodeDepth(d)), kBackgroundDepth for background);
    // otherwise it is emptied.
    Image renderFrame(FrameReport* report = nullptr, std::vector<float>* linear = nullptr,
                      std::vector<float>* depth = nullptr);

    // Frames of several views in one scheduler pass (both eyes, a CAVE's planes): each frame
    // begun after the call renders viewTiles(views) and renderViews gives one image per view, in
    // this order. Like an update, it takes effect in the next frame that begins: with async on,
    // renderViews returns the frame begun before (its report's viewsTag says which views it
    // shows: the caller's tag, e.g. the tracker packet behind its head pose) and begins one with
    // these. Views are not scene state: a new eye camera moves no sequence number. Empty views:
    // mono frames of setCamera's camera, one image (renderFrame), as before any call.
    // `roomEyes` (issue 30): the eyes (left, right) the views were made from, in the wall's room
    // coordinates, for display nodes that post-warp their screens (DisplayNodeRun::roomEyes).
    void setViews(std::vector<FrameView> views, uint64_t tag = 0, std::optional<std::array<Float3, 2>> roomEyes = {});
    // With display nodes (issue 28): the frames begun after the call are denoised on the nodes
    // with these settings, each window of the wall (DisplayNodeRun::denoiseWindows) with `ring`
    // pixels around it (ComposeFrame::denoiseRing), when their tiles carry the mode's features
    // (ClusterSettings::features, linear frames). Mode off (the default): not denoised. Without
    // nodes the application filters its own frames and this does nothing. While a mode is set
    // and nodes are present, renderViews begins a frame only once the one two before it was
    // swapped (each node's history is the frame before; it holds two), waiting at most 3 s.
    void setDenoise(const DenoiseSettings& settings, int ring);
    // A frame as renderFrame, one image per view of the frame (one without views); a view's
    // pixels outside its regions' tiles are unspecified. With linear tiles `linear` receives
    // each view's linear RGB; with ClusterSettings::depth `depth` each view's depth as
    // renderFrame's, NaN outside its regions' tiles (a hole to the warp). Both are emptied
    // otherwise, and with display nodes (the pixels are on the nodes).
    // With features (ClusterSettings::features) on a linear frame, `features` receives each
    // view's (zero outside its regions' tiles), else it is emptied.
    std::vector<Image> renderViews(FrameReport* report = nullptr, std::vector<std::vector<float>>* linear = nullptr,
                                   std::vector<std::vector<float>>* depth = nullptr,
                                   std::vector<FeatureImages>* features = nullptr);

    // With display nodes: waits until the swap barrier has released frame `frame` or a later
    // one to the nodes (true), or timeoutMs passed (false). A benchmark paces frames by it, so
    // that one frame at a time is in flight to the nodes (a node keeps two: the newest and the
    // one before).
    bool waitForSwap(uint32_t frame, int timeoutMs);

    // Re-projection on display nodes (DisplayNodeSettings::reproject; issue 27): every node shows
    // the newest frame the swap barrier released, warped from its views' cameras to `cameras`
    // (one per view of that frame: the head pose read just before this call), the same pose on
    // every node. For the application's display loop, once per refresh; returns at once (the
    // network thread sends it, ahead of any queued command). A pose not yet sent is replaced by a
    // newer one; nothing is sent before the first release. `debug` tints warped, filled and fresh
    // pixels on the nodes.
    // `roomEyes`: the eyes of `cameras` in the room, as setViews' (post-warping nodes).
    void presentPose(std::span<const CameraDesc> cameras, bool debug = false, std::optional<std::array<Float3, 2>> roomEyes = {});
    // The refreshes the nodes answered since the last call, oldest first (at most 4096 kept).
    std::vector<NodeRefreshDelay> takeNodeRefreshes();

    // A picture of what the display nodes present now (issue 31): every node present is asked
    // for the frame it presented last, box-filtered to `width` pixels across each eye (at least
    // the frame's width: every pixel, as the single-PC wall holds it); each pixel is summed by
    // one node only (DisplayNodeRun::previewOwners), so the picture is the single-PC wall's
    // box-filtered frame byte for byte where every node presented the same frame. Waits at most
    // timeoutMs for the answers, on the calling thread (any thread; at most 8 at once). nullopt:
    // no display node is present, or 8 pictures are already being taken.
    std::optional<NodePicture> nodePicture(int width, int timeoutMs);

    MasterCounters counters() const;
    uint64_t droppedMessages() const;  // counters().dropped()
    uint64_t failedSends() const;      // counters().failedSends
    uint64_t injectedUpdateLosses() const;  // update messages dropped by MasterFaults::dropEveryNthUpdate (tests)
    uint64_t resyncs() const;          // full states sent again after a client found a gap
    uint64_t refusedConnections() const;  // CURVE clients whose key is not in the config

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

// What a running client counts, for tests and monitoring (ClientSettings::counters).
struct ClientCounters {
    std::atomic<uint64_t> droppedMessages{0};  // malformed (multi-frame included), stale, replayed or unexpected
    std::atomic<uint64_t> rejectedAssets{0};   // texture or volume bytes from the master that do not match their hash
    std::atomic<uint64_t> assetsReceived{0};   // texture or volume files received from the master (and accepted)
    std::atomic<uint64_t> assetsLocal{0};      // found on this PC (at the material's path or in the cache) with the right hash
    std::atomic<uint64_t> droppedAssignments{0};  // assigned tiles beyond what a client queues (a master gone mad)
    std::atomic<uint64_t> stalledTiles{0};     // tiles reported to the master as stuck on a render thread
    std::atomic<uint64_t> refusedHandshakes{0};  // the master refused this client's key (CURVE)
    std::atomic<uint64_t> failedHandshakes{0};   // other broken handshakes (no CURVE on one side, wrong server key)
};

struct ClientSettings {
    std::string connect;                // tcp://HOST:PORT
    int threads = 0;                    // render threads, 0 = hardware threads
    int packetWidth = 0;                // rays per Embree packet: 0 = this CPU's widest, or 4, 8, 16
    std::filesystem::path cacheDir;     // meshes, textures and volumes received from the master, by content hash
    int maxReconnectMs = 5000;          // back-off ceiling
    int exitAfterIdleMs = 0;            // > 0: exit when no master answers for this long
    bool replay = false;                // benchmarks: render each tile once, then resend its bytes
    // A tile rendering longer than max(minStallMs, 16 x this client's mean tile time) is
    // reported to the master, which hands it to another client (or another thread of this one).
    int minStallMs = 1000;
    std::filesystem::path keyFile;      // this client's key pair: CURVE on (needs serverKeyFile)
    std::filesystem::path serverKeyFile;  // the master's public key: the client checks it
    std::shared_ptr<ClientCounters> counters;  // optional: updated while it runs
    std::shared_ptr<const ClientFaults> faults;  // null outside tests (rtwall/cluster_testing.h)
};

// Render-client processes on this PC: `EXECUTABLE client --connect ENDPOINT ...` children (the
// same executable by default, so client and master speak the same protocol version), stopped
// (SIGTERM and SIGCONT, then SIGKILL after 2 s) when the object goes away.
class LocalClients {
public:
    // With a netns prefix, client i runs in network namespace <prefix><i> (tools/netem.sh).
    LocalClients(int count, const std::string& endpoint, int threadsEach, bool replay = false,
                 const std::string& netnsPrefix = {}, const std::vector<std::string>& extraArgs = {},
                 const std::filesystem::path& executable = "/proc/self/exe");
    ~LocalClients();
    LocalClients(const LocalClients&) = delete;
    LocalClients& operator=(const LocalClients&) = delete;
    const std::vector<int>& pids() const { return pids_; }

private:
    std::vector<int> pids_;
};

// Display-node processes on this PC (a wall on several display nodes run on one machine):
// `EXECUTABLE display --connect ENDPOINT --node NAME ...` children, one per name, stopped as
// LocalClients are. Node NAME opens its windows, or writes its screens to outDir/NAME (headless, or
// where it finds no display). A node that ends
// while the wall runs is said by takeEnded(), never waited for.
class LocalDisplayNodes {
public:
    struct Options {
        bool headless = true;
        std::filesystem::path outDir = "out/frames";  // each node's screens in outDir/NAME, headless or without a display
        std::vector<std::string> extraArgs;          // e.g. Master::localClientArgs()
        std::filesystem::path executable = "/proc/self/exe";
    };
    LocalDisplayNodes(const std::vector<std::string>& names, const std::string& endpoint, const Options& options);
    ~LocalDisplayNodes();
    LocalDisplayNodes(const LocalDisplayNodes&) = delete;
    LocalDisplayNodes& operator=(const LocalDisplayNodes&) = delete;

    // One line per node process that ended since the last call: its name, pid and how it ended
    // (exit status or signal).
    std::vector<std::string> takeEnded();
    size_t running() const;
    int pid(const std::string& name) const;  // 0: no such node or it ended
    // Waits (bounded) for every node to end on its own, as each does on the master's goodbye
    // after showing the frames before it; true when none runs. The destructor's SIGTERM could
    // otherwise stop a node between the last swap's release and its reading of that swap.
    bool awaitEnd(int timeoutMs);

private:
    struct Child {
        std::string name;
        int pid = 0;
        bool ended = false;
        int status = 0;
    };
    std::vector<Child> children_;
    std::vector<std::string> endedLines_;
    void reap(bool block);
};

// Writes a new CURVE key pair to STEM.key (secret, mode 0600) and STEM.pub (public).
void writeNewKeyPair(const std::filesystem::path& stem);

// ---- Display nodes (issue 19) -------------------------------------------------------------------

// A display node: one PC of a wall whose screens are spread over several. It joins the master
// (NodeHello), takes the tiles its screens show straight from the render clients on a ROUTER of
// its own, says when it holds a frame and presents it when the master's swap barrier releases
// it. What it presents, and how, is the caller's (the wall library: rtwall display).
struct DisplayNodeRun {
    std::string connect;                  // the master, tcp://HOST:PORT
    std::string name;                     // this node's name in the wall config
    std::string bind = "tcp://127.0.0.1:0";  // where the clients send tiles (port 0: a free one); told to the master
    // The host the render clients reach the node at (the master tells them tcp://ADVERTISE:PORT,
    // PORT the bound one). Empty: the bound address, which must then not be a wildcard.
    std::string advertise;
    // CURVE, as for a render client (ClientSettings): the node joins the master with this key pair
    // (its public key in the master's client_keys) and checks the master's public key; its tile
    // socket is then a CURVE server with a key pair made for the run (its public key reaches the
    // clients through the master) and lets in only the client keys the master gives it.
    std::filesystem::path keyFile;
    std::filesystem::path serverKeyFile;
    std::shared_ptr<struct DisplayNodeCounters> counters;  // optional: updated while it runs
    int exitAfterIdleMs = 0;              // > 0: exit when no master answers for this long
    int frames = 0;                       // > 0: exit after presenting this many frames it held (tests, benchmarks)
    const std::atomic<bool>* stop = nullptr;  // set: say goodbye and return 0
    // The master's wall config text, on every (re)join, before any frame: the caller sets up its
    // screens. An exception ends the node with its message.
    std::function<void(const std::string& wallText)> onWall;
    // Frame `frame` is released: `left` is the whole wall image (the mono one, or the left eye's)
    // with this node's tiles in it, `right` the right eye's of a stereo frame (else null), each
    // accumulated over the frames of a still view of a stochastic scene as the single-PC wall
    // does; both null when this node does not hold that frame (it was left out). `leftOut` names
    // the nodes the wall did not wait for.
    std::function<void(uint32_t frame, const Image* left, const Image* right, const std::vector<std::string>& leftOut)> present;
    // Optional (issue 27): a frame this node holds whose tiles came with depth
    // (ClusterSettings::depth), when it becomes what the node shows (before its swap): each
    // view's depth (width * height floats, as Master::renderViews gives it), NaN outside the
    // tiles routed to this node. Valid during the call.
    std::function<void(uint32_t frame, const std::vector<std::vector<float>>& views)> depth;
    // Re-projection (the master's welcome says the wall re-projects; issue 27): a frame is not
    // presented at its swap but becomes the warp's newest source there, and at every pose the
    // master sends (NodePose, each refresh) this is called to show it warped to that pose.
    // Unset: the node warps on the CPU (Compositor::reproject) and calls `present` with the
    // warped eyes.
    std::function<void(const struct NodeRefresh&)> refresh;
    // Optional (issue 30): the eyes, in the wall's room coordinates, that the frame about to be
    // presented (or the pose about to be shown) was made for, when the master gave them
    // (Master::setViews, presentPose): called just before `present` or `refresh`. A post-warping
    // wall's node resamples its screens from them.
    std::function<void(const std::array<Float3, 2>& roomEyes)> roomEyes;
    // Denoising (issue 28; the master's setDenoise): the windows of a width x height frame with
    // these views (none: one image) and eyes that this node shows, per view: the rects it
    // filters, each with the ring of pixels the master gives (ComposeFrame::denoiseWindows).
    // The wall library gives its screens' windows (TileRouting::denoiseWindows), so that a node
    // filters them to the single-PC wall's bytes. Unset: each view is one window.
    std::function<std::vector<std::vector<TileRect>>(int width, int height, const std::vector<FrameView>& views,
                                                     const std::vector<int>& eyes, unsigned node)>
        denoiseWindows;
    // The operator console's picture of the wall (issue 31; Master::nodePicture): which node
    // owns each pixel of the width x height eye image `eye` (0 left or mono, 1 right) when the
    // nodes `nodes` (their bits) are asked: the lowest-numbered of them whose screens show it,
    // 0xFF where none does; one byte a pixel, row-major. The node sums the pixels it owns of the
    // frame it presented last. The wall library gives its screens' (TileRouting::owners).
    // Unset: the node answers with no pixels.
    std::function<std::vector<uint8_t>(int width, int height, int eye, uint64_t nodes)> previewOwners;
};

// One refresh of a re-projecting display node (DisplayNodeRun::refresh), valid during the call.
struct NodeRefresh {
    uint32_t refresh = 0;  // the master's count
    uint32_t frame = 0;    // the frame shown: the newest released frame this node holds
    // Holds that frame's views with depth, and the frame before: Compositor::reproject(targets,
    // {}, debug) gives the eyes; a GPU presenter warps its sources (newestSource, olderSource).
    Compositor* compositor = nullptr;
    std::span<const CameraDesc> targets;  // one per view: the master's pose
    bool debug = false;                   // tint warped, filled and fresh pixels
    const std::vector<std::string>* leftOut = nullptr;  // the nodes the wall did not wait for at that frame's swap
};

struct DisplayNodeCounters {
    std::atomic<uint64_t> refusedClients{0};     // tile connections whose key the master did not give (ZAP)
    std::atomic<uint64_t> refusedHandshakes{0};  // the master refused this node's key
    std::atomic<uint64_t> failedHandshakes{0};   // other broken handshakes with the master (no CURVE on one side, wrong server key)
    std::atomic<uint64_t> droppedMessages{0};    // malformed or unexpected messages from the master or on the tile socket
    std::atomic<uint64_t> refreshes{0};          // re-projecting: poses shown
    std::atomic<uint64_t> skippedPoses{0};       // re-projecting: poses not shown (no frame yet, or not one camera per view)
    std::atomic<uint64_t> supersededPoses{0};    // re-projecting: poses not shown because a newer one was already there
};

// The endpoint a node bound at `bound` (tcp://HOST:PORT, as ZMQ_LAST_ENDPOINT gives it) tells
// the clients: tcp://ADVERTISE:PORT, or `bound` itself without `advertise`. Throws InputError
// for a wildcard bind (0.0.0.0, *, [::]) without `advertise`, and for an advertised host that
// is not a host name, an IPv4 address or a bracketed IPv6 address.
std::string advertisedNodeEndpoint(const std::string& bound, const std::string& advertise);

// Runs a display node until the master says goodbye, `frames` are presented, the stop flag is
// set or no master answers for exitAfterIdleMs. Returns the process exit status.
int runDisplayNode(const DisplayNodeRun& run);

// Runs a render client until the master says goodbye (or exitAfterIdleMs passes).
// Returns the process exit status.
int runClient(const ClientSettings& settings);


// ---- Tile profiles and the cluster simulation (speed against accuracy) -------------------------

// What each tile of a scene costs, measured on this PC: render time per tile (one thread, so a
// client with T threads renders T tiles at a time at this speed), and for every codec its
// encoded size and encode/decode times. Recorded by profileTiles, stored as TOML
// (writeTileProfile), replayed by simulateCluster.
struct TileProfile {
    std::string scene;  // for the record
    int width = 0, height = 0, tileSize = 0;
    std::vector<std::vector<double>> renderSeconds;  // [frame][tile]: renderTile on one thread, CPU seconds
    struct CodecCost {
        CodecSettings codec;
        std::vector<uint32_t> bytes;        // [tile] encoded size (frame 0)
        std::vector<double> encodeSeconds;  // [tile] on the client, one thread
        std::vector<double> decodeSeconds;  // [tile] on the master, one thread
    };
    std::vector<CodecCost> codecs;
    size_t tileCount() const { return renderSeconds.empty() ? 0 : renderSeconds.front().size(); }
};

// Renders one frame per camera, tile by tile on the calling thread, timing every renderTile
// call; then encodes and decodes frame 0's tiles with every codec. `lossless` receives frame
// 0's image, `decoded` (when given) frame 0 as the master would assemble it with each codec.
TileProfile profileTiles(const Scene& scene, const std::vector<CameraDesc>& cameras, const RenderSettings& settings,
                         const std::vector<CodecSettings>& codecs, Image* lossless = nullptr,
                         std::vector<Image>* decoded = nullptr);

// An image as it arrives at the master through a codec, tile by tile; `bytes` gets the total size.
Image codecRoundTrip(const Image& image, int tileSize, const CodecSettings& codec, uint64_t* bytes = nullptr);

void writeTileProfile(const TileProfile& profile, const std::filesystem::path& file);  // throws InputError
TileProfile readTileProfile(const std::filesystem::path& file);                         // throws InputError

// One direction of a link: rate and one-way latency, with optional latency spikes (a message
// is delayed by spikeSeconds with probability spikeProbability; order is kept, as with TCP).
struct SimLink {
    double bitsPerSecond = 0;  // 0 = unlimited
    double latencySeconds = 0;
    double spikeProbability = 0;
    double spikeSeconds = 0;
};

struct SimConfig {
    int clients = 1;
    int threadsPerClient = 1;
    double clientSpeed = 1.0;        // render and encode times are divided by this
    int prefetch = 4;
    bool affinity = true;
    double stragglerFactor = 4.0;
    size_t codec = 0;                // index into TileProfile::codecs
    SimLink clientLink;              // every client's own link to the switch
    double masterBitsPerSecond = 0;  // the master's uplink, shared by all results (0 = unlimited)
    double masterSecondsPerMessage = 0;  // the master's network thread, per message handled
    int decodeThreads = 2;           // the master's decode pool
    double decodeSpeed = 1.0;        // decode times are divided by this
    uint32_t messageOverheadBytes = 0;  // header bytes per result message on the wire
    double housekeepingSeconds = 0.002;  // the master re-serves waiting clients this often (stragglers)
    // > 0: the clients' render threads, the master's network thread and its decode threads all
    // share this many cores (local clients on the master's PC), each thread at most one core,
    // the cores shared equally among the running threads (processor sharing, as the kernel's
    // fair scheduler does). 0: every client has its own machine and the master its own cores.
    // May be fractional: the share of the PC the cluster's processes get beside other jobs.
    double hostCores = 0;
    double hostBackgroundThreads = 0;  // with hostCores: other jobs' runnable threads, always competing
    // Host costs outside the render threads and the network thread's per-message cost, as
    // measured by `rtwall bench cluster` (its cpu_per_frame, per thread): a client's CPU per result
    // besides rendering and encoding it (its network thread, ZeroMQ's I/O thread, the kernel's
    // TCP send), spent after the render and before the result leaves; the master's per result
    // before its network thread sees it (ZeroMQ's I/O thread and the kernel's receive: one
    // thread, results queue for it); and the master's per frame after the last decode (the
    // caller takes the assembled frame). With hostCores they run on the shared cores; without,
    // they are delays on machines with a core to spare.
    double clientSecondsPerResult = 0, clientSecondsPerByte = 0;
    double masterSecondsPerResult = 0, masterSecondsPerByte = 0;
    double masterSecondsPerFrame = 0;
    // Display nodes (issue 19). 0: the master takes every result, as above. K > 0: a client
    // sends each result over its own link once per node of the tile's mask, each copy through
    // that node's link (FIFO, pipelined as the master's link) to the node's decode threads, and
    // then a header-sized ack to the master, which decodes nothing. A frame is swapped when the
    // last ack is in and the slowest node has decoded its last tile (the barrier), a round trip
    // later (NodeHave up, NodeSwap down); the next frame begins then (the benchmark's pacing).
    // Nodes are machines of their own (not on hostCores).
    int displayNodes = 0;
    std::vector<uint64_t> tileNodes;  // per tile, its node mask; empty: columnNodeMasks of the profile's frame
    double nodeBitsPerSecond = 0;     // each node's link (0 = unlimited)
    int nodeDecodeThreads = 1;
    int frames = 10;                 // measured frames
    int warmupFrames = 1;            // frames run first and not reported (affinity needs one)
    uint64_t seed = 1;               // latency spikes and the scheduler's steal victims
};

struct SimReport {
    std::vector<double> frameSeconds;  // measured frames
    double fps = 0;                    // frames / their total time
    double bytesPerFrame = 0;          // result bytes on the master's link
    double masterLinkLoad = 0;         // busy fraction of the master's link (0 when unlimited)
    double maxClientLinkLoad = 0;      // busiest client link
    double masterCpuLoad = 0;          // busy fraction of the master's network thread
    std::vector<double> clientUtilisation;  // render threads' busy fraction, per client
    double meanUtilisation = 0;
    double stolenPerFrame = 0, reissuedPerFrame = 0, duplicatesPerFrame = 0;
    double affinityHitFraction = 0;    // of the measured frames' tiles
    // With display nodes: result bytes each node receives per frame (bytesPerFrame is their
    // sum: a tile shown by two nodes counts twice), the busiest node link's load, and the mean
    // time per frame between the first and the slowest node holding all its tiles.
    std::vector<double> nodeBytesPerFrame;
    double maxNodeLinkLoad = 0;
    double meanBarrierWait = 0;
};

// The node masks of a wall whose nodes drive equal runs of columns, node 0 leftmost: a tile goes
// to every node whose columns [i * width / nodes, (i + 1) * width / nodes) it overlaps (two at a
// boundary that cuts it). makeTiles order.
std::vector<uint64_t> columnNodeMasks(int width, int height, int tileSize, int nodes);

// Event-driven, deterministic simulation of the master's TileScheduler (the same class, same
// calls as the master: request on a client's credits, complete on each result, housekeeping
// re-serves) against simulated clients and links fed with a tile profile. Frames follow each
// other as in `rtwall run`: FrameBegin, TileRequest(prefetch), assignments, results.
SimReport simulateCluster(const TileProfile& profile, const SimConfig& config);

}  // namespace rtwall
