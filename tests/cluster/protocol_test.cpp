// Tests for the protocol (cluster/src/protocol.h, protocol_*.cpp): a round trip per message with every field set, the header
// checks, truncation at every byte, hostile counts, value ranges, meshes and scene state.
#include "protocol.h"
#include "scene_state.h"

#include <gtest/gtest.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <array>
#include <limits>
#include <random>
#include <set>

namespace rtwall::cluster {

// TileFailed is the one message without a defaulted == (the engine's TileRect has none): every
// member compared, the rectangle by its corners.
bool operator==(const TileFailed& a, const TileFailed& b) {
    return a.frame == b.frame && a.tile == b.tile && a.rect.x0 == b.rect.x0 && a.rect.y0 == b.rect.y0 &&
           a.rect.x1 == b.rect.x1 && a.rect.y1 == b.rect.y1 && a.packetWidth == b.packetWidth && a.reason == b.reason;
}

namespace {

// -- Sample values: every field differs from its default ----------------------------------------

Material sampleMaterial(int k) {
    Material m;
    m.name = "material-" + std::to_string(k);
    m.type = k % 2 ? MaterialType::Glass : MaterialType::Phong;
    m.color = {0.25f, 0.5f + 0.01f * float(k), 0.75f};
    m.specular = {0.125f, 0.375f, 1.0f};
    m.shininess = 77.5f + float(k);
    m.ior = 1.33f + 0.1f * float(k);
    // Version 5: the uv and auto mappings, and the bump's own mapping.
    m.texture.mapping = k % 2 ? TextureMapping::Uv : TextureMapping::Spherical;
    m.alpha.mapping = k % 2 ? TextureMapping::Auto : TextureMapping::Uv;
    m.bumpMapping = k % 2 ? TextureMapping::Object : TextureMapping::Uv;
    m.twoSided = true;  // version 6
    m.alphaMode = AlphaMode::Hashed;  // version 19
    m.alphaChannel = AlphaChannel::Alpha;
    m.opacity = 0.375f + 0.125f * float(k);
    return m;
}

Light sampleLight(int k) {
    Light l;
    l.type = k % 2 ? LightType::Directional : LightType::Point;
    l.position = {1.5f, -2.25f, 3.0f + float(k)};
    l.direction = {0.5f, -0.75f, 0.25f};
    l.color = {0.9f, 0.8f, 0.7f};
    l.intensity = 123.5f + float(k);
    l.edge1 = {2.0f, 0.0f, 0.5f};
    l.edge2 = {0.0f, 0.25f, 1.5f + float(k)};
    l.twoSided = true;  // version 6
    return l;
}

CameraDesc sampleCamera() {
    CameraDesc c;
    c.name = "wall-left";
    c.position = {-4.5f, 2.0f, 9.25f};
    c.lookAt = {0.5f, 0.25f, -1.0f};
    c.up = {0.0f, 0.0f, 1.0f};
    c.fovY = 61.5f;
    return c;
}

CameraDesc sampleOffAxisCamera() {
    CameraDesc c = sampleCamera();
    c.name = "wall-left-eye";
    c.window = ProjectionWindow{{-1.25f, -0.75f, 0.5f}, {2.5f, 0.0f, -0.125f}, {0.0f, 1.5f, 0.0f}};
    return c;
}

Transform sampleTransform(int k) {
    Transform t;
    for (size_t i = 0; i < t.m.size(); ++i) t.m[i] = 0.1 * double(i + 1) + 1e-9 * k - 0.5;
    return t;
}

RenderSettings sampleSettings() {
    RenderSettings s;
    s.width = 1920;
    s.height = 1080;
    s.tileSize = 48;
    s.kernel = KernelType::Single;
    s.shading = ShadingMode::EyeLight;
    s.maxDepth = 12;
    s.supersample = 3;
    s.shadows = false;
    s.background = {0.1f, 0.2f, 0.3f};
    s.ambient = {0.05f, 0.06f, 0.07f};
    s.threads = 7;
    return s;
}

Hello sampleHello() { return Hello{7, 12, "render-node-3.local"}; }

Welcome sampleWelcome() {
    Welcome w;
    w.clientId = 42;
    w.codec = CodecSettings{TileCodec::Zstd, 77, true, 9};
    w.prefetch = 6;
    w.heartbeatMs = 125;
    w.timeoutMs = 900;
    return w;
}

SceneSnapshot sampleSnapshot() {
    SceneSnapshot s;
    s.updateSeq = 99;
    s.meshes.push_back(
        MeshRef{"bunny", "/shared/meshes/bunny.ply", {0x0123456789abcdefull, 0xfedcba9876543210ull}, 123456});
    s.meshes.push_back(MeshRef{"floor", "shape:quad", {1, 2}, 200});
    s.materials = {sampleMaterial(0), sampleMaterial(1)};
    s.instances.push_back(InstanceDesc{1, 0, sampleTransform(0)});
    s.instances.push_back(InstanceDesc{0, 1, sampleTransform(1), -1, Visibility::Hidden, true});
    s.lights = {sampleLight(0), sampleLight(1)};
    s.settings = sampleSettings();
    s.bvh = {BvhSettings::Quality::High, true, true, BvhSettings::Primitives::Triangles};
    s.origin = {1e6 + 0.25, -2e5, 3.0e5 + 1.0 / 1024};
    s.assets.push_back({"textures/bark.png", {0x5555666677778888ull, 0x9999aaaabbbbccccull}, 123456});
    s.assets.push_back({"/data/ct.vti", {1, 2}, kMaxAssetBytes});
    return s;
}

MeshData sampleMeshData() {
    MeshData m;
    m.mesh = encodeMesh(makeBox());
    m.hash = hashBytes(m.mesh.data(), m.mesh.size());
    return m;
}

Update sampleUpdate() {
    Update u;
    u.seq = 17;
    u.baseSeq = 12;
    u.changes = {TransformChange{3, sampleTransform(2)}, MaterialChange{5, sampleMaterial(3), {}},
                 MaterialChange{6, sampleMaterial(4), {AssetRef{"tex/rust.png", Hash128{0x1234, 0x5678}, 4096},
                                                       AssetRef{"vol/smoke.vti", Hash128{0x9abc, 0xdef0}, 1 << 20}}},
                 LightChange{2, sampleLight(1)}, SettingsChange{sampleSettings()}, VisibilityChange{4, Visibility::Highlighted}};
    return u;
}

TileResult sampleTileResult() {
    TileResult t;
    t.frame = 57;
    t.tile = 300;
    t.codec = TileCodec::Jpeg;
    t.renderMicros = 4567;
    for (int i = 0; i < 300; ++i) t.pixels.push_back(uint8_t(i * 7));
    t.format = TilePixels::LinearHalf;
    for (int i = 0; i < 70; ++i) t.depth.push_back(uint8_t(i * 5 + 1));  // version 14
    return t;
}

// A Z85 CURVE key (40 characters of the Z85 alphabet).
const std::string kSampleKey = "rq:rM>}U?@Lns47E1%kR.o@n%FcmmsL/@{H8]yf7";

NodeHello sampleNodeHello() { return NodeHello{uint16_t(kProtocolVersion + 1), "left-PC_2", "tcp://10.0.0.7:5600", kSampleKey}; }
NodeWelcome sampleNodeWelcome() {
    return NodeWelcome{63, 100, 2500, "[wall]\nscreens = 2\n", {kSampleKey, "Yne@$w-vo<fVvi]a<NY6T1ed:M$fCG*[IaLV{hID"}};
}
NodeList sampleNodeList() {
    return NodeList{{{0, "left", "tcp://127.0.0.1:5601", ""}, {63, "right", "tcp://127.0.0.1:5602", kSampleKey}}};
}

Header sampleHeader() {
    Header h;
    h.type = MsgType::Goodbye;  // encodeMessage sets the type from the message
    h.session = 0x1122334455667788ull;
    h.frame = 31337;
    h.sceneVersion = 4242;
    h.payloadLength = 12345;  // and the length
    return h;
}

// A stereo CAVE's frame: two views, one of the whole image, one with two regions and a window.
FrameBegin sampleViewsFrameBegin() {
    FrameBegin fb{1235, 100, TilePixels::Srgb8, {}};
    FrameView left;
    left.camera.position = {0.1f, 1.7f, 0.2f};
    left.camera.fovY = 45.0f;
    FrameView right;
    right.camera.position = {0.3f, 1.6f, 0.0f};
    right.camera.window = ProjectionWindow{{-1.5f, 0.0f, -1.5f}, {3.0f, 0.0f, 0.0f}, {0.0f, 2.25f, 0.0f}};
    right.regions = {{0, 0, 1024, 768}, {2048, 0, 1024, 768}};
    right.refWidth = 3072;
    right.refHeight = 768;
    // Version 18: a calibrated projector's rectangle, its grid and where the room is.
    right.warps = {{2, {2048, 0, 1024, 768}, {{1, 2, 3}, {0, 1.7f, 2}, {0, 0, -1}, {0, 1, 0}, {1, 0, 0}, 2.5f}}};
    fb.views = {left, right};
    fb.depth = true;  // version 14
    return fb;
}

// Version 18: a wall's warp grids, one of each kind (finite: NaN never equals itself).
WarpGrids sampleWarpGrids() {
    PixelWarp offsets{PixelWarp::Kind::ScreenOffsets, 2, 1, {{0.5f, -1.0f, 0.0f}, {3.0f, 0.25f, 0.0f}}};
    PixelWarp surface{PixelWarp::Kind::SurfacePoints, 1, 2, {{-1.5f, 0.0f, -2.0f}, {-1.5f, 2.25f, -2.1f}}};
    return {{offsets, surface}};
}

// The same stereo CAVE's frame as a display node is told it (version 12): views, their eyes, and
// that it accumulates.
NodeFrame sampleViewsNodeFrame() {
    NodeFrame f{86, 3072, 768, 64, TilePixels::LinearHalf, sampleViewsFrameBegin().views, {0, 1}, true, 0xA1B2C3D4u, true};
    return f;
}

// A denoised frame on a display node (version 17): every setting off its default.
NodeDenoise sampleNodeDenoise() {
    NodeDenoise d;
    d.settings.mode = DenoiseSettings::Mode::Svgf;
    d.settings.levels = 4;
    d.settings.history = 17;
    d.settings.sigmaDepth = 1.5f;
    d.settings.sigmaNormal = 64.0f;
    d.settings.sigmaLuminance = 3.0f;
    d.ring = 47;
    d.features = kFeatureAll;
    d.sceneSeq = 0x51525354u;
    d.camera = sampleCamera();
    return d;
}
NodeFrame sampleDenoisedNodeFrame() {
    NodeFrame f = sampleViewsNodeFrame();
    f.denoise = sampleNodeDenoise();
    return f;
}

// A post-warping wall's frame (version 21): its eyes in the room, with the denoised frame's parts.
NodeFrame sampleEyesNodeFrame() {
    NodeFrame f = sampleDenoisedNodeFrame();
    f.roomEyes = std::array<Float3, 2>{Float3{-0.0325f, 1.7f, 2.5f}, Float3{0.0325f, 1.7f, 2.5f}};
    return f;
}

// Calls f with every sample message (FrameBegin and NodeFrame twice: mono and with views and
// depth; TileResult with and without depth).
template <class F> void forEachSample(F&& f) {
    f(sampleHello());
    f(sampleWelcome());
    f(sampleSnapshot());
    f(MeshRequest{{0xaaaabbbbccccddddull, 0x1111222233334444ull}});
    f(sampleMeshData());
    f(sampleUpdate());
    f(FrameBegin{1234, 99, TilePixels::LinearHalf, {FrameView{sampleCamera(), {}, 0, 0}}});  // mono: one view
    f(sampleViewsFrameBegin());
    f(TileRequest{55, 8});
    f(TileAssign{56, {0, 7, 1u << 20, 0xFFFFFFFFu}});
    f(sampleTileResult());
    f(TileResult{58, 301, TileCodec::Zstd, 12, {1, 2, 3}});  // without depth (version 14's trailing field left out)
    f(Heartbeat{77, 9, true});
    f(Goodbye{"shutting down: operator request"});
    f(Ready{99, {0x0102030405060708ull, 0x1112131415161718ull}});
    f(ResyncRequest{98});
    f(AssetRequest{{0x0102030405060708ull, 0x1112131415161718ull}});
    f(AssetData{{7, 8}, {1, 2, 3, 4, 5}});
    f(TileStalled{78, 12, 61000});
    f(TileFailed{79, 13, {32, 64, 48, 80}, 8, "injected fault at pixel 40,70"});
    f(sampleNodeHello());
    f(sampleNodeWelcome());
    f(NodeFrame{80, 3840, 2160, 64, TilePixels::LinearHalf, {}, {}, true, 41});
    f(sampleViewsNodeFrame());
    f(sampleDenoisedNodeFrame());
    f(sampleEyesNodeFrame());
    f(NodeHave{81});
    f(NodeSwap{82, {"right", "node-3"}});
    f(NodeSwapped{83});
    f(sampleNodeList());
    f(TileRoutes{84, {1, 3, 0, 0x8000000000000002ull}});
    f(TileDone{85, 14, 2500, 12288});
    f(NodeWelcome{2, 250, 3000, "[wall]\n", {}, true});  // re-projecting (version 15's trailing flag)
    f(NodePose{900, 86, true, {sampleCamera(), sampleCamera()}});
    f(NodePose{901, 86, false, {sampleCamera()}, std::array<Float3, 2>{Float3{-0.03f, 1.7f, 2.5f}, Float3{0.03f, 1.7f, 2.5f}}});
    f(NodeShown{900});
    f(sampleWarpGrids());
    f(NodePreviewAsk{5, 320, 0x3});
    f(NodePreview{5, 86, 1, 1600, 1200, 0, 10, 320, 20, 2, true, {1, 2, 3}});
}

template <class Msg> std::vector<uint8_t> payloadOf(const Msg& msg) {
    const std::vector<uint8_t> bytes = encodeMessage(sampleHeader(), msg);
    return std::vector<uint8_t>(bytes.begin() + kHeaderSize, bytes.end());
}

template <class Msg> Msg decode(const std::vector<uint8_t>& payload) {
    return decodePayload<Msg>(payload.data(), payload.size());
}

// The message comes back with every member equal (the structs' defaulted ==).
template <class Msg> void expectRoundTrip(const Msg& msg) { EXPECT_EQ(decode<Msg>(payloadOf(msg)), msg); }

void putU32(std::vector<uint8_t>& bytes, size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes[at + i] = uint8_t(v >> (8 * i));
}

// -- Round trips ---------------------------------------------------------------------------------

TEST(Protocol, RoundTripEveryMessage) {
    std::set<MsgType> seen;
    forEachSample([&](const auto& msg) {
        using Msg = std::decay_t<decltype(msg)>;
        SCOPED_TRACE("message type " + std::to_string(int(messageTypeOf(msg))));
        seen.insert(messageTypeOf(msg));
        const std::vector<uint8_t> bytes = encodeMessage(sampleHeader(), msg);
        // encodeMessage reserved the counted size; a different written size would have grown the
        // vector past it (and the header's length, which is the counted size, would disagree).
        EXPECT_EQ(bytes.capacity(), bytes.size());
        const Header h = decodeHeader(bytes.data(), bytes.size());
        EXPECT_EQ(h.version, kProtocolVersion);
        EXPECT_EQ(h.type, messageTypeOf(msg));
        EXPECT_EQ(h.session, 0x1122334455667788ull);
        EXPECT_EQ(h.frame, 31337u);
        EXPECT_EQ(h.sceneVersion, 4242u);
        EXPECT_EQ(size_t(h.payloadLength) + kHeaderSize, bytes.size());
        const Msg back = decodePayload<Msg>(bytes.data() + kHeaderSize, bytes.size() - kHeaderSize);
        EXPECT_EQ(back, msg);
        // The encoding is canonical: the decoded message encodes to the same bytes.
        EXPECT_EQ(encodeMessage(sampleHeader(), back), bytes);
    });
    EXPECT_EQ(seen.size(), size_t(kMaxMsgType));
}

TEST(Protocol, RoundTripEmptyAndLimitValues) {
    SceneSnapshot empty;
    expectRoundTrip(empty);
    expectRoundTrip(Update{});
    expectRoundTrip(TileAssign{});
    expectRoundTrip(TileResult{});
    expectRoundTrip(Goodbye{std::string(kMaxStringBytes, 'x')});
    EXPECT_THROW(decode<Goodbye>(payloadOf(Goodbye{std::string(kMaxStringBytes + 1, 'x')})), DecodeError);

    SceneSnapshot edges = sampleSnapshot();
    edges.settings.width = 16384;
    edges.settings.height = 1;
    edges.settings.tileSize = 1024;
    edges.settings.maxDepth = 64;
    edges.settings.supersample = 16;
    edges.settings.threads = 1024;
    edges.materials[0].ior = 1.0f;
    edges.materials[1].ior = 4.0f;
    edges.materials[0].color = {0, 0, 0};
    edges.materials[1].color = {1, 1, 1};
    edges.lights[0].intensity = 0;
    expectRoundTrip(edges);
    FrameBegin wide{7, 3, TilePixels::Srgb8, {FrameView{sampleCamera(), {}, 0, 0}}};
    wide.views[0].camera.fovY = 179.9f;
    expectRoundTrip(wide);
}

// Version 13: a camera reaches a client only as a view of a FrameBegin (a mono frame has one).
TEST(Protocol, RoundTripOffAxisCamera) {
    FrameBegin plain{2, 1, TilePixels::Srgb8, {FrameView{sampleCamera(), {}, 0, 0}}};
    FrameBegin offAxis = plain;
    offAxis.views[0].camera = sampleOffAxisCamera();
    const FrameBegin back = decode<FrameBegin>(payloadOf(offAxis));
    EXPECT_EQ(offAxis, back);
    EXPECT_EQ(back.views[0].camera, sampleOffAxisCamera());
    // The window costs a flag byte plus three Float3s; an absent window costs only the flag.
    EXPECT_EQ(payloadOf(offAxis).size(),
              payloadOf(plain).size() + 36 + (offAxis.views[0].camera.name.size() - plain.views[0].camera.name.size()));
}

// A frame without a view has no camera to render with: the decoder refuses it.
TEST(Protocol, FrameBeginNeedsAView) {
    EXPECT_THROW(decode<FrameBegin>(payloadOf(FrameBegin{2, 1, TilePixels::Srgb8, {}})), DecodeError);
}

TEST(Protocol, EncodeSetsTypeAndLength) {
    Header h = sampleHeader();
    h.type = MsgType::Hello;
    const std::vector<uint8_t> bytes = encodeMessage(h, Goodbye{"x"});
    const Header back = decodeHeader(bytes.data(), bytes.size());
    EXPECT_EQ(back.type, MsgType::Goodbye);
    EXPECT_EQ(back.payloadLength, 5u);
}

TEST(Protocol, GoldenBytes) {
    // The exact layout of a header and a small payload; a change here breaks every deployed peer
    // (version 2: the shading fields of materials, lights and settings; 4: FrameBegin's tile format;
    // 5: the snapshot's BVH primitives; 6: two-sided emission of materials and area lights; 7: the
    // client's work report in Heartbeat, TileStalled; 8: TileFailed; 9: section planes, instance visibility;
    // 10: FrameBegin's views; 11: display nodes; 12: views and accumulation on display nodes; 13:
    // the frame's views are its only camera; 14: depth with every tile, left out when off; 15:
    // re-projection on the display nodes; 16: the denoiser's features, left out when off; 17: how
    // display nodes denoise, left out when off; 18: warp grids and each view's warps; 19: the
    // materials' alpha modes and opacity; 20: pictures of the display nodes' screens; 21: the
    // eyes a frame was made for, to display nodes).
    Header h;
    h.session = 0x0807060504030201ull;
    h.frame = 0x0C0B0A09u;
    h.sceneVersion = 0x100F0E0Du;
    const std::vector<uint8_t> bytes = encodeMessage(h, FrameBegin{0x44332211u, 0x88776655u});
    const std::vector<uint8_t> expected{
        'R',  'T',  'W',  'L',                           // magic 0x4C575452
        0x15, 0x00,                                      // version (21: the frame's eyes to nodes)
        0x07, 0x00,                                      // type FrameBegin
        0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08,  // session
        0x09, 0x0A, 0x0B, 0x0C,                          // frame
        0x0D, 0x0E, 0x0F, 0x10,                          // scene version
        0x0D, 0x00, 0x00, 0x00,                          // payload length
        0x00, 0x00, 0x00, 0x00,                          // reserved
        0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88,  // payload: frame, update sequence
        0x00,                                            // tile pixels: 8-bit sRGB
        0x00, 0x00, 0x00, 0x00,                          // no views (the layout only: a decoder wants one)
    };
    EXPECT_EQ(bytes, expected);
}

// Version 14: depth is each message's last field, there only when asked for, so a frame without
// depth travels as in version 13 (same payload bytes); a flag or a depth that says "none" is not
// a second encoding of the same message.
// Version 16: the denoiser's features, a byte after the depth flag in FrameBegin and a blob after
// the depth in TileResult, each only when asked for; without depth or linear tiles, with bits
// outside 1..7 or empty, refused.
TEST(Protocol, FeaturesAreATrailingFieldAfterTheDepth) {
    const FrameView view{sampleCamera(), {}, 0, 0};
    const std::vector<uint8_t> depthOnly = payloadOf(FrameBegin{5, 4, TilePixels::LinearHalf, {view}, true});
    std::vector<uint8_t> on = depthOnly;
    on.push_back(kFeatureAll);
    EXPECT_EQ(payloadOf(FrameBegin{5, 4, TilePixels::LinearHalf, {view}, true, kFeatureAll}), on);
    EXPECT_EQ(decode<FrameBegin>(on).features, kFeatureAll);
    EXPECT_EQ(decode<FrameBegin>(depthOnly).features, 0);
    for (uint8_t bits : {0, 8, 255}) {
        std::vector<uint8_t> bad = depthOnly;
        bad.push_back(bits);
        EXPECT_THROW(decode<FrameBegin>(bad), DecodeError) << int(bits);
    }
    // Features of an 8-bit frame.
    std::vector<uint8_t> srgb = payloadOf(FrameBegin{5, 4, TilePixels::Srgb8, {view}, true});
    srgb.push_back(kFeatureAll);
    EXPECT_THROW(decode<FrameBegin>(srgb), DecodeError);

    const TileResult withDepth{1, 2, TileCodec::Lz4, 3, {9, 9}, TilePixels::LinearHalf, {0xA1, 0xA2, 0xA3}};
    std::vector<uint8_t> p = payloadOf(withDepth);
    for (uint8_t b : {0x02, 0x00, 0x00, 0x00, 0xB1, 0xB2}) p.push_back(b);
    TileResult withFeatures = withDepth;
    withFeatures.features = {0xB1, 0xB2};
    EXPECT_EQ(payloadOf(withFeatures), p);
    EXPECT_EQ(decode<TileResult>(p), withFeatures);
    const TileResultInfo info = peekTileResult(p.data(), p.size());
    EXPECT_EQ(info.depthBytes, 3u);
    EXPECT_EQ(info.featureBytes, 2u);
    std::vector<uint8_t> empty = payloadOf(withDepth);
    for (uint8_t b : {0x00, 0x00, 0x00, 0x00}) empty.push_back(b);
    EXPECT_THROW(decode<TileResult>(empty), DecodeError);
}

// Version 17: how a display node denoises a frame, after NodeFrame's parts byte (bit 1, since
// version 21), only when it does; never with mode off, without depth or linear tiles, or with
// features the mode lacks.
TEST(Protocol, NodeDenoiseFollowsTheFrameOnlyWhenItDenoises) {
    const NodeFrame plain = sampleViewsNodeFrame();
    const NodeFrame denoised = sampleDenoisedNodeFrame();
    const std::vector<uint8_t> a = payloadOf(plain), b = payloadOf(denoised);
    ASSERT_GT(b.size(), a.size());
    EXPECT_TRUE(std::equal(a.begin(), a.end() - 1, b.begin())) << "the frame's bytes as before, then the block";
    EXPECT_EQ(b[a.size() - 1], a.back() | 0x02) << "the parts byte says so";
    EXPECT_EQ(decode<NodeFrame>(b), denoised);
    auto refused = [&](auto change, const char* what) {
        NodeFrame f = denoised;
        change(f);
        EXPECT_THROW(decode<NodeFrame>(payloadOf(f)), DecodeError) << what;
    };
    refused([](NodeFrame& f) { f.denoise->settings.mode = DenoiseSettings::Mode::Off; }, "mode off");
    refused([](NodeFrame& f) { f.denoise->features = kFeatureNormal | kFeatureId; }, "svgf without albedo");
    refused([](NodeFrame& f) { f.denoise->features = 0; }, "no features");
    refused([](NodeFrame& f) { f.denoise->features = 8; }, "bit 3");
    refused([](NodeFrame& f) { f.denoise->ring = -1; }, "a negative ring");
    refused([](NodeFrame& f) { f.denoise->settings.levels = 11; }, "11 levels");
    refused([](NodeFrame& f) { f.denoise->settings.sigmaLuminance = 0.0f; }, "sigma_luminance 0");
    refused([](NodeFrame& f) { f.denoise->settings.sigmaDepth = std::nanf(""); }, "NaN sigma_depth");
    refused([](NodeFrame& f) { f.pixels = TilePixels::Srgb8; }, "8-bit tiles");
    // Temporal needs only normals and ids.
    NodeFrame temporal = denoised;
    temporal.denoise->settings.mode = DenoiseSettings::Mode::Temporal;
    temporal.denoise->features = kFeatureNormal | kFeatureId;
    EXPECT_EQ(decode<NodeFrame>(payloadOf(temporal)), temporal);
}

TEST(Protocol, DepthIsATrailingFieldLeftOutWhenOff) {
    const FrameView view{sampleCamera(), {}, 0, 0};
    const std::vector<uint8_t> off = payloadOf(FrameBegin{5, 4, TilePixels::Srgb8, {view}});
    std::vector<uint8_t> on = off;
    on.push_back(0x01);
    EXPECT_EQ(payloadOf(FrameBegin{5, 4, TilePixels::Srgb8, {view}, true}), on);
    EXPECT_TRUE(decode<FrameBegin>(on).depth);
    EXPECT_FALSE(decode<FrameBegin>(off).depth);
    std::vector<uint8_t> no = off;
    no.push_back(0x00);
    EXPECT_THROW(decode<FrameBegin>(no), DecodeError);

    const std::vector<uint8_t> plain = payloadOf(TileResult{1, 2, TileCodec::Lz4, 3, {9, 9}});
    EXPECT_EQ(plain.size(), 4u + 4 + 1 + 4 + 4 + 2 + 1);  // version 13's layout
    std::vector<uint8_t> withDepth = plain;
    for (uint8_t b : {0x03, 0x00, 0x00, 0x00, 0xA1, 0xA2, 0xA3}) withDepth.push_back(b);  // u32 length, bytes
    EXPECT_EQ(payloadOf(TileResult{1, 2, TileCodec::Lz4, 3, {9, 9}, TilePixels::Srgb8, {0xA1, 0xA2, 0xA3}}), withDepth);
    std::vector<uint8_t> empty = plain;
    for (uint8_t b : {0x00, 0x00, 0x00, 0x00}) empty.push_back(b);
    EXPECT_THROW(decode<TileResult>(empty), DecodeError);
    const TileResultInfo info = peekTileResult(withDepth.data(), withDepth.size());
    EXPECT_EQ(info.pixelBytes, 2u);
    EXPECT_EQ(info.depthBytes, 3u);

    // A node frame says in one byte which of its optional parts follow (version 21): depth is bit 0.
    NodeFrame node{1, 64, 64, 32};
    std::vector<uint8_t> nodeOn = payloadOf(node);
    ASSERT_EQ(nodeOn.back(), 0x00);
    nodeOn.back() = 0x01;
    node.depth = true;
    EXPECT_EQ(payloadOf(node), nodeOn);
}

// Version 21: the eyes a frame was rendered for, in the wall's room (a post-warping wall's
// nodes resample from them): in NodeFrame bit 2 of its parts byte and two points after the
// rest, with or without depth and denoising; in NodePose last, left out when absent. Never
// infinite or NaN, never a parts byte with bits it does not know.
TEST(Protocol, TheRoomEyesGoToTheNodesWithOrWithoutTheOtherParts) {
    const std::array<Float3, 2> eyes{Float3{-0.0325f, 1.7f, 2.5f}, Float3{0.0325f, 1.7f, 2.5f}};
    for (NodeFrame f : {NodeFrame{80, 3840, 2160, 64, TilePixels::Srgb8, {}, {}, false, 41}, sampleViewsNodeFrame(),
                        sampleDenoisedNodeFrame()}) {
        const std::vector<uint8_t> without = payloadOf(f);
        f.roomEyes = eyes;
        std::vector<uint8_t> with = payloadOf(f);
        ASSERT_EQ(with.size(), without.size() + 24);
        EXPECT_EQ(decode<NodeFrame>(with), f);
        // The parts byte is where it was, with bit 2 set.
        NodeFrame undenoised = f;
        undenoised.denoise.reset();
        undenoised.roomEyes.reset();
        const size_t partsAt = payloadOf(undenoised).size() - 1;
        EXPECT_EQ(with[partsAt], without[partsAt] | 0x04);
        for (const float bad : {std::numeric_limits<float>::infinity(), std::nanf("")}) {
            NodeFrame b = f;
            (*b.roomEyes)[1].y = bad;
            EXPECT_THROW(decode<NodeFrame>(payloadOf(b)), DecodeError);
        }
        std::vector<uint8_t> unknown = with;
        unknown[partsAt] |= 0x08;
        EXPECT_THROW(decode<NodeFrame>(unknown), DecodeError);
    }
    NodePose pose{900, 86, true, {sampleCamera()}};
    const std::vector<uint8_t> plain = payloadOf(pose);
    pose.roomEyes = eyes;
    const std::vector<uint8_t> with = payloadOf(pose);
    ASSERT_EQ(with.size(), plain.size() + 24);
    EXPECT_TRUE(std::equal(plain.begin(), plain.end(), with.begin()));
    EXPECT_EQ(decode<NodePose>(with), pose);
    EXPECT_THROW(decode<NodePose>(std::vector<uint8_t>(with.begin(), with.end() - 4)), DecodeError);
}

// -- Header checks -------------------------------------------------------------------------------

TEST(Protocol, HeaderRejectsMalformed) {
    const std::vector<uint8_t> good = encodeMessage(sampleHeader(), Goodbye{"bye"});
    ASSERT_NO_THROW(decodeHeader(good.data(), good.size()));

    auto rejects = [](std::vector<uint8_t> bytes, const char* what) {
        EXPECT_THROW(decodeHeader(bytes.data(), bytes.size()), DecodeError) << what;
    };
    std::vector<uint8_t> b = good;
    b[0] ^= 1;
    rejects(b, "wrong magic");
    rejects(std::vector<uint8_t>(good.begin(), good.begin() + 31), "31 bytes");
    rejects({}, "empty");
    b = good;
    b.push_back(0);
    rejects(b, "payload longer than the length");
    b = good;
    b.pop_back();
    rejects(b, "payload shorter than the length");
    b = good;
    putU32(b, 24, 0xFFFFFFFFu);
    rejects(b, "huge length");
    for (uint16_t type : {uint16_t(0), uint16_t(kMaxMsgType + 1), uint16_t(0xFFFF)}) {
        b = good;
        b[6] = uint8_t(type);
        b[7] = uint8_t(type >> 8);
        rejects(b, "type out of range");
    }
    for (size_t at = 28; at < 32; ++at) {
        b = good;
        b[at] = 1;
        rejects(b, "reserved not zero");
    }
    EXPECT_THROW(decodeHeader(nullptr, 0), DecodeError);
}

TEST(Protocol, HeaderReturnsOtherVersions) {
    Header h = sampleHeader();
    h.version = 2;
    const std::vector<uint8_t> bytes = encodeMessage(h, Hello{2, 4, "future"});
    const Header back = decodeHeader(bytes.data(), bytes.size());
    EXPECT_EQ(back.version, 2);
    EXPECT_EQ(back.type, MsgType::Hello);
    EXPECT_EQ(decodePayload<Hello>(bytes.data() + kHeaderSize, bytes.size() - kHeaderSize).protocolVersion, 2);
}

TEST(Protocol, HeaderAloneIsAValidHeader) {
    // A version-5 heartbeat was the header alone: the header still decodes (so the peer can be
    // told its version), the empty payload no longer does.
    Header h = sampleHeader();
    h.type = MsgType::Heartbeat;
    std::vector<uint8_t> bytes = encodeMessage(h, Heartbeat{});
    bytes.resize(kHeaderSize);
    putU32(bytes, 24, 0);
    EXPECT_EQ(decodeHeader(bytes.data(), bytes.size()).type, MsgType::Heartbeat);
    EXPECT_THROW(decodePayload<Heartbeat>(bytes.data() + kHeaderSize, 0), DecodeError);
}

// Version 6: a heartbeat carries the client's work report; its flag is a strict boolean.
TEST(Protocol, HeartbeatReportGoldenBytes) {
    Header h;
    const std::vector<uint8_t> bytes = encodeMessage(h, Heartbeat{0x04030201u, 0x08070605u, true});
    const std::vector<uint8_t> payload(bytes.begin() + kHeaderSize, bytes.end());
    EXPECT_EQ(payload, (std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 8, 1}));
    std::vector<uint8_t> bad = payload;
    bad[8] = 2;
    EXPECT_THROW(decode<Heartbeat>(bad), DecodeError);
    EXPECT_THROW(decode<Heartbeat>(std::vector<uint8_t>(payload.begin(), payload.end() - 1)), DecodeError);
    EXPECT_EQ(payloadOf(TileStalled{1, 2, 3}).size(), 12u);
}

// -- Truncation and trailing bytes ---------------------------------------------------------------

// A message without its version-14 trailing field (depth), which a decoder takes for a message
// that never had it: the one truncation that decodes. (A NodeFrame says in a byte which parts
// follow since version 21: no truncation of it decodes.)
template <class Msg> Msg withoutTrailing(Msg msg) {
    if constexpr (std::is_same_v<Msg, NodePose>) msg.roomEyes.reset();
    if constexpr (std::is_same_v<Msg, FrameBegin>) msg.depth = false;
    if constexpr (std::is_same_v<Msg, TileResult>) msg.depth.clear();
    if constexpr (std::is_same_v<Msg, NodeWelcome>) msg.reproject = false;
    return msg;
}

TEST(Protocol, EveryTruncationThrows) {
    forEachSample([&](const auto& msg) {
        using Msg = std::decay_t<decltype(msg)>;
        SCOPED_TRACE("message type " + std::to_string(int(messageTypeOf(msg))));
        const std::vector<uint8_t> bytes = encodeMessage(sampleHeader(), msg);
        const size_t shorter = encodeMessage(sampleHeader(), withoutTrailing(msg)).size();
        for (size_t cut = 0; cut < bytes.size(); ++cut) {
            // Exactly sized copies, so that AddressSanitizer would see any read past the end.
            const std::vector<uint8_t> whole(bytes.begin(), bytes.begin() + ptrdiff_t(cut));
            EXPECT_THROW(decodeHeader(whole.data(), whole.size()), DecodeError) << "cut at " << cut;
            if (cut >= kHeaderSize) {
                const std::vector<uint8_t> payload(bytes.begin() + kHeaderSize, bytes.begin() + ptrdiff_t(cut));
                if (cut == shorter)  // the whole message before its trailing field: a message without it
                    EXPECT_EQ(decodePayload<Msg>(payload.data(), payload.size()), withoutTrailing(msg));
                else
                    EXPECT_THROW(decodePayload<Msg>(payload.data(), payload.size()), DecodeError) << "cut at " << cut;
            }
        }
        std::vector<uint8_t> trailing(bytes.begin() + kHeaderSize, bytes.end());
        trailing.push_back(0);
        EXPECT_THROW(decodePayload<Msg>(trailing.data(), trailing.size()), DecodeError);
    });
}

TEST(Protocol, RandomCorruptionNeverCrashes) {
    // A small deterministic fuzz pass that runs with every test; tests/fuzz goes further.
    std::mt19937 rng(12345);
    forEachSample([&](const auto& msg) {
        using Msg = std::decay_t<decltype(msg)>;
        const std::vector<uint8_t> payload = payloadOf(msg);
        if (payload.empty()) return;
        for (int iteration = 0; iteration < 500; ++iteration) {
            std::vector<uint8_t> bad = payload;
            const int flips = 1 + int(rng() % 4);
            for (int f = 0; f < flips; ++f) bad[rng() % bad.size()] = uint8_t(rng());
            try {
                const Msg back = decodePayload<Msg>(bad.data(), bad.size());
                // Whatever decodes must be canonical.
                EXPECT_EQ(payloadOf(back), bad);
            } catch (const DecodeError&) {
            }
        }
    });
}

// -- Hostile counts ------------------------------------------------------------------------------

TEST(Protocol, OversizedCountsThrowBeforeAllocating) {
    // Counts far beyond the limits, and within the limits but beyond the bytes present. A
    // decoder that sized a vector first would throw bad_alloc (or take gigabytes) instead.
    for (uint32_t count : {0x80000000u, 0xFFFFFFFFu, kMaxTilesPerMessage, kMaxTilesPerMessage + 1}) {
        std::vector<uint8_t> p = payloadOf(TileAssign{9, {}});
        putU32(p, 4, count);
        EXPECT_THROW(decode<TileAssign>(p), DecodeError) << count;
    }
    for (uint32_t count : {0x80000000u, 0xFFFFFFFFu, kMaxChangesPerUpdate, kMaxChangesPerUpdate + 1}) {
        std::vector<uint8_t> p = payloadOf(Update{3, {}});
        putU32(p, 4, count);
        EXPECT_THROW(decode<Update>(p), DecodeError) << count;
    }
    // Each of the snapshot's four vectors in turn: its count sits right after the previous (empty) ones.
    SceneSnapshot empty;
    for (size_t vectorIndex = 0; vectorIndex < 4; ++vectorIndex) {
        for (uint32_t count : {0x80000000u, 0xFFFFFFFFu, kMaxSceneObjects, kMaxSceneObjects + 1}) {
            std::vector<uint8_t> p = payloadOf(empty);
            putU32(p, 4 + 4 * vectorIndex, count);
            EXPECT_THROW(decode<SceneSnapshot>(p), DecodeError) << vectorIndex << " " << count;
        }
    }
    // Blobs and strings with lengths of up to 4 GiB.
    for (uint32_t length : {0x80000000u, 0xFFFFFFFFu}) {
        std::vector<uint8_t> p = payloadOf(MeshData{});
        putU32(p, 16, length);
        EXPECT_THROW(decode<MeshData>(p), DecodeError);
        p = payloadOf(TileResult{});
        putU32(p, 13, length);
        EXPECT_THROW(decode<TileResult>(p), DecodeError);
        p = payloadOf(Goodbye{});
        putU32(p, 0, length);
        EXPECT_THROW(decode<Goodbye>(p), DecodeError);
        p = payloadOf(Hello{});
        putU32(p, 6, length);
        EXPECT_THROW(decode<Hello>(p), DecodeError);
    }
}

// -- Value ranges --------------------------------------------------------------------------------

TEST(Protocol, SnapshotRejectsValuesOutOfRange) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const std::vector<std::pair<const char*, std::function<void(SceneSnapshot&)>>> cases = {
        {"width 0", [](SceneSnapshot& s) { s.settings.width = 0; }},
        {"width 16385", [](SceneSnapshot& s) { s.settings.width = 16385; }},
        {"height -1", [](SceneSnapshot& s) { s.settings.height = -1; }},
        {"height 16385", [](SceneSnapshot& s) { s.settings.height = 16385; }},
        {"tile 0", [](SceneSnapshot& s) { s.settings.tileSize = 0; }},
        {"tile 1025", [](SceneSnapshot& s) { s.settings.tileSize = 1025; }},
        {"depth 0", [](SceneSnapshot& s) { s.settings.maxDepth = 0; }},
        {"depth 65", [](SceneSnapshot& s) { s.settings.maxDepth = 65; }},
        {"supersample 0", [](SceneSnapshot& s) { s.settings.supersample = 0; }},
        {"supersample 17", [](SceneSnapshot& s) { s.settings.supersample = 17; }},
        {"threads -1", [](SceneSnapshot& s) { s.settings.threads = -1; }},
        {"threads 1025", [](SceneSnapshot& s) { s.settings.threads = 1025; }},
        {"kernel 2", [](SceneSnapshot& s) { s.settings.kernel = KernelType(2); }},
        {"shading 2", [](SceneSnapshot& s) { s.settings.shading = ShadingMode(2); }},
        {"background NaN", [=](SceneSnapshot& s) { s.settings.background.y = nan; }},
        {"ambient inf", [=](SceneSnapshot& s) { s.settings.ambient.z = inf; }},
        {"bvh quality 3", [](SceneSnapshot& s) { s.bvh.quality = BvhSettings::Quality(3); }},
        {"bvh primitives 2", [](SceneSnapshot& s) { s.bvh.primitives = BvhSettings::Primitives(2); }},
        {"origin NaN", [](SceneSnapshot& s) { s.origin[1] = std::numeric_limits<double>::quiet_NaN(); }},
        {"origin inf", [](SceneSnapshot& s) { s.origin[0] = -std::numeric_limits<double>::infinity(); }},
        {"material type 7", [](SceneSnapshot& s) { s.materials[1].type = MaterialType(7); }},
        {"roughness 1.5", [](SceneSnapshot& s) { s.materials[0].roughness = 1.5f; }},
        {"absorption -1", [](SceneSnapshot& s) { s.materials[0].absorption.y = -1.0f; }},
        {"emission NaN", [=](SceneSnapshot& s) { s.materials[0].emission.x = nan; }},
        {"texture kind 5", [](SceneSnapshot& s) { s.materials[0].texture.kind = TextureKind(5); }},
        {"texture mapping object", [](SceneSnapshot& s) { s.materials[0].texture.mapping = TextureMapping::Object; }},
        {"texture mapping 8", [](SceneSnapshot& s) { s.materials[0].alpha.mapping = TextureMapping(8); }},
        {"bump mapping xy", [](SceneSnapshot& s) { s.materials[1].bumpMapping = TextureMapping::PlanarXY; }},
        {"bump mapping 8", [](SceneSnapshot& s) { s.materials[1].bumpMapping = TextureMapping(8); }},
        {"alpha mode 2", [](SceneSnapshot& s) { s.materials[1].alphaMode = AlphaMode(2); }},
        {"alpha channel 2", [](SceneSnapshot& s) { s.materials[0].alphaChannel = AlphaChannel(2); }},
        {"opacity NaN", [=](SceneSnapshot& s) { s.materials[0].opacity = nan; }},
        {"opacity 1.5", [](SceneSnapshot& s) { s.materials[1].opacity = 1.5f; }},
        {"image texture without file", [](SceneSnapshot& s) { s.materials[0].texture.kind = TextureKind::Image; }},
        {"volume without file", [](SceneSnapshot& s) { s.materials[0].type = MaterialType::Volume; }},
        {"volume step 0", [](SceneSnapshot& s) { s.materials[0].volumeStep = 0.0f; }},
        {"prune threshold -0.1", [](SceneSnapshot& s) { s.settings.pruneThreshold = -0.1f; }},
        {"samples 0", [](SceneSnapshot& s) { s.settings.samples = 0; }},
        {"view 5", [](SceneSnapshot& s) { s.settings.view = ViewMode(5); }},
        {"color 1.01", [](SceneSnapshot& s) { s.materials[0].color.x = 1.01f; }},
        {"color -0.1", [](SceneSnapshot& s) { s.materials[0].color.z = -0.1f; }},
        {"specular 2", [](SceneSnapshot& s) { s.materials[1].specular.y = 2.0f; }},
        {"color NaN", [=](SceneSnapshot& s) { s.materials[0].color.y = nan; }},
        {"ior 0.99", [](SceneSnapshot& s) { s.materials[1].ior = 0.99f; }},
        {"ior 4.01", [](SceneSnapshot& s) { s.materials[1].ior = 4.01f; }},
        {"shininess -1", [](SceneSnapshot& s) { s.materials[0].shininess = -1; }},
        {"shininess inf", [=](SceneSnapshot& s) { s.materials[0].shininess = inf; }},
        {"light type 3", [](SceneSnapshot& s) { s.lights[0].type = LightType(3); }},
        {"intensity -1", [](SceneSnapshot& s) { s.lights[0].intensity = -1; }},
        {"light position NaN", [=](SceneSnapshot& s) { s.lights[1].position.x = nan; }},
        {"light direction inf", [=](SceneSnapshot& s) { s.lights[1].direction.z = -inf; }},
        {"transform NaN", [](SceneSnapshot& s) { s.instances[0].transform.m[11] = std::nan(""); }},
        {"transform inf", [](SceneSnapshot& s) { s.instances[1].transform.m[0] = HUGE_VAL; }},
        {"instance mesh out of range", [](SceneSnapshot& s) { s.instances[1].mesh = 2; }},
        {"instance material out of range", [](SceneSnapshot& s) { s.instances[0].material = 2; }},
        {"mesh bytes over the limit", [](SceneSnapshot& s) { s.meshes[0].bytes = kMaxMeshBytes + 1; }},
    };
    ASSERT_NO_THROW(decode<SceneSnapshot>(payloadOf(sampleSnapshot())));
    for (const auto& [what, mutate] : cases) {
        SceneSnapshot s = sampleSnapshot();
        mutate(s);
        EXPECT_THROW(decode<SceneSnapshot>(payloadOf(s)), DecodeError) << what;
        // The same values arrive in changes, and must be rejected there too.
        Update u;
        u.changes = {MaterialChange{0, s.materials[0], {}}, MaterialChange{1, s.materials[1], {}},
                     LightChange{0, s.lights[0]}, LightChange{1, s.lights[1]},
                     TransformChange{0, s.instances[0].transform}, TransformChange{1, s.instances[1].transform},
                     SettingsChange{s.settings}};
        const std::string name = what;
        const bool crossReference = name.find("out of range") != std::string::npos || name.find("mesh bytes") == 0;
        const bool snapshotOnly = name.find("bvh") == 0 || name.find("origin") == 0;  // no change carries these
        if (!crossReference && !snapshotOnly) {
            EXPECT_THROW(decode<Update>(payloadOf(u)), DecodeError) << what;
        }
    }
}

