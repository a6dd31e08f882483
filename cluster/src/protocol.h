// The rtwall wire protocol, version 20 (2 added the master's peer timeout to Welcome; 3 added
// materials, area lights and shading settings; 4 added vertex colours to meshes, the scene's
// origin and [bvh] settings to the snapshot, spherical and cylindrical texture mappings, texture
// and volume files by content hash (AssetRequest, AssetData, SceneSnapshot::assets) and linear
// half-float tiles for accumulation (FrameBegin::pixels, TileResult::pixels); 5 added texture
// coordinates to meshes, the uv and auto texture mappings and Material::bumpMapping; 6 added
// Material::twoSided and Light::twoSided, which side emits; 7 added the client's work report to
// Heartbeat (the frame, the tiles of its assignments that arrived, and whether it holds any tile:
// the master releases hand-outs an idle client no longer holds) and TileStalled (a render thread
// stuck on a tile); 8 added TileFailed (a tile whose rendering threw, before the client leaves);
// 9 added section planes and instance visibility (SceneSnapshot::sections, SectionChange,
// InstanceDesc::visibility, VisibilityChange); 10 added the views of a multi-view frame to FrameBegin
// (each view's camera and image regions: both eyes of a stereo wall, a CAVE's planes, in one
// scheduler pass; no views: the state's camera, 4 bytes more); 11 added display nodes (issue 19):
// the node <-> master messages NodeHello to NodeSwapped, and for clients NodeList, TileRoutes and
// TileDone: tiles go straight from the clients to the nodes that show them, the master gets a
// small ack); 12 added CURVE to the node links (NodeWelcome::clientKeys: the client keys a node's
// tile socket lets in) and to NodeFrame the frame's views with each view's eye (a node assembles
// one image per view and composes the eyes, as the single-PC wall does) and what a node needs to
// accumulate a stochastic frame as the single-PC wall does (whether it is stochastic, and its
// state's sequence number); 13 made FrameBegin the one route of the viewer's camera to the
// clients (issue 26): every frame carries its views, a mono frame one view; CameraChange and the
// snapshot's camera are gone (the camera is not scene state: it moves no sequence number); 14
// added depth with every tile (issue 27): FrameBegin::depth and NodeFrame::depth ask for it,
// TileResult::depth carries it. Each is the last field of its message and left out when off, so
// that a frame without depth travels byte for byte as in version 13; 15 added re-projection on
// the display nodes (issue 27): NodeWelcome::reproject, NodePose (every refresh, the cameras to
// warp the newest released frame to) and NodeShown (a node showed that refresh); 16 added the
// denoiser's features with tiles (issue 28: FrameBegin::features, TileResult::features); 17 let
// display nodes denoise their screens (NodeFrame::denoise); 18 added calibrated projectors
// (issue 30): WarpGrids (a wall's projector grids, once after the Welcome) and FrameView::warps;
// 19 added Material::alphaMode, alphaChannel and opacity (glTF's MASK and BLEND, issue 29); 20
// added pictures of what the display nodes show (issue 31: the operator console's thumbnail and
// screenshot of a wall on nodes): NodePreviewAsk and NodePreview, and InstanceDesc::movable
// (issue 29: an instance in the moving top level from the start); 21 added the eyes a frame was
// rendered for, in the wall's room, to NodeFrame and NodePose (issue 30: display nodes that
// post-warp a calibrated wall's screens resample from them): in NodeFrame a byte now says which
// of its optional parts (depth, denoise settings, eyes) follow; in NodePose they are last.
//
// Every message is one ZeroMQ frame: a fixed 32-byte little-endian header, then a payload whose
// layout depends on the type. Each message type is a plain struct with one fields() function that
// describes it for both directions (message_fields.h; protocol_*.cpp by message family), so its
// encoder and decoder are one piece of code; encodeMessage() measures and writes with the same
// code. Decoders check every length and range before touching data and throw DecodeError; the
// caller drops the message and counts it.
//
// Header: magic "RTWL" (u32 0x4C575452), protocol version (u16), type (u16), session (u64),
// frame (u32), scene version = update sequence number (u32), payload length (u32), reserved (u32, 0).
#pragma once

