// Writes the seed corpus for fuzz_protocol: one valid input per decoder, in the layout that
// fuzz_protocol.cpp documents (a selector byte, then the decoder's input).
//   make_protocol_corpus <directory>
#include "codec.h"
#include "protocol.h"
#include "protocol_selectors.h"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

using namespace rtwall;
using namespace rtwall::cluster;

namespace {

std::filesystem::path outDir;

void writeSeed(const std::string& name, uint8_t selector, const std::vector<uint8_t>& bytes) {
    std::ofstream out(outDir / name, std::ios::binary);
    out.put(char(selector));
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    if (!out) {
        std::fprintf(stderr, "make_protocol_corpus: cannot write %s\n", (outDir / name).c_str());
        std::exit(1);
    }
}

// Each message twice: whole (selector 0) and as a bare payload (selector = its type).
template <class Msg> void seedMessage(const std::string& name, const Msg& msg) {
    Header header;
    header.session = 0x5EED;
    header.frame = 3;
    header.sceneVersion = 2;
    const std::vector<uint8_t> bytes = encodeMessage(header, msg);
    writeSeed("msg-" + name, 0, bytes);
    writeSeed("payload-" + name, uint8_t(messageTypeOf(msg)),
              std::vector<uint8_t>(bytes.begin() + kHeaderSize, bytes.end()));
}

// Built by hand so that the generator needs no engine code (Transform's helpers live there).
Transform translation(double x, double y, double z) {
    Transform t;
    t.m[3] = x;
    t.m[7] = y;
    t.m[11] = z;
    return t;
}

SceneSnapshot snapshot() {
    SceneSnapshot s;
    s.updateSeq = 2;
    const std::vector<uint8_t> box = encodeMesh(makeBox());
    s.meshes.push_back(MeshRef{"box", "shape:box", hashBytes(box.data(), box.size()), box.size()});
    Material glass;
    glass.name = "glass";
    glass.type = MaterialType::Glass;
    glass.ior = 1.45f;
    s.materials = {Material{}, glass};
    s.instances.push_back(InstanceDesc{0, 1, translation(1, 2, 3)});
    Light sun;
    sun.type = LightType::Directional;
    s.lights = {Light{}, sun};
    s.settings.width = 320;
    s.settings.height = 200;
    s.sections[1].enabled = true;  // version 9
    s.sections[1].normal = {0, 0, -1};
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: make_protocol_corpus <directory>\n");
        return 2;
    }
    outDir = argv[1];
    std::filesystem::create_directories(outDir);