// A camera travels only as a frame's view (version 13): its values are checked there.
TEST(Protocol, FrameViewCamerasRejectValuesOutOfRange) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const std::vector<std::pair<const char*, std::function<void(CameraDesc&)>>> cases = {
        {"fov 0", [](CameraDesc& c) { c.fovY = 0; }},
        {"fov 180", [](CameraDesc& c) { c.fovY = 180; }},
        {"fov -10", [](CameraDesc& c) { c.fovY = -10; }},
        {"window NaN", [=](CameraDesc& c) { c.window = ProjectionWindow{{0, 0, 0}, {nan, 0, 0}, {0, 1, 0}}; }},
        {"window inf", [=](CameraDesc& c) { c.window = ProjectionWindow{{0, 0, inf}, {1, 0, 0}, {0, 1, 0}}; }},
        {"camera NaN", [=](CameraDesc& c) { c.lookAt.x = nan; }},
        {"camera name too long", [](CameraDesc& c) { c.name.assign(kMaxStringBytes + 1, 'c'); }},
    };
    const FrameBegin good{3, 2, TilePixels::Srgb8, {FrameView{sampleCamera(), {}, 0, 0}}};
    ASSERT_NO_THROW(decode<FrameBegin>(payloadOf(good)));
    for (const auto& [what, mutate] : cases) {
        FrameBegin fb = good;
        mutate(fb.views[0].camera);
        EXPECT_THROW(decode<FrameBegin>(payloadOf(fb)), DecodeError) << what;
    }
}