#include "wire.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace rtwall::cluster {

inline constexpr uint32_t kMagic = 0x4C575452u;
inline constexpr uint16_t kProtocolVersion = 21;  // 21: the frame's eyes to post-warping display nodes
inline constexpr size_t kHeaderSize = 32;

// Limits every decoder enforces (and ZMQ_MAXMSGSIZE is derived from).
inline constexpr size_t kMaxStringBytes = 4096;
inline constexpr uint32_t kMaxTilesPerMessage = 1 << 16;
inline constexpr uint32_t kMaxChangesPerUpdate = 1 << 16;
inline constexpr uint32_t kMaxSceneObjects = 1 << 24;  // meshes, instances, materials, lights, cameras
inline constexpr uint64_t kMaxMeshBytes = uint64_t(1) << 31;
inline constexpr uint64_t kMaxAssetBytes = uint64_t(1) << 30;  // one texture image or volume file
inline constexpr uint32_t kMaxFilesPerMaterial = 3;  // texture, alpha mask, volume
inline constexpr uint32_t kMaxViews = 64;             // images of one multi-view frame
inline constexpr uint32_t kMaxRegionsPerView = 1024;  // screens a view shows
inline constexpr uint32_t kMaxTimeoutMs = 3'600'000;  // heartbeat and timeout: an hour at most
inline constexpr uint32_t kMaxNodes = 64;                 // display nodes: node sets are 64-bit masks
inline constexpr uint32_t kMaxTilesPerFrame = 1 << 22;    // a 16384-pixel-square frame of 8-pixel tiles
inline constexpr size_t kMaxWallConfigBytes = 1 << 20;    // the wall config text a node is sent
inline constexpr uint32_t kMaxClientKeys = 4096;          // client public keys a node is given
inline constexpr uint32_t kMaxWarpGrids = 1024;           // calibrated projector regions of a wall
inline constexpr uint32_t kMaxWarpSide = 16384;           // a warp grid's width or height
inline constexpr uint64_t kMaxWarpSamples = uint64_t(1) << 26;  // one grid's samples (as the MPCDI reader's bound)
inline constexpr uint32_t kMaxWarpsPerView = 1024;        // warped rectangles one view names

enum class MsgType : uint16_t {
    Hello = 1,          // client -> master
    Welcome = 2,        // master -> client
    SceneSnapshot = 3,  // master -> client: the whole state at one update sequence number
    MeshRequest = 4,    // client -> master
    MeshData = 5,       // master -> client
    Update = 6,         // master -> client: one numbered set of changes
    FrameBegin = 7,     // master -> client
    TileRequest = 8,    // client -> master
    TileAssign = 9,     // master -> client
    TileResult = 10,    // client -> master
    Heartbeat = 11,     // both ways
    Goodbye = 12,       // both ways, with the reason
    Ready = 13,         // client -> master: holds the state at a sequence number with this hash
    ResyncRequest = 14, // client -> master: saw a gap after this sequence number
    AssetRequest = 15,  // client -> master: a texture or volume file by content hash
    AssetData = 16,     // master -> client
    TileStalled = 17,   // client -> master: a render thread has been on this tile far too long
    TileFailed = 18,    // client -> master: rendering this tile threw; the client leaves after it
    // Version 11: display nodes. A node talks to the master's ROUTER like a client does, but
    // opens with NodeHello; the clients send tiles to the nodes' own ROUTERs.
    NodeHello = 19,     // node -> master
    NodeWelcome = 20,   // master -> node
    NodeFrame = 21,     // master -> node: a frame's size and pixel format, before its tiles come
    NodeHave = 22,      // node -> master: it holds every tile of the frame routed to it
    NodeSwap = 23,      // master -> node: present the frame (the barrier released it)
    NodeSwapped = 24,   // node -> master: presented it (for the swap skew)
    NodeList = 25,      // master -> client: where the nodes take tiles
    TileRoutes = 26,    // master -> client and node: each tile's node mask, from a frame on
    TileDone = 27,      // client -> master: a tile went to its nodes (instead of TileResult)
    // Version 15: re-projection on the display nodes (issue 27).
    NodePose = 28,      // master -> node, every refresh: show the newest released frame warped to these cameras
    NodeShown = 29,     // node -> master: it showed that refresh (the master measures the pose's delay)
    // Version 18: calibrated projectors (issue 30).
    WarpGrids = 30,     // master -> client, after each Welcome: the wall's warp grids, which FrameView::warps name
    // Version 20: the operator console's pictures of a wall on display nodes (issue 31).
    NodePreviewAsk = 31,  // master -> node: the cells of the frame it presented, for a picture this wide
    NodePreview = 32,     // node -> master: some of those cells (one eye's rows), in parts
};
inline constexpr uint16_t kMaxMsgType = 32;