    seedMessage("hello", Hello{kProtocolVersion, 8, "node-1"});
    seedMessage("welcome", Welcome{1, CodecSettings{TileCodec::Jpeg, 85, true, 3}, 4, 250, 3000});
    seedMessage("snapshot", snapshot());
    seedMessage("mesh-request", MeshRequest{{1, 2}});
    MeshData mesh;
    mesh.mesh = encodeMesh(makeSphere(3, 4));
    mesh.hash = hashBytes(mesh.mesh.data(), mesh.mesh.size());
    seedMessage("mesh-data", mesh);
    Update update;
    update.seq = 3;
    update.changes = {TransformChange{0, translation(0, 1, 0)},
                      MaterialChange{1, Material{}, {AssetRef{"wood.png", Hash128{1, 2}, 777}}}, LightChange{0, Light{}},
                      SettingsChange{RenderSettings{}}, SectionChange{2, SectionPlane{}},
                      VisibilityChange{0, Visibility::Hidden}};
    seedMessage("update", update);
    CameraDesc offAxis;  // a stereo eye: the projection window travels with the camera
    offAxis.window = ProjectionWindow{{-1.6f, -1.2f, 0.0f}, {3.2f, 0.0f, 0.0f}, {0.0f, 2.4f, 0.0f}};
    // Version 13: a mono frame carries its one view (the camera travels only in FrameBegin).
    seedMessage("frame-begin", FrameBegin{3, 2, TilePixels::Srgb8, {FrameView{}}});
    // Both eyes in one frame; the right eye a CAVE plane with two screens' regions.
    FrameView left{offAxis, {}, 0, 0}, right{offAxis, {{0, 0, 1024, 768}, {2048, 0, 1024, 768}}, 3072, 768};
    right.camera.position.x += 0.065f;
    seedMessage("frame-begin-views", FrameBegin{4, 2, TilePixels::Srgb8, {left, right}});
    seedMessage("tile-request", TileRequest{3, 4});
    seedMessage("tile-assign", TileAssign{3, {0, 1, 2, 17}});
    seedMessage("tile-result", TileResult{3, 17, TileCodec::Lz4, 1500, {1, 2, 3, 4, 5}});
    // Version 14: depth with every tile, each field its message's last and only when asked for.
    seedMessage("frame-begin-depth", FrameBegin{5, 2, TilePixels::Srgb8, {FrameView{}}, true});
    seedMessage("tile-result-depth", TileResult{5, 17, TileCodec::Lz4, 1500, {1, 2, 3, 4, 5}, TilePixels::Srgb8, {6, 7, 8}});
    seedMessage("heartbeat", Heartbeat{});
    seedMessage("heartbeat-idle", Heartbeat{3, 12, true});
    seedMessage("tile-stalled", TileStalled{3, 17, 61000});
    seedMessage("tile-failed", TileFailed{3, 17, {32, 0, 64, 32}, 16, "injected fault at pixel 40,20"});
    seedMessage("goodbye", Goodbye{"done"});
    seedMessage("ready", Ready{2, {3, 4}});
    seedMessage("resync-request", ResyncRequest{1});
    seedMessage("asset-request", AssetRequest{{5, 6}});
    seedMessage("asset-data", AssetData{{5, 6}, {0x89, 'P', 'N', 'G', 1, 2, 3}});
    // Display nodes (version 11; 12: the welcome's client keys, the frame's views and accumulation).
    seedMessage("node-hello", NodeHello{kProtocolVersion, "left", "tcp://127.0.0.1:5601", ""});
    seedMessage("node-hello-curve", NodeHello{kProtocolVersion, "right_2", "tcp://127.0.0.1:5602",
                                              "rq:rM>}U?@Lns47E1%kR.o@n%FcmmsL/@{H8]yf7"});
    seedMessage("node-welcome", NodeWelcome{1, 250, 3000, "[wall]\nrows = 1\ncolumns = 2\n"});
    seedMessage("node-welcome-keys", NodeWelcome{1, 250, 3000, "[wall]\nrows = 1\ncolumns = 2\n",
                                                 {"rq:rM>}U?@Lns47E1%kR.o@n%FcmmsL/@{H8]yf7"}});
    seedMessage("node-frame", NodeFrame{3, 128, 64, 32, TilePixels::Srgb8});
    seedMessage("node-frame-depth", NodeFrame{5, 128, 64, 32, TilePixels::Srgb8, {}, {}, false, 0, true});
    // Version 12: a stereo frame's views with their eyes, accumulated as linear tiles.
    {
        FrameView leftEye, rightEye;
        leftEye.camera.position = {-0.0325f, 0.0f, 2.0f};
        rightEye.camera.position = {0.0325f, 0.0f, 2.0f};
        rightEye.regions = {{0, 0, 64, 64}};
        rightEye.refWidth = 128;
        rightEye.refHeight = 64;
        seedMessage("node-frame-stereo",
                    NodeFrame{4, 128, 64, 32, TilePixels::LinearHalf, {leftEye, rightEye}, {0, 1}, true, 9});
    }
    seedMessage("node-have", NodeHave{3});
    seedMessage("node-swap", NodeSwap{3, {"right_2"}});
    seedMessage("node-swapped", NodeSwapped{3});
    seedMessage("node-list", NodeList{{{0, "left", "tcp://127.0.0.1:5601", ""}, {1, "right_2", "tcp://127.0.0.1:5602", ""}}});
    seedMessage("tile-routes", TileRoutes{3, {1, 3, 2, 0, 1, 3, 2, 2}});
    seedMessage("tile-done", TileDone{3, 17, 1500, 3072});
    // Version 15: re-projection on the nodes.
    seedMessage("node-welcome-reproject", NodeWelcome{1, 250, 3000, "[wall]\nrows = 1\ncolumns = 2\n", {}, true});
    {
        CameraDesc leftEye, rightEye;
        leftEye.name = rightEye.name = "";
        leftEye.position = {-0.0325f, 0.0f, 2.0f};
        rightEye.position = {0.0325f, 0.0f, 2.0f};
        rightEye.window = ProjectionWindow{{-1.6f, -1.2f, 0.0f}, {3.2f, 0.0f, 0.0f}, {0.0f, 2.4f, 0.0f}};
        seedMessage("node-pose", NodePose{12, 3, false, {leftEye, rightEye}});
    }
    seedMessage("node-shown", NodeShown{12});
    // Version 16: the denoiser's features after the depth, each only when asked for.
    seedMessage("frame-begin-features", FrameBegin{6, 2, TilePixels::LinearHalf, {FrameView{}}, true, kFeatureAll});
    seedMessage("tile-result-features",
                TileResult{6, 17, TileCodec::Lz4, 1500, {1, 2, 3, 4, 5}, TilePixels::LinearHalf, {6, 7, 8}, {9, 10}});

