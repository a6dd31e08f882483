// Issue 7, cluster part: texture images and volume files travel to the clients by content hash
// (clients need no copy of them), a tampered asset is rejected and counted, accumulated frames
// travel as linear half floats and sum exactly as one machine's Accumulator::addLinear, and
// only stochastic scenes are accumulated.
#include "codec.h"
#include "protocol.h"
#include "shading_scenes.h"
#include "local_cluster.h"
#include "fake_master.h"
#include "test_util.h"
#include "../cli_util.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>
#include <zmq.hpp>

#include <fstream>
#include <future>
#include <iterator>
#include <memory>
#include <optional>
#include <thread>

namespace rtwall {
namespace {

using test::LocalCluster;
using test::differingBytes;
using test::singleMachine;
using test::FakeMaster;

// One machine's frame in linear RGB (the whole image as one tile: pixels do not depend on tiles).
std::vector<float> singleMachineLinear(const Scene& scene, const SceneDesc& d, uint32_t frame) {
    const int w = d.settings.width, h = d.settings.height;
    std::vector<float> out(size_t(w) * h * 3);
    RenderSettings s = d.settings;
    s.threads = 1;
    renderTileLinear(scene, Camera(d.cameras.front(), w, h), TileRect{0, 0, w, h}, frame, s, out.data(), size_t(w) * 3);
    return out;
}

std::vector<uint8_t> readFileForTest(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}


// A legacy VTK structured-points volume (ASCII), the other format a volume material reads.
std::string writeLegacyVolume(const std::filesystem::path& dir) {
    std::string text = "# vtk DataFile Version 3.0\nramp\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 5 5 5\n"
                       "ORIGIN 0 0 0\nSPACING 1 1 1\nPOINT_DATA 125\nSCALARS density float 1\nLOOKUP_TABLE default\n";
    for (int k = 0; k < 5; ++k)
        for (int j = 0; j < 5; ++j)
            for (int i = 0; i < 5; ++i) text += std::to_string(0.1f * float(i + j + k) / 1.2f) + "\n";
    return test::writeFile(dir / "ramp.vtk", text).string();
}

// The material zoo (a PNG texture and a .vti volume among every material) plus a second volume
// from a legacy .vtk file; 3 files in all.
SceneDesc sceneWithFiles(const std::filesystem::path& dir) {
    SceneDesc d = test::zooInTilesOf8(dir, 64, 48);
    Material legacy = test::material("legacy", MaterialType::Volume, {1, 1, 1});
    legacy.volumeFile = writeLegacyVolume(dir);
    legacy.transfer = {{0.0f, {0.2f, 0.4f, 1.0f}, 0.5f}, {1.0f, {1, 1, 1}, 4.0f}};
    d.materials.push_back(legacy);
    d.instances.push_back({2, uint32_t(d.materials.size() - 1),
                           Transform::translate(-2.2, 0.4, -1.0) * Transform::scale(0.5, 0.5, 0.5)});
    return d;
}

// Clients run where the files do not exist (the directory is moved away after the master read
// them): they get the bytes from the master, and the frames are bit-identical to one machine.
TEST(ClusterAssets, TexturesAndVolumesTravelToClientsWithoutTheFiles) {
    const auto dir = test::scratchDir();
    const auto files = dir / "files";
    std::filesystem::create_directories(files);
    const SceneDesc desc = sceneWithFiles(files);
    const Scene reference(desc);  // reads the files while they are there
    ClusterSettings cs = test::inStep();
    cs.wideAccumulation = false;  // 8-bit frames, compared with one machine's 8-bit frames
    const auto cache = dir / "cache";
    {
        LocalCluster cluster(desc, cs, 0);
        std::filesystem::rename(files, dir / "elsewhere");  // no client can open the paths now
        ASSERT_FALSE(std::filesystem::exists(desc.materials[6].texture.file));
        // Two clients, one with a cache directory.
        for (int i = 0; i < 2; ++i) {
            ClientSettings c;
            c.cacheDir = i == 0 ? cache : std::filesystem::path();
            cluster.add(c);
        }
        ASSERT_TRUE(cluster.ready());
        for (int f = 0; f < 2; ++f) {
            FrameReport r;
            const Image img = cluster.master->renderFrame(&r);
            EXPECT_EQ(differingBytes(img, singleMachine(reference, desc, r.frame)), 0u) << "frame " << r.frame;
        }
        EXPECT_EQ(cluster.sum(&ClientCounters::assetsReceived), 6u) << "3 files to each of 2 clients";
        EXPECT_EQ(cluster.sum(&ClientCounters::assetsLocal), 0u);
        EXPECT_EQ(cluster.sum(&ClientCounters::rejectedAssets), 0u);
    }
    size_t cached = 0;
    std::filesystem::path oneCached;
    for (const auto& e : std::filesystem::directory_iterator(cache))
        if (e.path().extension() == ".rtasset") {
            ++cached;
            oneCached = e.path();
        }
    EXPECT_EQ(cached, 3u) << "every file was cached by content hash";

    // A client with that cache takes them from it; a cache file changed on disk (same size,
    // other bytes) is not trusted: that one file is fetched from the master again.
    {
        std::fstream f(oneCached, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(0);
        f.put('#');
    }
    SceneDesc inMemory = desc;  // the files are gone from their paths: the master gets them in memory
    for (const auto& e : std::filesystem::directory_iterator(dir / "elsewhere"))
        inMemory.files[(files / e.path().filename()).string()] =
            std::make_shared<const std::vector<uint8_t>>(readFileForTest(e.path().string()));
    LocalCluster again(inMemory, cs, 1, cache);
    ASSERT_TRUE(again.ready());
    FrameReport r;
    const Image img = again.master->renderFrame(&r);
    EXPECT_EQ(differingBytes(img, singleMachine(reference, desc, r.frame)), 0u);
    EXPECT_EQ(again.sum(&ClientCounters::assetsLocal), 2u);
    EXPECT_EQ(again.sum(&ClientCounters::assetsReceived), 1u);
}

// A master given the files in memory (SceneDesc::files, keyed by the materials' paths) needs
// them nowhere on disk either; its clients render the same bytes.
TEST(ClusterAssets, AMasterWithFilesInMemory) {
    const auto dir = test::scratchDir();
    const SceneDesc onDisk = sceneWithFiles(dir);
    const Scene reference(onDisk);
    SceneDesc inMemory = onDisk;
    for (const std::string& path : {onDisk.materials[6].texture.file, onDisk.materials[9].volumeFile,
                                    onDisk.materials.back().volumeFile}) {
        inMemory.files[path] = std::make_shared<const std::vector<uint8_t>>(readFileForTest(path));
        std::filesystem::remove(path);
    }
    const Scene fromMemory(inMemory);  // the engine decodes them from memory too
    ClusterSettings cs = test::inStep();
    cs.wideAccumulation = false;
    LocalCluster cluster(inMemory, cs, 2);
    ASSERT_TRUE(cluster.ready());
    FrameReport r;
    const Image img = cluster.master->renderFrame(&r);
    const Image expected = singleMachine(reference, onDisk, r.frame);
    EXPECT_EQ(differingBytes(img, expected), 0u);
    EXPECT_EQ(differingBytes(singleMachine(fromMemory, inMemory, r.frame), expected), 0u);
    EXPECT_EQ(cluster.sum(&ClientCounters::assetsReceived), 6u);
}

// A material changed at run time to an image the scene never loaded: the change names the file
// by hash and the clients fetch it from the master (the path exists nowhere: the master has the
// bytes in memory), so the frame is one machine's with that image. A client that joins later
// gets it with the state; a file that cannot be read is refused before anything changes.
TEST(ClusterAssets, AMaterialChangedToANewFileTravels) {
    const auto dir = test::scratchDir();
    SceneDesc desc = sceneWithFiles(dir);
    Image stripes;
    stripes.width = stripes.height = 8;
    stripes.rgb.resize(8 * 8 * 3);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            uint8_t* p = stripes.pixel(x, y);
            p[0] = uint8_t(x & 1 ? 250 : 10);
            p[1] = uint8_t(y * 30);
            p[2] = 128;
        }
    writePng(stripes, dir / "stripes.png");
    const std::string path = (dir / "nowhere" / "stripes.png").string();
    desc.files[path] = std::make_shared<const std::vector<uint8_t>>(readFileForTest((dir / "stripes.png").string()));
    ASSERT_FALSE(std::filesystem::exists(path));

    ClusterSettings cs = test::inStep();
    cs.wideAccumulation = false;
    LocalCluster cluster(desc, cs, 2);
    Master& master = *cluster.master;
    ASSERT_TRUE(cluster.ready());
    const Image before = cluster.expectFrameOf(desc);

    SceneDesc changed = desc;
    changed.materials[0].texture.kind = TextureKind::Image;  // the floor
    changed.materials[0].texture.file = path;
    changed.materials[0].texture.scale = 0.5f;
    master.setMaterial(0, changed.materials[0]);
    const Image after = cluster.expectFrameOf(changed, "the new image");
    EXPECT_GT(differingBytes(after, before), after.rgb.size() / 10) << "the floor shows the new image";
    EXPECT_EQ(cluster.sum(&ClientCounters::assetsReceived), 2u) << "the new file, to each client";
    EXPECT_EQ(cluster.sum(&ClientCounters::rejectedAssets), 0u);

    cluster.add();
    const std::shared_ptr<ClientCounters> late = cluster.counters.back();
    ASSERT_TRUE(cluster.ready());
    Material unreadable = changed.materials[0];
    unreadable.texture.file = (dir / "missing.png").string();
    try {
        master.setMaterial(0, unreadable);
        ADD_FAILURE() << "a material naming a missing file was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos) << e.what();
    }
    for (int f = 0; f < 2; ++f) cluster.expectFrameOf(changed, "with a late client");
    EXPECT_EQ(late->assetsReceived.load(), 1u) << "the late client fetched the new file with the state";
}


TEST(ClusterAssets, ATamperedAssetIsRejectedAndCounted) {
    using namespace cluster;
    const auto dir = test::scratchDir();
    SceneDesc desc = test::materialZoo(dir, 32, 24);
    const std::string texture = desc.materials[6].texture.file;
    const std::vector<uint8_t> realBytes = readFileForTest(texture);
    ASSERT_FALSE(realBytes.empty());
    std::filesystem::remove(texture);  // the client must get it from the (fake) master

    FakeMaster fake;
    ClientSettings cs;
    cs.counters = std::make_shared<ClientCounters>();
    auto client = test::startClient(fake, 3000, cs);
    std::string peer;
    ASSERT_NO_FATAL_FAILURE(test::welcome(fake, peer));

    // The state: the zoo without its volume (so that only the texture is an asset).
    desc.materials[9] = test::material("plain", MaterialType::Lambert, {0.5f, 0.5f, 0.5f});
    test::ScriptedScene scripted = test::scriptedScene(desc);
    SceneSnapshot& snap = scripted.snapshot;
    const Hash128 textureHash = hashBytes(realBytes.data(), realBytes.size());
    snap.assets.push_back({texture, textureHash, realBytes.size()});
    fake.send(peer, snap);
    ASSERT_NO_FATAL_FAILURE(test::serveMeshes(fake, peer, scripted));
    const auto assetReq = fake.expect(MsgType::AssetRequest, 10000);
    ASSERT_TRUE(assetReq) << "the client asks for the file it does not have";
    EXPECT_EQ(decodePayload<AssetRequest>(assetReq->payload.data(), assetReq->payload.size()).hash, textureHash);

    // Tampered: one byte changed (same size), then one byte short, then a file it never asked for.
    std::vector<uint8_t> tampered = realBytes;
    tampered[tampered.size() / 2] ^= 0x40;
    fake.send(peer, AssetData{textureHash, tampered});
    fake.send(peer, AssetData{textureHash, std::vector<uint8_t>(realBytes.begin(), realBytes.end() - 1)});
    fake.send(peer, AssetData{Hash128{1, 2}, realBytes});
    EXPECT_FALSE(fake.expect(MsgType::Ready, 1000)) << "no scene without the true file";
    EXPECT_EQ(cs.counters->rejectedAssets.load(), 2u);
    EXPECT_GE(cs.counters->droppedMessages.load(), 1u) << "the unrequested file";

    // The true bytes: the client builds the scene and proves the state.
    fake.send(peer, AssetData{textureHash, realBytes});
    const auto ready = fake.expect(MsgType::Ready, 30000);
    ASSERT_TRUE(ready);
    const Ready r = decodePayload<Ready>(ready->payload.data(), ready->payload.size());
    EXPECT_EQ(r.stateHash, stateHash(snap));
    EXPECT_EQ(cs.counters->assetsReceived.load(), 1u);
    EXPECT_EQ(cs.counters->rejectedAssets.load(), 2u);
    fake.send(peer, Goodbye{"done"});
    EXPECT_EQ(client.get(), 0);
}

// Progressive GI over the cluster: N frames accumulated from linear half-float tiles equal one
// machine's N-frame Accumulator::addLinear bit for bit, with any codec (JPEG becomes lossless for
// them). The 8-bit accumulation they replace differs (its quantisation bias).
TEST(ClusterAccumulation, LinearTilesAccumulateExactlyAsOneMachine) {
    const auto dir = test::scratchDir();
    SceneDesc desc = test::zooInTilesOf8(dir, 64, 48, 1);
    const Scene scene(desc);
    ClusterSettings cs = test::inStep();
    cs.prefetch = 2;
    LocalCluster cluster(desc, cs, 3);
    Master& master = *cluster.master;
    ASSERT_TRUE(cluster.ready());
    constexpr int kFrames = 6;
    Accumulator clusterAcc, localAcc, local8;
    std::vector<float> linear;
    uint64_t wideBytes = 0;
    for (int f = 0; f < kFrames; ++f) {
        if (f == kFrames / 2) {
            CodecSettings jpeg;
            jpeg.codec = TileCodec::Jpeg;
            master.setCodec(jpeg);
        }
        FrameReport r;
        const Image img = master.renderFrame(&r, &linear);
        ASSERT_TRUE(r.stochastic);
        ASSERT_TRUE(r.linear);
        ASSERT_EQ(linear.size(), size_t(64 * 48 * 3));
        const std::vector<float> local = singleMachineLinear(scene, desc, r.frame);
        size_t differing = 0;
        for (size_t i = 0; i < local.size(); ++i) differing += cluster::roundToHalf(local[i]) != linear[i];
        EXPECT_EQ(differing, 0u) << "frame " << r.frame << ": the half-float tiles carry one machine's values";
        clusterAcc.addLinear(linear.data(), img.width, img.height);
        localAcc.addLinear(local.data(), 64, 48);
        local8.add(singleMachine(scene, desc, r.frame));
        wideBytes += r.bytes;
    }
    EXPECT_EQ(differingBytes(clusterAcc.resolve(), localAcc.resolve()), 0u);
    EXPECT_GT(differingBytes(local8.resolve(), localAcc.resolve()), 0u) << "8-bit accumulation is biased";
    std::printf("linear tiles: %.0f bytes per frame (64x48, lz4 then jpeg->lz4)\n", double(wideBytes) / kFrames);
}

// Only stochastic frames are accumulated (rtwall run follows FrameReport::stochastic); the
// predicate agrees with what rendering does: a deterministic scene gives the same bytes every
// frame, each stochastic feature alone makes frames differ.
TEST(ClusterAccumulation, OnlyStochasticScenesAccumulate) {
    const auto dir = test::scratchDir();
    SceneDesc base = test::materialZoo(dir, 48, 32);
    base.settings.tileSize = 16;
    // Deterministic: no area light, the metal polished, no volume.
    base.lights.resize(1);
    base.materials[3].roughness = 0.0f;
    base.materials[9] = test::material("plain", MaterialType::Lambert, {0.5f, 0.5f, 0.5f});
    // In linear values: a small light's sampling noise may stay within one 8-bit level.
    auto framesDiffer = [](const SceneDesc& d) {
        const Scene s(d);
        return singleMachineLinear(s, d, 1) != singleMachineLinear(s, d, 2);
    };
    EXPECT_FALSE(rendersStochastically(base));
    EXPECT_FALSE(framesDiffer(base));
    std::vector<std::pair<std::string, SceneDesc>> variants;
    SceneDesc v = base;
    v.settings.gi = true;
    variants.emplace_back("gi", v);
    v = base;
    // Its own area light, the same as the zoo's (which pointed up, away from the scene, before
    // issue 7's fix).
    Light area;
    area.type = LightType::Area;
    area.position = {0.5f, 3.5f, -0.5f};
    area.edge1 = {1, 0, 0};
    area.edge2 = {0, 0, 1};  // cross points down
    area.intensity = 3.0f;
    v.lights.push_back(area);
    variants.emplace_back("area light", v);
    v = base;
    v.materials[3].roughness = 0.3f;
    variants.emplace_back("rough metal", v);
    v = base;
    v.materials[9] = test::materialZoo(dir, 48, 32).materials[9];
    variants.emplace_back("volume", v);
    for (const auto& [name, d] : variants) {
        EXPECT_TRUE(rendersStochastically(d)) << name;
        EXPECT_TRUE(framesDiffer(d)) << name;
    }
    SceneDesc depth = variants[0].second;
    depth.settings.view = ViewMode::Depth;
    EXPECT_FALSE(rendersStochastically(depth)) << "false-colour views are not refined";

    // The master reports it per frame, and sends linear tiles for stochastic frames only.
    LocalCluster cluster(base, test::inStep(), 1);
    ASSERT_TRUE(cluster.ready());
    FrameReport r;
    std::vector<float> linear{1.0f};
    cluster.master->renderFrame(&r, &linear);
    EXPECT_FALSE(r.stochastic);
    EXPECT_FALSE(r.linear);
    EXPECT_TRUE(linear.empty());
    cluster.master->setRenderSettings(variants[0].second.settings);
    cluster.master->renderFrame(&r, &linear);
    EXPECT_TRUE(r.stochastic);
    EXPECT_TRUE(r.linear);
    EXPECT_EQ(linear.size(), size_t(48 * 32 * 3));
}

// A codec change is a state change: an accumulation over it restarts.
TEST(ClusterAccumulation, SetCodecMovesTheStateOn) {
    const auto dir = test::scratchDir();
    SceneDesc desc = test::materialZoo(dir, 32, 24);
    LocalCluster cluster(desc, test::inStep(), 1);
    ASSERT_TRUE(cluster.ready());
    FrameReport a, b, c;
    cluster.master->renderFrame(&a);
    cluster.master->renderFrame(&b);
    EXPECT_EQ(a.stateSeq, b.stateSeq);
    CodecSettings zstd;
    zstd.codec = TileCodec::Zstd;
    cluster.master->setCodec(zstd);
    cluster.master->renderFrame(&c);
    EXPECT_NE(c.stateSeq, b.stateSeq);
}

// rtwall run accumulates a stochastic scene's frames only.
TEST(ClusterAccumulation, RunAccumulatesOnlyStochasticScenes) {
    const auto dir = test::scratchDir();
    auto run = [](const std::string& args) { return test::runCli(RTWALL_EXE, args, 300); };
    // A mesh with the default point light: deterministic.
    test::writeFile(dir / "plain.toml", "scene = \"" + (test::dataDir() / "meshes/box_quads.obj").string() +
                                            "\"\n[image]\nwidth = 48\nheight = 32\n"
                                            "[cluster]\nclients = 1\n[run]\nframes = 3\nwrite_every = 0\norbit = 0\n");
    test::CliResult r = run("run " + (dir / "plain.toml").string() + " --headless");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("no accumulation: the scene is deterministic"), std::string::npos) << r.output;
    // The office (a volume on the desk, an area light): every frame of the still view is
    // accumulated, as linear tiles.
    ASSERT_EQ(run("gen office --out " + (dir / "office").string()).status, 0);
    test::writeFile(dir / "run.toml", "scene = \"office/office.toml\"\n[image]\nwidth = 48\nheight = 32\n"
                                      "[cluster]\nclients = 1\n[run]\nframes = 3\nwrite_every = 0\norbit = 0\n");
    r = run("run " + (dir / "run.toml").string() + " --headless");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("progressive refinement: 3 of 3 frames accumulated (stochastic scene), 3 of them as linear tiles"),
              std::string::npos)
        << r.output;
}

}  // namespace
}  // namespace rtwall