TEST(Protocol, OtherMessagesRejectValuesOutOfRange) {
    auto welcomeWith = [](auto mutate) {
        Welcome w = sampleWelcome();
        mutate(w);
        return payloadOf(w);
    };
    EXPECT_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.codec.codec = TileCodec(4); })), DecodeError);
    EXPECT_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.codec.jpegQuality = 0; })), DecodeError);
    EXPECT_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.codec.jpegQuality = 101; })), DecodeError);
    EXPECT_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.codec.zstdLevel = 0; })), DecodeError);
    EXPECT_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.codec.zstdLevel = 20; })), DecodeError);
    EXPECT_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.timeoutMs = kMaxTimeoutMs + 1; })), DecodeError);
    EXPECT_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.heartbeatMs = kMaxTimeoutMs + 1; })), DecodeError);
    EXPECT_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.prefetch = kMaxTilesPerMessage + 1; })),
                 DecodeError);
    EXPECT_NO_THROW(decode<Welcome>(welcomeWith([](Welcome& w) {
        w.codec = {TileCodec::Jpeg, 100, false, 19};
    })));
    EXPECT_NO_THROW(decode<Welcome>(welcomeWith([](Welcome& w) { w.codec = {TileCodec::Raw, 1, false, 1}; })));

    std::vector<uint8_t> p = payloadOf(sampleWelcome());
    p[9] = 2;  // the subsampling boolean
    EXPECT_THROW(decode<Welcome>(p), DecodeError);

    TileResult t = sampleTileResult();
    t.codec = TileCodec(4);
    EXPECT_THROW(decode<TileResult>(payloadOf(t)), DecodeError);
    EXPECT_THROW(decode<TileRequest>(payloadOf(TileRequest{1, kMaxTilesPerMessage + 1})), DecodeError);
    EXPECT_NO_THROW(decode<TileRequest>(payloadOf(TileRequest{1, kMaxTilesPerMessage})));
    EXPECT_THROW(decode<Hello>(payloadOf(Hello{1, 1025, "big"})), DecodeError);

    // Change kinds past the last one.
    p = payloadOf(Update{1, {VisibilityChange{}}});
    ASSERT_EQ(p[8], 5);
    p[8] = 6;
    EXPECT_THROW(decode<Update>(p), DecodeError);

    // Mesh bytes that do not match their hash.
    MeshData m = sampleMeshData();
    m.hash[1] ^= 1;
    EXPECT_THROW(decode<MeshData>(payloadOf(m)), DecodeError);
}