struct Header {
    uint16_t version = kProtocolVersion;
    MsgType type = MsgType::Heartbeat;
    uint64_t session = 0;
    uint32_t frame = 0;
    uint32_t sceneVersion = 0;
    uint32_t payloadLength = 0;  // set by encodeMessage
};

using Hash128 = std::array<uint64_t, 2>;

struct Hello {
    uint16_t protocolVersion = kProtocolVersion;
    uint32_t threads = 0;
    std::string host;
    bool operator==(const Hello&) const = default;
};

struct Welcome {
    uint32_t clientId = 0;
    CodecSettings codec;
    uint32_t prefetch = 4;
    uint32_t heartbeatMs = 250;
    uint32_t timeoutMs = 3000;  // the client declares the master dead after this much silence
    bool operator==(const Welcome&) const = default;
};

struct MeshRef {
    std::string name;
    std::string source;  // a path the client may load directly on a shared file system
    Hash128 hash{};      // of the canonical mesh bytes (encodeMesh)
    uint64_t bytes = 0;  // size of those bytes
    bool operator==(const MeshRef&) const = default;
};

// A texture image or volume file a material names, by the path the material uses (the key of
// SceneDesc::files on the client) and the hash of the file's bytes.
struct AssetRef {
    std::string path;
    Hash128 hash{};      // XXH3 128-bit of the file's bytes
    uint64_t bytes = 0;  // the file's size, at most kMaxAssetBytes
    bool operator==(const AssetRef&) const = default;
};

// How a frame's tiles travel: 8-bit sRGB (the displayed frame) or linear RGB as IEEE half
// floats, little-endian (frames that are accumulated: the master sums them in float).
enum class TilePixels : uint8_t { Srgb8 = 0, LinearHalf = 1 };

// The scene without geometry: meshes are referenced by content hash.
struct SceneSnapshot {
    uint32_t updateSeq = 0;
    std::vector<MeshRef> meshes;
    std::vector<Material> materials;
    std::vector<InstanceDesc> instances;
    std::vector<Light> lights;
    RenderSettings settings;
    // Version 4: so that a client builds the same BVHs as the master, and knows where the
    // (rebased) coordinates lie in the world.
    BvhSettings bvh;
    std::array<double, 3> origin{0, 0, 0};
    std::vector<AssetRef> assets;  // every texture image and volume file the materials name
    SectionPlanes sections;        // version 9
    bool operator==(const SceneSnapshot&) const = default;
};

struct MeshRequest {
    Hash128 hash{};
    bool operator==(const MeshRequest&) const = default;
};

struct MeshData {
    Hash128 hash{};
    std::vector<uint8_t> mesh;  // encodeMesh bytes
    bool operator==(const MeshData&) const = default;
};