    // Version 17: how a display node denoises a frame, after its depth flag.
    {
        NodeDenoise d;
        d.settings.mode = DenoiseSettings::Mode::Svgf;
        d.ring = 70;
        d.features = kFeatureAll;
        d.sceneSeq = 4;
        seedMessage("node-frame-denoise",
                    NodeFrame{7, 128, 64, 32, TilePixels::LinearHalf, {}, {}, true, 9, true, d});
    }

    // Version 21: the eyes a frame and a pose were made for (a post-warping wall's nodes), alone
    // and with the frame's other optional parts.
    {
        const std::array<Float3, 2> eyes{Float3{-0.0325f, 1.7f, 2.5f}, Float3{0.0325f, 1.7f, 2.5f}};
        seedMessage("node-frame-eyes", NodeFrame{8, 128, 64, 32, TilePixels::Srgb8, {}, {}, false, 0, false, {}, eyes});
        NodeDenoise d;
        d.settings.mode = DenoiseSettings::Mode::Temporal;
        d.ring = 8;
        d.features = kFeatureNormal | kFeatureId;
        seedMessage("node-frame-denoise-eyes", NodeFrame{9, 128, 64, 32, TilePixels::LinearHalf, {}, {}, true, 9, true, d, eyes});
        CameraDesc c;
        c.name.clear();
        seedMessage("node-pose-eyes", NodePose{13, 4, false, {c}, eyes});
    }

    // Version 18: calibrated projectors: the grids (one NaN sample: a pixel on no screen) and a
    // frame whose view names them.
    {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        PixelWarp offsets{PixelWarp::Kind::ScreenOffsets, 2, 2, {{0.5f, 0.0f, 0.0f}, {nan, nan, nan}, {0, 1, 0}, {1, 1, 0}}};
        PixelWarp surface{PixelWarp::Kind::SurfacePoints, 1, 2, {{-1.5f, 0.0f, -2.0f}, {-1.5f, 2.25f, -2.1f}}};
        seedMessage("warp-grids", WarpGrids{{offsets, surface}});
        FrameView v;
        v.camera.name.clear();
        v.refWidth = 64;
        v.refHeight = 32;
        v.warps = {{0, {0, 0, 32, 32}, {}}, {1, {32, 0, 32, 32}, {}}};
        seedMessage("frame-begin-warps", FrameBegin{8, 2, TilePixels::Srgb8, {v}});
    }