TEST(Protocol, NodeMessagesRejectValuesOutOfRange) {
    auto helloWith = [](auto mutate) {
        NodeHello h = sampleNodeHello();
        mutate(h);
        return payloadOf(h);
    };
    EXPECT_NO_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.publicKey.clear(); })));
    EXPECT_NO_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.name = std::string(32, 'n'); })));
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.name.clear(); })), DecodeError);
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.name = std::string(33, 'n'); })), DecodeError);
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.name = "left pc"; })), DecodeError);
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.name = "../etc"; })), DecodeError);
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.endpoint.clear(); })), DecodeError);
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.endpoint = "tcp://a b:1"; })), DecodeError);
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.endpoint = "tcp://" + std::string(251, 'a'); })),
                 DecodeError);
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.publicKey.pop_back(); })), DecodeError);
    EXPECT_THROW(decode<NodeHello>(helloWith([](NodeHello& h) { h.publicKey[5] = '_'; })), DecodeError);

    NodeWelcome w = sampleNodeWelcome();
    w.node = kMaxNodes;
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    w = sampleNodeWelcome();
    w.timeoutMs = w.heartbeatMs - 1;
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    w = sampleNodeWelcome();
    w.heartbeatMs = 0;
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    w = sampleNodeWelcome();
    w.wall.clear();
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    w.wall = std::string(kMaxWallConfigBytes, '#');
    EXPECT_NO_THROW(decode<NodeWelcome>(payloadOf(w)));
    w.wall.push_back('#');
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    // Version 12: the client keys a node's tile socket lets in, each a Z85 key.
    w = sampleNodeWelcome();
    w.clientKeys.clear();
    EXPECT_NO_THROW(decode<NodeWelcome>(payloadOf(w)));
    w.clientKeys = {""};
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    w.clientKeys = {kSampleKey.substr(1)};
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    w.clientKeys = {kSampleKey + "x"};
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    w.clientKeys = {kSampleKey};
    w.clientKeys[0][3] = '~';
    EXPECT_THROW(decode<NodeWelcome>(payloadOf(w)), DecodeError);
    {
        std::vector<uint8_t> p = payloadOf(sampleNodeWelcome());
        const size_t countAt = p.size() - 2 * (4 + 40) - 4;  // the key count before the two keys
        for (uint32_t count : {3u, kMaxClientKeys + 1, 0xFFFFFFFFu}) {
            putU32(p, countAt, count);
            EXPECT_THROW(decode<NodeWelcome>(p), DecodeError) << count;
        }
    }

    EXPECT_THROW(decode<NodeFrame>(payloadOf(NodeFrame{1, 0, 10, 8})), DecodeError);
    EXPECT_THROW(decode<NodeFrame>(payloadOf(NodeFrame{1, 10, 16385, 8})), DecodeError);
    EXPECT_THROW(decode<NodeFrame>(payloadOf(NodeFrame{1, 10, 10, 1025})), DecodeError);
    EXPECT_NO_THROW(decode<NodeFrame>(payloadOf(NodeFrame{1, 16384, 16384, 8})));  // exactly the tile limit
    EXPECT_THROW(decode<NodeFrame>(payloadOf(NodeFrame{1, 16384, 16384, 4})), DecodeError);
    std::vector<uint8_t> p = payloadOf(NodeFrame{1, 10, 10, 8});
    p[16] = 2;  // the pixel format
    EXPECT_THROW(decode<NodeFrame>(p), DecodeError);
    // Version 12: the views, their eyes, the accumulation.
    EXPECT_NO_THROW(decode<NodeFrame>(payloadOf(sampleViewsNodeFrame())));
    NodeFrame f = sampleViewsNodeFrame();
    f.eyes.pop_back();  // an eye short
    EXPECT_THROW(decode<NodeFrame>(payloadOf(f)), DecodeError);
    f = sampleViewsNodeFrame();
    f.eyes.push_back(-1);  // one too many
    EXPECT_THROW(decode<NodeFrame>(payloadOf(f)), DecodeError);
    for (int8_t eye : {int8_t(2), int8_t(-2), int8_t(127)}) {
        f = sampleViewsNodeFrame();
        f.eyes[1] = eye;
        EXPECT_THROW(decode<NodeFrame>(payloadOf(f)), DecodeError) << int(eye);
    }
    f = sampleViewsNodeFrame();
    f.eyes = {-1, -1};
    EXPECT_NO_THROW(decode<NodeFrame>(payloadOf(f)));
    f = sampleViewsNodeFrame();
    f.stochastic = false;  // linear tiles are only for frames that accumulate
    EXPECT_THROW(decode<NodeFrame>(payloadOf(f)), DecodeError);
    f.pixels = TilePixels::Srgb8;
    EXPECT_NO_THROW(decode<NodeFrame>(payloadOf(f)));
    p = payloadOf(NodeFrame{1, 10, 10, 8});
    p[p.size() - 6] = 2;  // the stochastic flag is a boolean (before the state and the parts byte)
    EXPECT_THROW(decode<NodeFrame>(p), DecodeError);
    // Two views of a frame at the tile limit are over it.
    f = sampleViewsNodeFrame();
    f.width = f.height = 16384;
    f.tileSize = 8;
    EXPECT_THROW(decode<NodeFrame>(payloadOf(f)), DecodeError);
    f.views.resize(1);
    f.eyes.resize(1);
    EXPECT_NO_THROW(decode<NodeFrame>(payloadOf(f)));
    // A view region outside its reference image, as in FrameBegin.
    f = sampleViewsNodeFrame();
    f.views[1].regions[1].x = 2049;
    EXPECT_THROW(decode<NodeFrame>(payloadOf(f)), DecodeError);

    EXPECT_THROW(decode<NodeSwap>(payloadOf(NodeSwap{1, {"ok", "not ok"}})), DecodeError);
    NodeList twice = sampleNodeList();
    twice.nodes[1].node = twice.nodes[0].node;
    EXPECT_THROW(decode<NodeList>(payloadOf(twice)), DecodeError);
    NodeList high = sampleNodeList();
    high.nodes[1].node = kMaxNodes;
    EXPECT_THROW(decode<NodeList>(payloadOf(high)), DecodeError);
    EXPECT_TRUE(isNodeName("a-Z_09"));
    EXPECT_FALSE(isNodeName("caf\xc3\xa9"));
}