struct AssetRequest {
    Hash128 hash{};
    bool operator==(const AssetRequest&) const = default;
};

// The file's bytes. The decoder checks the size bound only: the receiver checks the hash, so
// that it can count and report a mismatch.
struct AssetData {
    Hash128 hash{};
    std::vector<uint8_t> bytes;
    bool operator==(const AssetData&) const = default;
};

struct TransformChange {
    uint32_t instance = 0;
    Transform transform;
    bool operator==(const TransformChange&) const = default;
};
struct MaterialChange {
    uint32_t material = 0;
    Material value;
    // Version 5: the texture, alpha and volume files `value` names, by hash, so that a file the
    // scene never loaded reaches the clients like the snapshot's (they fetch it by hash).
    std::vector<AssetRef> files;
    bool operator==(const MaterialChange&) const = default;
};
struct LightChange {
    uint32_t light = 0;
    Light value;
    bool operator==(const LightChange&) const = default;
};
struct SettingsChange {
    RenderSettings settings;
    bool operator==(const SettingsChange&) const = default;
};
// Version 9: one section plane slot (moved, turned, enabled or disabled).
struct SectionChange {
    uint32_t section = 0;  // slot, below kMaxSections
    SectionPlane value;
    bool operator==(const SectionChange&) const = default;
};
// Version 9: hide, show or highlight an instance (parts by name, on the master).
struct VisibilityChange {
    uint32_t instance = 0;
    Visibility visibility = Visibility::Shown;
    bool operator==(const VisibilityChange&) const = default;
};
using Change = std::variant<TransformChange, MaterialChange, LightChange, SettingsChange, SectionChange,
                            VisibilityChange>;

// The changes that take the state from baseSeq to seq. The master merges the updates made
// between two network-thread wake-ups into one (keeping the last change to each object), so a
// burst of application calls costs one message, not thousands.
struct Update {
    uint32_t seq = 0;  // the state's sequence number after applying this update
    std::vector<Change> changes;
    uint32_t baseSeq = 0;  // the state it applies to (seq - 1 unless merged)
    bool operator==(const Update&) const = default;
};

struct FrameBegin {
    uint32_t frame = 0;
    uint32_t updateSeq = 0;  // the frame renders the state at exactly this sequence number
    TilePixels pixels = TilePixels::Srgb8;  // how its tiles are sent
    // The frame's views, 1 to kMaxViews (version 13: the only way a camera reaches a client). Its
    // tiles are viewTiles(views) at the state's resolution and tile size, each rendered with its
    // view's camera; a mono frame is one view without regions (makeTiles order). Per frame, not
    // state: a camera moves at no sequence number.
    std::vector<FrameView> views{};
    // Version 14: every tile's result carries its depth (TileResult::depth). Off, the frame
    // renders and travels exactly as without.
    bool depth = false;
    // Version 16: every tile's result carries these features for the denoiser (FeatureBits,
    // rtwall/feature_codec.h; TileResult::features). Only with depth and linear tiles; 0: none,
    // the frame travels exactly as in version 15.
    uint8_t features = 0;
    bool operator==(const FrameBegin&) const = default;
};

struct TileRequest {
    uint32_t frame = 0;
    uint32_t count = 0;
    bool operator==(const TileRequest&) const = default;
};

struct TileAssign {
    uint32_t frame = 0;
    std::vector<uint32_t> tiles;
    bool operator==(const TileAssign&) const = default;
};

struct TileResult {
    uint32_t frame = 0;
    uint32_t tile = 0;
    TileCodec codec = TileCodec::Raw;
    uint32_t renderMicros = 0;
    std::vector<uint8_t> pixels;  // encoded
    TilePixels format = TilePixels::Srgb8;  // LinearHalf: `pixels` are 6 bytes a pixel before the codec
    // Version 14: the tile's depth when its frame asked for it (FrameBegin::depth), else empty:
    // distance along each pixel's primary ray through the 16-bit log code of rtwall/depth_codec.h,
    // compressed with kDepthCodec (codec.h, encodeDepthTile).
    std::vector<uint8_t> depth{};
    // Version 16: its features when its frame asked for them (FrameBegin::features), else empty:
    // encodeFeatureTile (codec.h), after the depth.
    std::vector<uint8_t> features{};
    bool operator==(const TileResult&) const = default;
};