    // Version 20: the console's picture of a wall on display nodes: the ask, an answer's part
    // (one row band of the right eye, compressed cells) and a node that presented nothing yet.
    seedMessage("node-preview-ask", NodePreviewAsk{3, 320, 0x3});
    {
        const uint32_t sums[8] = {2500, 1200, 40, 25, 255, 0, 17, 1};
        std::vector<uint8_t> z, scratch;
        encodePreviewCells(sums, 2, 2, z, scratch);
        seedMessage("node-preview", NodePreview{3, 41, 1, 1600, 1200, 4, 7, 6, 8, 2, true, z});
    }
    seedMessage("node-preview-none", NodePreview{3, 0, 0, 0, 0, 0, 0, 0, 0, 1, true, {}});

    writeSeed("mesh-box", fuzz::kMesh, encodeMesh(makeBox()));
    writeSeed("mesh-sphere-normals", fuzz::kMesh, encodeMesh(makeSphere(3, 5)));

    // An 8x6 gradient tile per codec; the three bytes after the selector give 8x6 and 3 bytes of padding.
    const int w = 8, h = 6;
    std::vector<uint8_t> rgb(size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) rgb[(size_t(y) * w + x) * 3 + c] = uint8_t(x * 30 + y * 20 + c * 50);
    for (TileCodec codec : {TileCodec::Raw, TileCodec::Lz4, TileCodec::Zstd, TileCodec::Jpeg}) {
        CodecSettings settings;
        settings.codec = codec;
        std::vector<uint8_t> bytes{uint8_t(w - 1), uint8_t(h - 1), 3};
        encodeTile(settings, rgb.data(), w, h, size_t(w) * 3, bytes);
        writeSeed(std::string("tile-") + codecName(codec), uint8_t(fuzz::kTile + unsigned(codec)), bytes);
    }
    // The same gradient as a linear half-float tile, LZ4 and zstd.
    std::vector<float> linear(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) linear[i] = float(rgb[i]) / 255.0f;
    for (TileCodec codec : {TileCodec::Lz4, TileCodec::Zstd}) {
        CodecSettings settings;
        settings.codec = codec;
        std::vector<uint8_t> scratch, bytes{uint8_t(w - 1), uint8_t(h - 1), 3};
        encodeWideTile(settings, linear.data(), w, h, size_t(w) * 3, scratch, bytes);
        const unsigned selector = fuzz::kWideTile + (codec == TileCodec::Lz4 ? 0 : 1);
        writeSeed(std::string("wide-tile-") + codecName(codec), uint8_t(selector), bytes);
    }
    // An 8x6 tile of features: a floor and an object, every feature and normal and id only.
    {
        std::vector<float> albedo(size_t(w) * h * 3), normal(size_t(w) * h * 3);
        std::vector<uint32_t> id(size_t(w) * h);
        for (int i = 0; i < w * h; ++i) {
            const bool object = i % w >= 4;
            albedo[size_t(i) * 3] = object ? 0.7f : 0.2f;
            albedo[size_t(i) * 3 + 1] = albedo[size_t(i) * 3 + 2] = 0.3f;
            normal[size_t(i) * 3 + (object ? 0 : 1)] = 1.0f;
            id[size_t(i)] = object ? 2u : 1u;
        }
        for (uint8_t bits : {uint8_t(kFeatureAll), uint8_t(kFeatureNormal | kFeatureId)}) {
            std::vector<uint8_t> scratch, packed, bytes{uint8_t(w - 1), uint8_t(h - 1), bits};
            encodeFeatureTile(bits, {albedo.data(), normal.data(), id.data(), size_t(w)}, w, h, scratch, packed);
            bytes.insert(bytes.end(), packed.begin(), packed.end());
            writeSeed("feature-tile-" + std::to_string(int(bits)), uint8_t(fuzz::kFeatureTile), bytes);
        }
    }
    return 0;
}