TEST(Protocol, NodeMessageCountsThrowBeforeAllocating) {
    for (uint32_t count : {0x80000000u, 0xFFFFFFFFu, kMaxTilesPerFrame + 1}) {
        std::vector<uint8_t> p = payloadOf(TileRoutes{9, {}});
        putU32(p, 4, count);
        EXPECT_THROW(decode<TileRoutes>(p), DecodeError) << count;
    }
    for (uint32_t count : {kMaxNodes + 1, 0xFFFFFFFFu}) {
        std::vector<uint8_t> p = payloadOf(NodeList{});
        putU32(p, 0, count);
        EXPECT_THROW(decode<NodeList>(p), DecodeError) << count;
        p = payloadOf(NodeSwap{3, {}});
        putU32(p, 4, count);
        EXPECT_THROW(decode<NodeSwap>(p), DecodeError) << count;
    }
}

// A client forwards its own results to the display nodes as they are and tells the master their
// figures: read with the TileResult decoder's own reader, checked as it checks them.
TEST(Protocol, PeekTileResultReadsWhatTheDecoderReads) {
    const TileResult t = sampleTileResult();
    const std::vector<uint8_t> p = payloadOf(t);
    const TileResultInfo info = peekTileResult(p.data(), p.size());
    EXPECT_EQ(info.frame, t.frame);
    EXPECT_EQ(info.tile, t.tile);
    EXPECT_EQ(info.renderMicros, t.renderMicros);
    EXPECT_EQ(info.pixelBytes, t.pixels.size());
    EXPECT_EQ(info.depthBytes, t.depth.size());
    const size_t withoutDepth = payloadOf(withoutTrailing(t)).size();
    for (size_t n = 0; n < p.size(); ++n)
        if (n == withoutDepth) EXPECT_EQ(peekTileResult(p.data(), n).depthBytes, 0u);  // a result without depth
        else EXPECT_THROW(peekTileResult(p.data(), n), DecodeError) << n << " bytes";
    std::vector<uint8_t> longer = p;
    longer.push_back(0);
    EXPECT_THROW(peekTileResult(longer.data(), longer.size()), DecodeError);
    TileResult badCodec = t;
    badCodec.codec = TileCodec(4);
    const std::vector<uint8_t> bad = payloadOf(badCodec);
    EXPECT_THROW(peekTileResult(bad.data(), bad.size()), DecodeError);
}