// A TileResult's fields without a copy of its pixels: what a client that forwards its own
// encoded results to the display nodes reads of one (the message goes on as it is), checked as
// decodePayload<TileResult> checks them. Throws DecodeError.
struct TileResultInfo {
    uint32_t frame = 0;
    uint32_t tile = 0;
    uint32_t renderMicros = 0;
    uint32_t pixelBytes = 0;  // the encoded pixels' length
    uint32_t depthBytes = 0;  // the encoded depth's length (0: none)
    uint32_t featureBytes = 0;  // the encoded features' length (0: none)
};
TileResultInfo peekTileResult(const uint8_t* data, size_t size);
// The largest TileResult message a decoder accepts (header included): ZMQ_MAXMSGSIZE of the
// sockets that take tiles.
size_t maxTileResultBytes();

// From the master all fields are 0. From a client: what it holds, so that the master can tell a
// lost hand-out from a slow one. `tilesSeen` counts the tiles of every assignment for `frame`
// that reached the client (used or not); with `idle` it holds no tile at all (none queued,
// rendering or on its way out). Messages on one connection arrive in order, so when a client
// says idle and has seen every tile the master sent it for the frame, every hand-out still
// awaiting its result is lost: its result was dropped on the way (a full queue) or never made.
struct Heartbeat {
    uint32_t frame = 0;
    uint32_t tilesSeen = 0;
    bool idle = false;
    bool operator==(const Heartbeat&) const = default;
};

// A client's render thread has been on this tile far longer than its tiles take: the master
// logs it and hands the tile to another client (or another thread of this one).
struct TileStalled {
    uint32_t frame = 0;
    uint32_t tile = 0;
    uint32_t elapsedMs = 0;
    bool operator==(const TileStalled&) const = default;
};

// A tile the engine could not render (TileError), sent just before the client's Goodbye: what
// the master needs, with the frame's state, to say how to replay exactly that tile.
struct TileFailed {
    uint32_t frame = 0;
    uint32_t tile = 0;
    TileRect rect;            // the tile's pixels, as the client's tiling has them
    int32_t packetWidth = 0;  // rays per Embree packet the client traced with (4, 8 or 16)
    std::string reason;
};

struct Goodbye {
    std::string reason;
    bool operator==(const Goodbye&) const = default;
};

// -- Display nodes (version 11) ----------------------------------------------------------------

// Node names follow the wall config's rule (1 to 32 letters, digits, '-' or '_'); an endpoint is
// what the clients connect to (tcp://HOST:PORT), at most 256 bytes; a CURVE key is Z85 (40
// characters) or empty (no CURVE).
struct NodeHello {
    uint16_t protocolVersion = kProtocolVersion;
    std::string name;
    std::string endpoint;   // the node's ROUTER for tiles
    std::string publicKey;  // its tile socket's CURVE server key (a pair made for the run), Z85; empty without keys
    bool operator==(const NodeHello&) const = default;
};

// The node's place in the wall: bit `node` of the tile masks, and the whole wall config (the
// node presents nodeWall(wall, name)).
struct NodeWelcome {
    uint32_t node = 0;  // below kMaxNodes
    uint32_t heartbeatMs = 250;
    uint32_t timeoutMs = 3000;
    std::string wall;  // the wall config's TOML text, at most kMaxWallConfigBytes
    // Version 12: with CURVE, the public keys (Z85) of the render clients the master lets in: the
    // node's tile socket takes only these (its ZAP handler). Empty without keys.
    std::vector<std::string> clientKeys{};
    // Version 15: the wall re-projects (issue 27). Frames are no longer shown at their swap but
    // at every NodePose, warped; the swap makes a frame the warp's newest source. Last, and left
    // out when false.
    bool reproject = false;
    bool operator==(const NodeWelcome&) const = default;
};