TEST(Protocol, TileDoneGoldenBytes) {
    // The ack that replaces a tile's pixels on the master's link: 16 bytes of payload.
    const std::vector<uint8_t> expected{0x01, 0, 0, 0, 0x02, 0, 0, 0, 0x03, 0, 0, 0, 0x04, 0x01, 0, 0};
    EXPECT_EQ(payloadOf(TileDone{1, 2, 3, 0x104}), expected);
}

// -- Meshes --------------------------------------------------------------------------------------

void expectSameMesh(const TriangleMesh& a, const TriangleMesh& b) {
    ASSERT_EQ(a.vertexCount(), b.vertexCount());
    ASSERT_EQ(a.triangleCount(), b.triangleCount());
    ASSERT_EQ(a.hasNormals(), b.hasNormals());
    // Bitwise, so that -0.0 and 0.0 count as different; std::equal also copes with the null
    // pointers of an empty mesh, which memcmp must not be given.
    auto sameBits = [](const auto* x, const auto* y, size_t n) {
        return std::equal(x, x + n, y, [](auto u, auto v) { return std::memcmp(&u, &v, sizeof u) == 0; });
    };
    EXPECT_TRUE(sameBits(a.positions(), b.positions(), 3 * a.vertexCount()));
    EXPECT_TRUE(sameBits(a.indices(), b.indices(), 3 * a.triangleCount()));
    if (a.hasNormals()) {
        EXPECT_TRUE(sameBits(a.normals(), b.normals(), 3 * a.vertexCount()));
    }
}

TEST(ProtocolMesh, RoundTrip) {
    for (const TriangleMesh& mesh : {makeBox(), makeSphere(5, 7), makeTorusKnot(2, 3, 40, 6, 0.2f), TriangleMesh{}}) {
        const std::vector<uint8_t> bytes = encodeMesh(mesh);
        EXPECT_EQ(bytes.size(), 8 + 12 * mesh.vertexCount() + 8 + 12 * mesh.triangleCount() + 1 +
                                    (mesh.hasNormals() ? 12 * mesh.vertexCount() : 0) + 1 + 1);
        const TriangleMesh back = decodeMesh(bytes.data(), bytes.size());
        expectSameMesh(mesh, back);
        EXPECT_EQ(encodeMesh(back), bytes);
    }
}

// Three vertices on the axes and one triangle: small enough to check byte offsets by hand.
TriangleMesh oneTriangle() {
    TriangleMesh m;
    m.addVertex({1.0f, 0.0f, 0.0f});
    m.addVertex({0.0f, 1.0f, 0.0f});
    m.addVertex({0.0f, 0.0f, 1.0f});
    m.addTriangle(0, 1, 2);
    return m;
}

TEST(ProtocolMesh, Layout) {
    TriangleMesh m = oneTriangle();
    const std::vector<uint8_t> bytes = encodeMesh(m);
    ASSERT_EQ(bytes.size(), 8u + 36u + 8u + 12u + 1u + 1u + 1u);
    EXPECT_EQ(bytes[0], 3);                            // vertex count
    EXPECT_EQ(bytes[8 + 3], 0x3F);                     // 1.0f, little-endian
    EXPECT_EQ(bytes[44], 1);                           // triangle count
    EXPECT_EQ(bytes[52 + 4], 1);                       // second index
    EXPECT_EQ(bytes[64], 0);                           // no normals
    EXPECT_EQ(bytes[65], 0);                           // no colours
    EXPECT_EQ(bytes[66], 0);                           // no texture coordinates (version 5)
    m.setColors({255, 128, 0, 0, 255, 0, 0, 0, 255});
    const std::vector<uint8_t> colored = encodeMesh(m);
    ASSERT_EQ(colored.size(), 8u + 36u + 8u + 12u + 1u + 1u + 9u + 1u);
    EXPECT_EQ(colored[65], 1);
    EXPECT_EQ(std::vector<uint8_t>(colored.begin() + 66, colored.end() - 1), (std::vector<uint8_t>{255, 128, 0, 0, 255, 0, 0, 0, 255}));
    m.setUVs({0.25f, 0.5f, 1.0f, 0.0f, -2.0f, 3.0f});
    const std::vector<uint8_t> textured = encodeMesh(m);
    ASSERT_EQ(textured.size(), colored.size() + 24u);
    EXPECT_EQ(textured[75], 1);                        // the UV flag, after the colours
    EXPECT_EQ(textured[76 + 3], 0x3E);                 // 0.25f, little-endian
    EXPECT_EQ(textured[76 + 20 + 3], 0x40);            // 3.0f
}

// Vertex colours (version 4) survive the trip byte for byte and change the hash.
TEST(ProtocolMesh, ColorsRoundTrip) {
    TriangleMesh m = makeSphere(3, 4);
    const std::vector<uint8_t> plain = encodeMesh(m);
    std::vector<uint8_t> colors(3 * m.vertexCount());
    for (size_t i = 0; i < colors.size(); ++i) colors[i] = uint8_t(i * 37);
    m.setColors(colors);
    const std::vector<uint8_t> bytes = encodeMesh(m);
    const TriangleMesh back = decodeMesh(bytes.data(), bytes.size());
    ASSERT_TRUE(back.hasColors());
    EXPECT_EQ(std::vector<uint8_t>(back.colors(), back.colors() + colors.size()), colors);
    EXPECT_EQ(encodeMesh(back), bytes);
    EXPECT_NE(hashBytes(bytes.data(), bytes.size()), hashBytes(plain.data(), plain.size()));
    for (size_t cut = bytes.size() - colors.size() - 2; cut < bytes.size(); ++cut)
        EXPECT_THROW(decodeMesh(bytes.data(), cut), DecodeError) << cut;
    std::vector<uint8_t> flag2 = bytes;
    flag2[bytes.size() - colors.size() - 2] = 2;
    EXPECT_THROW(decodeMesh(flag2.data(), flag2.size()), DecodeError);
}

TEST(ProtocolMesh, HashIsStableAndSeesEveryByte) {
    const std::vector<uint8_t> bytes = encodeMesh(makeSphere(3, 4));
    const Hash128 h = hashBytes(bytes.data(), bytes.size());
    EXPECT_EQ(hashBytes(encodeMesh(makeSphere(3, 4)).data(), bytes.size()), h);
    EXPECT_NE(hashBytes(bytes.data(), bytes.size() - 1), h);
    for (size_t i = 0; i < bytes.size(); ++i) {
        std::vector<uint8_t> changed = bytes;
        changed[i] ^= 0x10;
        EXPECT_NE(hashBytes(changed.data(), changed.size()), h) << "byte " << i;
    }
    // Low then high half of XXH3-128, as documented.
    const XXH128_hash_t ref = XXH3_128bits(bytes.data(), bytes.size());
    EXPECT_EQ(h[0], ref.low64);
    EXPECT_EQ(h[1], ref.high64);
}

TEST(ProtocolMesh, RejectsMalformed) {
    TriangleMesh m = oneTriangle();
    m.setNormals({0, 0, 1, 0, 0, 1, 0, 0, 1});
    const std::vector<uint8_t> good = encodeMesh(m);
    ASSERT_NO_THROW(decodeMesh(good.data(), good.size()));
    const size_t indexAt = 8 + 36 + 8, flagAt = indexAt + 12;

    auto rejects = [](const std::vector<uint8_t>& b, const std::string& what) {
        EXPECT_THROW(decodeMesh(b.data(), b.size()), DecodeError) << what;
    };
    std::vector<uint8_t> b = good;
    putU32(b, indexAt + 8, 3);  // == vertex count
    rejects(b, "index out of range");
    b = good;
    putU32(b, indexAt, 0xFFFFFFFFu);
    rejects(b, "index 2^32-1");
    b = good;
    putU32(b, 8 + 4, 0x7FC00000u);  // NaN in a position
    rejects(b, "NaN position");
    b = good;
    putU32(b, flagAt + 1 + 20, 0x7F800000u);  // inf in a normal
    rejects(b, "infinite normal");
    b = good;
    b[flagAt] = 2;
    rejects(b, "normals flag 2");
    b = good;
    b.push_back(0);
    rejects(b, "trailing byte");
    for (size_t cut = 0; cut < good.size(); ++cut) {
        const std::vector<uint8_t> prefix(good.begin(), good.begin() + ptrdiff_t(cut));
        rejects(prefix, "cut at " + std::to_string(cut));
    }
    // Counts that cannot fit, up to 2^64 - 1, fail before anything is reserved.
    for (uint64_t count : {uint64_t(1000), uint64_t(1) << 32, uint64_t(1) << 40, ~uint64_t(0)}) {
        b = good;
        for (int i = 0; i < 8; ++i) b[size_t(i)] = uint8_t(count >> (8 * i));
        rejects(b, "vertex count");
        b = good;
        for (int i = 0; i < 8; ++i) b[44 + size_t(i)] = uint8_t(count >> (8 * i));
        rejects(b, "triangle count");
    }
    // A normals flag on a mesh without vertices would not re-encode to the same bytes.
    std::vector<uint8_t> empty = encodeMesh(TriangleMesh{});
    empty[empty.size() - 3] = 1;
    rejects(empty, "normals without vertices");
    empty = encodeMesh(TriangleMesh{});
    empty[empty.size() - 2] = 1;
    rejects(empty, "colours without vertices");
    empty = encodeMesh(TriangleMesh{});
    empty.back() = 1;
    rejects(empty, "texture coordinates without vertices");
}