// Frame `frame` is width x height in tiles of tileSize (makeTiles order; with views, viewTiles
// order), its tiles sent as `pixels`; sent before any of its tiles can reach the node.
// How a display node denoises a frame (NodeFrame::denoise): the settings (mode not off), the
// ring of pixels each window of the wall is filtered with (ComposeFrame::denoiseRing), the
// features its tiles carry (FeatureBits, those of the mode or more), the scene state without
// camera moves (FrameReport::sceneSeq) and, for a frame without views, its camera.
struct NodeDenoise {
    DenoiseSettings settings{};
    int32_t ring = 0;
    uint8_t features = 0;
    uint32_t sceneSeq = 0;
    CameraDesc camera{};
    bool operator==(const NodeDenoise&) const = default;
};

struct NodeFrame {
    uint32_t frame = 0;
    int32_t width = 0;
    int32_t height = 0;
    int32_t tileSize = 0;
    TilePixels pixels = TilePixels::Srgb8;
    // Version 12. A multi-view frame's views (as in its FrameBegin: the node computes the same
    // viewTiles) and each view's eye: -1 the mono image, 0 the left eye's, 1 the right eye's.
    // A view with regions gives its eye those pixels, one without is the eye's whole image.
    std::vector<FrameView> views{};
    std::vector<int8_t> eyes{};  // one per view
    // A stochastic frame refines: the node sums the frames of one state (per view: of one state
    // and one camera) exactly as the single-PC wall does; LinearHalf tiles only come with it.
    bool stochastic = false;
    uint32_t stateSeq = 0;  // the scene state it renders (any change restarts the sums)
    // Version 14: its tiles carry depth (the frame's FrameBegin asked for it), which the node
    // keeps per view beside the images.
    bool depth = false;
    // Version 17: a denoised frame (issue 28): what the node's compositor filters its screens
    // with, as the single-PC wall's does.
    std::optional<NodeDenoise> denoise{};
    // Version 21: the eyes (left, right; a mono frame's twice) its views were made from, in the
    // wall's room coordinates (Master::setViews' roomEyes): a post-warping wall's nodes resample
    // their screens from them (issue 30). Since 21 a byte before these three says which of
    // them follow (each absent alone).
    std::optional<std::array<Float3, 2>> roomEyes{};
    bool operator==(const NodeFrame&) const = default;
};

struct NodeHave {
    uint32_t frame = 0;
    bool operator==(const NodeHave&) const = default;
};

// Present `frame`; `leftOut` names the wall's nodes that do not take part in it (stalled, gone
// or never joined): their screens are dark, and the overlay says which.
struct NodeSwap {
    uint32_t frame = 0;
    std::vector<std::string> leftOut;
    bool operator==(const NodeSwap&) const = default;
};

struct NodeSwapped {
    uint32_t frame = 0;
    bool operator==(const NodeSwapped&) const = default;
};

// Version 15 (issue 27): one refresh of a re-projecting wall. Every node warps `frame`, the
// newest frame the swap barrier released (it got that NodeSwap before this, on the same
// connection), from the cameras it was rendered with to `cameras`, one per view of the frame (the
// head pose the master read just before sending), and shows it at once. One message for every
// node: the screens of one refresh show one frame for one pose.
struct NodePose {
    uint32_t refresh = 0;  // counts up in a session
    uint32_t frame = 0;
    bool debug = false;    // tint warped, filled and fresh pixels (warpDebugColours)
    std::vector<CameraDesc> cameras;
    std::optional<std::array<Float3, 2>> roomEyes{};  // version 21: the eyes of `cameras` in the room (as NodeFrame's)
    bool operator==(const NodePose&) const = default;
};