// Texture coordinates (version 5) survive the trip bit for bit, with normals and colours
// beside them, change the hash, and a NaN, a flag of 2 or a cut in their section is refused.
TEST(ProtocolMesh, UVsRoundTrip) {
    TriangleMesh m = makeSphere(3, 4);
    m.setColors(std::vector<uint8_t>(3 * m.vertexCount(), 200));
    const std::vector<uint8_t> plain = encodeMesh(m);
    std::vector<float> uv(2 * m.vertexCount());
    for (size_t i = 0; i < uv.size(); ++i) uv[i] = float(i) * 0.125f - 3.0f;
    m.setUVs(uv);
    const std::vector<uint8_t> bytes = encodeMesh(m);
    ASSERT_EQ(bytes.size(), plain.size() + 4 * uv.size());
    const TriangleMesh back = decodeMesh(bytes.data(), bytes.size());
    ASSERT_TRUE(back.hasUVs());
    ASSERT_TRUE(back.hasColors());
    ASSERT_TRUE(back.hasNormals());
    EXPECT_EQ(std::vector<float>(back.uvs(), back.uvs() + uv.size()), uv);
    EXPECT_EQ(encodeMesh(back), bytes);
    EXPECT_NE(hashBytes(bytes.data(), bytes.size()), hashBytes(plain.data(), plain.size()));
    const size_t flagAt = plain.size() - 1, uvAt = flagAt + 1;
    for (size_t cut = flagAt; cut < bytes.size(); cut += 3) EXPECT_THROW(decodeMesh(bytes.data(), cut), DecodeError) << cut;
    std::vector<uint8_t> b = bytes;
    b[flagAt] = 2;
    EXPECT_THROW(decodeMesh(b.data(), b.size()), DecodeError);
    b = bytes;
    putU32(b, uvAt + 4 * 5, 0x7FC00000u);  // NaN
    EXPECT_THROW(decodeMesh(b.data(), b.size()), DecodeError);
    b = bytes;
    putU32(b, uvAt + 4 * 6, 0xFF800000u);  // -inf
    EXPECT_THROW(decodeMesh(b.data(), b.size()), DecodeError);
}

// -- Scene state ---------------------------------------------------------------------------------

SceneDesc sampleScene() {
    SceneDesc scene;
    scene.materials = {sampleMaterial(0), sampleMaterial(1)};
    scene.instances = {InstanceDesc{0, 0, {}}, InstanceDesc{0, 1, {}}};
    scene.lights = {sampleLight(0)};
    return scene;
}

TEST(Protocol, ApplyChange) {
    SceneDesc scene = sampleScene();

    applyChange(scene, TransformChange{1, sampleTransform(5)});
    EXPECT_EQ(scene.instances[1].transform, sampleTransform(5));
    EXPECT_EQ(scene.instances[0].transform, Transform{});
    EXPECT_EQ(scene.instances[1].material, 1u);  // only the transform changes

    applyChange(scene, MaterialChange{0, sampleMaterial(7), {}});
    EXPECT_EQ(scene.materials[0], sampleMaterial(7));
    EXPECT_EQ(scene.materials[1], sampleMaterial(1));

    applyChange(scene, LightChange{0, sampleLight(3)});
    EXPECT_EQ(scene.lights[0], sampleLight(3));

    applyChange(scene, SettingsChange{sampleSettings()});
    EXPECT_EQ(scene.settings, sampleSettings());

    EXPECT_THROW(applyChange(scene, TransformChange{2, {}}), DecodeError);
    EXPECT_THROW(applyChange(scene, MaterialChange{2, {}, {}}), DecodeError);
    EXPECT_THROW(applyChange(scene, LightChange{1, {}}), DecodeError);
    EXPECT_THROW(applyChange(scene, LightChange{0xFFFFFFFFu, {}}), DecodeError);
    EXPECT_EQ(scene.lights[0], sampleLight(3));  // a failed change leaves the scene alone
}

TEST(Protocol, StateHash) {
    const SceneSnapshot base = sampleSnapshot();
    const Hash128 h = stateHash(base);
    EXPECT_EQ(stateHash(sampleSnapshot()), h);
    SceneSnapshot s = base;
    s.updateSeq = 1000;
    EXPECT_EQ(stateHash(s), h) << "the sequence number is not part of the state";

    const std::vector<std::function<void(SceneSnapshot&)>> changes = {
        [](SceneSnapshot& x) { x.meshes[0].hash[0] ^= 1; },
        [](SceneSnapshot& x) { x.meshes[1].name += "'"; },
        [](SceneSnapshot& x) { x.meshes.pop_back(); },
        [](SceneSnapshot& x) { x.materials[1].color.x = std::nextafter(x.materials[1].color.x, 0.0f); },
        [](SceneSnapshot& x) { x.instances[0].transform.m[3] += 1e-12; },
        [](SceneSnapshot& x) { std::swap(x.instances[0], x.instances[1]); },
        [](SceneSnapshot& x) { x.lights[1].intensity *= 2; },
        [](SceneSnapshot& x) { x.lights[0].twoSided = !x.lights[0].twoSided; },
        [](SceneSnapshot& x) { x.materials[0].twoSided = !x.materials[0].twoSided; },
        [](SceneSnapshot& x) { x.settings.shadows = true; },
        [](SceneSnapshot& x) { x.settings.threads = 3; },
        [](SceneSnapshot& x) { x.bvh.quality = BvhSettings::Quality::Low; },
        [](SceneSnapshot& x) { x.bvh.compact = false; },
        [](SceneSnapshot& x) { x.bvh.robust = false; },
        [](SceneSnapshot& x) { x.bvh.primitives = BvhSettings::Primitives::Auto; },
        [](SceneSnapshot& x) { x.origin[2] += 1; },
    };
    std::set<Hash128> seen{h};
    for (size_t i = 0; i < changes.size(); ++i) {
        SceneSnapshot changed = base;
        changes[i](changed);
        EXPECT_TRUE(seen.insert(stateHash(changed)).second) << "change " << i;
    }
}

}  // namespace
}  // namespace rtwall::cluster

namespace rtwall::cluster {
namespace {

TEST(Protocol, AssetsAndLinearTilesRejectValuesOutOfRange) {
    // An asset larger than the bound, or without a path; an unknown tile format.
    SceneSnapshot s = sampleSnapshot();
    s.assets[0].bytes = kMaxAssetBytes + 1;
    EXPECT_THROW(decode<SceneSnapshot>(payloadOf(s)), DecodeError);
    s = sampleSnapshot();
    s.assets[0].path.clear();
    EXPECT_THROW(decode<SceneSnapshot>(payloadOf(s)), DecodeError);
    std::vector<uint8_t> p = payloadOf(FrameBegin{1, 2, TilePixels::LinearHalf, {FrameView{}}});
    p[8] = 2;
    EXPECT_THROW(decode<FrameBegin>(p), DecodeError);
    p = payloadOf(withoutTrailing(sampleTileResult()));
    p.back() = 7;  // the pixel format
    EXPECT_THROW(decode<TileResult>(p), DecodeError);
    // AssetData claiming more bytes than the bound throws before allocating.
    p = payloadOf(AssetData{{1, 2}, {}});
    putU32(p, 16, 0xFFFFFFF0u);
    EXPECT_THROW(decode<AssetData>(p), DecodeError);
}

}  // namespace
}  // namespace rtwall::cluster

namespace rtwall::cluster {
namespace {

TEST(Protocol, FrameViewsRoundTripAndRejectBadRegions) {
    const FrameBegin fb = sampleViewsFrameBegin();
    const FrameBegin back = decode<FrameBegin>(payloadOf(fb));
    EXPECT_EQ(back.views, fb.views);
    ASSERT_EQ(back.views.size(), 2u);
    EXPECT_TRUE(back.views[1].camera.window.has_value());
    // A region beyond its reference image, a negative size, a view without a reference size,
    // more views than the limit, a view count larger than the bytes: each one clear error.
    FrameBegin bad = fb;
    bad.views[1].regions[1].width = 1025;  // 2048 + 1025 > 3072
    EXPECT_THROW(decode<FrameBegin>(payloadOf(bad)), DecodeError);
    bad = fb;
    bad.views[1].regions[0].height = -1;
    EXPECT_THROW(decode<FrameBegin>(payloadOf(bad)), DecodeError);
    bad = fb;
    bad.views[1].refWidth = 0;
    EXPECT_THROW(decode<FrameBegin>(payloadOf(bad)), DecodeError);
    bad = fb;
    bad.views.assign(kMaxViews + 1, fb.views[0]);
    EXPECT_THROW(decode<FrameBegin>(payloadOf(bad)), DecodeError);
    std::vector<uint8_t> p = payloadOf(fb);
    putU32(p, 9, 1000);  // the view count
    EXPECT_THROW(decode<FrameBegin>(p), DecodeError);
    // Truncated anywhere: never read past the end.
    // Truncated anywhere (but right before the trailing depth flag, which is a frame without it):
    // never read past the end.
    p = payloadOf(fb);
    for (size_t n = 0; n + 1 < p.size(); ++n)
        EXPECT_THROW(decode<FrameBegin>(std::vector<uint8_t>(p.begin(), p.begin() + long(n))), DecodeError) << n;
}

}  // namespace
}  // namespace rtwall::cluster