// The node showed refresh `refresh` (answered right after its presentation).
struct NodeShown {
    uint32_t refresh = 0;
    bool operator==(const NodeShown&) const = default;
};

// A calibrated wall's warp grids (ClusterSettings::warpGrids), sent to each client once right
// after its Welcome: frames name them by index (FrameView::warps). Samples may be NaN (a pixel
// on no screen), never infinite.
struct WarpGrids {
    std::vector<PixelWarp> grids;
    bool operator==(const WarpGrids&) const = default;
};

// Version 20 (issue 31): the master asks the nodes in `nodes` (their bits) for a picture of the
// frame each presented last, `width` cells across each eye (rtwall/image_box.h's BoxGrid; at
// least the frame's width: every pixel). A pixel several of them show is summed by the lowest
// numbered only, so that the sums of all answers add up to the picture of the whole frame.
struct NodePreviewAsk {
    uint32_t id = 0;
    int32_t width = 0;  // 1 to kMaxImageSide
    uint64_t nodes = 0;
    bool operator==(const NodePreviewAsk&) const = default;
};

// The largest part of an answer, before compression: a node sends an eye's cells in row bands
// of at most this many bytes.
inline constexpr size_t kMaxPreviewPartBytes = size_t(1) << 22;

// A part of a node's answer: the cells [x0, x1) x [y0, y1) of one eye's grid (the frame's eye
// images are srcWidth x srcHeight), each cell's red, green and blue sums and pixel count over the
// pixels this node owns, `valueBytes` bytes each, in byte planes (every value's low byte first),
// compressed with zstd. frame 0: it presented nothing yet (no cells, the answer's only part).
struct NodePreview {
    uint32_t id = 0;
    uint32_t frame = 0;
    uint8_t eye = 0;  // 0: left (or mono), 1: right
    int32_t srcWidth = 0, srcHeight = 0;
    int32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    uint8_t valueBytes = 1;  // 1, 2 or 4
    bool last = false;       // the node's last part of this answer
    std::vector<uint8_t> cells;
    bool operator==(const NodePreview&) const = default;
};

struct NodeEndpoint {
    uint32_t node = 0;  // its bit in the tile masks, below kMaxNodes
    std::string name;
    std::string endpoint;
    std::string serverKey;  // Z85, or empty
    bool operator==(const NodeEndpoint&) const = default;
};

// Every connected node (sent whenever one joins or leaves): a client keeps one connection per
// node and sends a tile to every node of its mask that the list has.
struct NodeList {
    std::vector<NodeEndpoint> nodes;
    bool operator==(const NodeList&) const = default;
};

// masks[t]: the nodes that show tile t (bit i: node i), for frames from `frame` on until the next
// TileRoutes. Sent once per frame size or tiling, before that frame's FrameBegin or NodeFrame.
struct TileRoutes {
    uint32_t frame = 0;
    std::vector<uint64_t> masks;  // at most kMaxTilesPerFrame
    bool operator==(const TileRoutes&) const = default;
};

// The client sent tile `tile` of `frame` to its nodes (`bytes` encoded bytes to each): the master
// completes it in the scheduler as it would a TileResult.
struct TileDone {
    uint32_t frame = 0;
    uint32_t tile = 0;
    uint32_t renderMicros = 0;
    uint32_t bytes = 0;
    bool operator==(const TileDone&) const = default;
};

// Whether a name is a node name by the wall config's rule (validNodeName in display.h), for the wire.
bool isNodeName(const std::string& name);

struct Ready {
    uint32_t updateSeq = 0;
    Hash128 stateHash{};
    bool operator==(const Ready&) const = default;
};

struct ResyncRequest {
    uint32_t lastSeq = 0;
    bool operator==(const ResyncRequest&) const = default;
};

// Header alone (for routing before the payload is decoded). Checks magic, length and type
// range; a version mismatch is reported to the caller through header.version, not thrown, so
// that a peer can be told both versions.
Header decodeHeader(const uint8_t* data, size_t size);

// Encoders: the header's payloadLength is filled in.
template <class Msg> std::vector<uint8_t> encodeMessage(Header header, const Msg& msg);

// Decoders: the payload after the header; throw DecodeError.
template <class Msg> Msg decodePayload(const uint8_t* data, size_t size);

// The same from a whole message (header included, already checked by decodeHeader), so that no
// caller steps over the header by hand.
template <class Msg> Msg decodeMessage(const uint8_t* message, size_t size) {
    if (size < kHeaderSize) throw DecodeError("a message of " + std::to_string(size) + " bytes, shorter than its header");
    return decodePayload<Msg>(message + kHeaderSize, size - kHeaderSize);
}

MsgType messageTypeOf(const Hello&);
MsgType messageTypeOf(const Welcome&);
MsgType messageTypeOf(const SceneSnapshot&);
MsgType messageTypeOf(const MeshRequest&);
MsgType messageTypeOf(const MeshData&);
MsgType messageTypeOf(const Update&);
MsgType messageTypeOf(const FrameBegin&);
MsgType messageTypeOf(const TileRequest&);
MsgType messageTypeOf(const TileAssign&);
MsgType messageTypeOf(const TileResult&);
MsgType messageTypeOf(const Heartbeat&);
MsgType messageTypeOf(const Goodbye&);
MsgType messageTypeOf(const Ready&);
MsgType messageTypeOf(const ResyncRequest&);
MsgType messageTypeOf(const AssetRequest&);
MsgType messageTypeOf(const AssetData&);
MsgType messageTypeOf(const TileStalled&);
MsgType messageTypeOf(const TileFailed&);
MsgType messageTypeOf(const NodeHello&);
MsgType messageTypeOf(const NodeWelcome&);
MsgType messageTypeOf(const NodeFrame&);
MsgType messageTypeOf(const NodeHave&);
MsgType messageTypeOf(const NodeSwap&);
MsgType messageTypeOf(const NodeSwapped&);
MsgType messageTypeOf(const NodeList&);
MsgType messageTypeOf(const TileRoutes&);
MsgType messageTypeOf(const TileDone&);
MsgType messageTypeOf(const NodePose&);
MsgType messageTypeOf(const NodeShown&);
MsgType messageTypeOf(const WarpGrids&);
MsgType messageTypeOf(const NodePreviewAsk&);
MsgType messageTypeOf(const NodePreview&);

// Canonical mesh bytes (vertex count, positions, triangle count, indices, normals flag and
// normals, colours flag and RGB bytes, all little-endian), their hash (XXH3 128-bit) and the way back. decodeMesh
// validates counts against the size and every index against the vertex count.
std::vector<uint8_t> encodeMesh(const TriangleMesh& mesh);
TriangleMesh decodeMesh(const uint8_t* data, size_t size);
Hash128 hashBytes(const uint8_t* data, size_t size);

// The bytes a scene value travels as, inside a snapshot or a change (Material, Light, CameraDesc,
// InstanceDesc, RenderSettings): two values render alike for the clients exactly when these are
// equal (scene_state.h's sameOnWire).
template <class T> std::vector<uint8_t> encodeValue(const T& value);

// A hash of everything that affects the image (all of SceneSnapshot except updateSeq, with
// meshes by content hash). Master and client compare it before a client's tiles are accepted.
Hash128 stateHash(const SceneSnapshot& snapshot);

// A snapshot message and the stateHash of the state it carries, from one serialisation: the
// master hashes a state only when it sends it (a client proves what it was sent).
struct EncodedSnapshot {
    std::vector<uint8_t> message;
    Hash128 stateHash{};
};
EncodedSnapshot encodeSnapshot(const Header& header, const SceneSnapshot& snapshot);

}  // namespace rtwall::cluster
