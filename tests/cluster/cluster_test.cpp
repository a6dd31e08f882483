// The cluster end to end on loopback: a Master in this process and render clients running
// runClient() on threads (each with its own ZeroMQ context, so nothing is shared but TCP).
// Every loop is bounded; every wait has a timeout.
#include "test_util.h"

#include "protocol.h"

#include <rtwall/cluster.h>

#include <zmq.hpp>

#include <gtest/gtest.h>

#include <algorithm>

#include <memory>
#include <thread>

namespace rtwall {
namespace {

class ClientThreads {
public:
    ClientThreads(const std::string& endpoint, int count, int threadsEach = 1) {
        for (int i = 0; i < count; ++i) add(endpoint, threadsEach);
    }
    void add(const std::string& endpoint, int threadsEach = 1, const std::filesystem::path& cacheDir = {},
             int extraTileDelayMs = 0) {
        ClientSettings cs;
        cs.extraTileDelayMs = extraTileDelayMs;
        cs.connect = endpoint;
        cs.threads = threadsEach;
        cs.cacheDir = cacheDir;
        cs.exitAfterIdleMs = 4000;  // never outlive the test by much
        threads_.emplace_back([cs] { runClient(cs); });
    }
    ~ClientThreads() {
        for (auto& t : threads_) t.join();
    }

private:
    std::vector<std::thread> threads_;
};

// A master with client threads. The master goes first (its goodbye ends the clients), then
// the client threads are joined, also when a test fails half-way.
struct LocalCluster {
    LocalCluster(const SceneDesc& desc, const ClusterSettings& cs, int clientCount)
        : master(std::make_unique<Master>(desc, cs)), clients(master->endpoint(), clientCount) {}
    ~LocalCluster() { master.reset(); }
    std::unique_ptr<Master> master;
    ClientThreads clients;
};

SceneDesc demoScene(int width, int height) {
    SceneDesc desc = loadSceneFile(test::sourceDir() / "configs/demo.toml");
    desc.settings.width = width;
    desc.settings.height = height;
    desc.settings.supersample = 1;
    return desc;
}

Image singleMachine(const SceneDesc& desc) {
    const Scene scene(desc);
    return renderFrame(scene, Camera(desc.cameras.front(), desc.settings.width, desc.settings.height), desc.settings);
}

size_t differingBytes(const Image& a, const Image& b) {
    if (a.rgb.size() != b.rgb.size()) return std::max(a.rgb.size(), b.rgb.size());
    size_t n = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) n += a.rgb[i] != b.rgb[i];
    return n;
}

struct Layout {
    int clients, tile, prefetch;
    TileCodec codec;
};

class ClusterImage : public ::testing::TestWithParam<Layout> {};

TEST_P(ClusterImage, BitIdenticalToOneMachine) {
    const Layout& l = GetParam();
    SceneDesc desc = demoScene(160, 120);
    desc.settings.tileSize = l.tile;
    ClusterSettings cs;
    cs.prefetch = l.prefetch;
    cs.async = false;
    cs.codec.codec = l.codec;
    LocalCluster cluster(desc, cs, l.clients);
    Master& master = *cluster.master;
    ASSERT_TRUE(master.waitForClients(l.clients, 30000));
    FrameReport report;
    const Image img = master.renderFrame(&report);
    EXPECT_EQ(differingBytes(img, singleMachine(desc)), 0u);
    uint64_t tiles = 0;
    for (const ClientReport& c : report.clients) tiles += c.tiles;
    EXPECT_EQ(tiles, makeTiles(160, 120, l.tile).size());
    // Every tile names the client that rendered it (the display's false-colour view), and the
    // counts agree with the per-client report.
    ASSERT_EQ(report.tileOwners.size(), makeTiles(160, 120, l.tile).size());
    for (const ClientReport& c : report.clients)
        EXPECT_EQ(uint64_t(std::count(report.tileOwners.begin(), report.tileOwners.end(), c.id)), c.tiles);
}

INSTANTIATE_TEST_SUITE_P(Layouts, ClusterImage,
                         ::testing::Values(Layout{1, 32, 4, TileCodec::Lz4}, Layout{2, 16, 1, TileCodec::Raw},
                                           Layout{4, 8, 8, TileCodec::Zstd}, Layout{2, 13, 4, TileCodec::Lz4},
                                           Layout{4, 64, 2, TileCodec::Raw}));

TEST(Cluster, JpegIsCloseButLossy) {
    SceneDesc desc = demoScene(160, 120);
    ClusterSettings cs;
    cs.async = false;
    cs.codec.codec = TileCodec::Jpeg;
    cs.codec.jpegQuality = 95;
    LocalCluster cluster(desc, cs, 2);
    Master& master = *cluster.master;
    ASSERT_TRUE(master.waitForClients(2, 30000));
    const Image img = master.renderFrame();
    const Image ref = singleMachine(desc);
    ASSERT_EQ(img.rgb.size(), ref.rgb.size());
    double se = 0;
    for (size_t i = 0; i < img.rgb.size(); ++i) se += double(int(img.rgb[i]) - int(ref.rgb[i])) * (int(img.rgb[i]) - int(ref.rgb[i]));
    const double psnr = 10 * std::log10(255.0 * 255.0 / (se / double(img.rgb.size())));
    EXPECT_GT(psnr, 35.0);
    EXPECT_GT(differingBytes(img, ref), 0u) << "JPEG at quality 95 should not be bit-exact on this image";
}

// Affinity is measured with two equally fast clients, as on a wall's dedicated render PCs: on
// this 2-core test machine the clients and the master share the CPUs, and whichever process the
// kernel runs less would have its tiles stolen; a fixed 2 ms per tile (sleep, no CPU) makes
// the pace of both clients the same.
double affinityFraction(bool affinity, uint64_t* stolenOut) {
    SceneDesc desc = demoScene(320, 240);
    desc.settings.tileSize = 16;
    ClusterSettings cs;
    cs.async = false;
    cs.affinity = affinity;
    LocalCluster cluster(desc, cs, 0);
    for (int i = 0; i < 2; ++i) cluster.clients.add(cluster.master->endpoint(), 1, {}, 2);
    Master& master = *cluster.master;
    if (!master.waitForClients(2, 30000)) return -1;
    master.renderFrame();
    const size_t tiles = makeTiles(320, 240, 16).size();
    uint64_t hits = 0, total = 0;
    for (int f = 0; f < 4; ++f) {
        FrameReport r;
        master.renderFrame(&r);
        hits += r.affinityHits;
        *stolenOut += r.tilesStolen;
        total += tiles;
    }
    return double(hits) / double(total);
}

TEST(Cluster, AffinityKeepsTilesWithTheirClient) {
    // A still camera: at least 90% of tiles go back to the client that rendered them last frame.
    uint64_t stolen = 0;
    EXPECT_GE(affinityFraction(true, &stolen), 0.9) << stolen << " stolen";
}

TEST(Cluster, WithoutAffinityNothingIsStolen) {
    // With affinity off every tile starts in the shared queue, so there are no per-client
    // queues to steal from. How many tiles land on last frame's client is then down to timing
    // (two evenly paced clients can take turns identically frame after frame), so that share is
    // reported, not asserted; the scheduler tests compare the two policies deterministically.
    uint64_t stolen = 0;
    const double kept = affinityFraction(false, &stolen);
    EXPECT_GE(kept, 0.0);
    EXPECT_EQ(stolen, 0u);
    std::printf("affinity off: %.0f%% of tiles kept their client\n", 100.0 * kept);
}

TEST(Cluster, UpdatesShowInTheNextFrameOnly) {
    SceneDesc desc = demoScene(96, 72);
    ClusterSettings cs;
    cs.async = true;
    LocalCluster cluster(desc, cs, 2);
    Master& master = *cluster.master;
    ASSERT_TRUE(master.waitForClients(2, 30000));

    SceneDesc moved = desc;
    CameraDesc top = *desc.findCamera("top");
    moved.cameras = {top};
    const Image before = singleMachine(desc), after = singleMachine(moved);
    ASSERT_GT(differingBytes(before, after), 0u);

    // Asynchronous: renderFrame returns frame N while N+1 already renders. An update made now
    // lands in the first frame that begins after it.
    const Image f1 = master.renderFrame();  // frame 1 (frame 2 begins)
    master.setCamera(top);                   // during frame 2
    const Image f2 = master.renderFrame();  // frame 2 (frame 3 begins, with the update)
    const Image f3 = master.renderFrame();  // frame 3
    EXPECT_EQ(differingBytes(f1, before), 0u);
    EXPECT_EQ(differingBytes(f2, before), 0u) << "an update made during frame 2 must not show in frame 2";
    EXPECT_EQ(differingBytes(f3, after), 0u) << "it must show in frame 3";
}

TEST(Cluster, TransformMaterialAndLightUpdatesMatchARebuiltScene) {
    SceneDesc desc = demoScene(96, 72);
    ClusterSettings cs;
    cs.async = false;
    LocalCluster cluster(desc, cs, 2);
    Master& master = *cluster.master;
    ASSERT_TRUE(master.waitForClients(2, 30000));
    master.renderFrame();

    SceneDesc changed = desc;
    changed.instances[1].transform = Transform::translate(0.5, 1.0, 0.3) * changed.instances[1].transform;
    changed.materials[1].color = {0.2f, 0.6f, 0.3f};
    changed.lights[0].intensity = 40.0f;
    master.setInstanceTransform(1, changed.instances[1].transform);
    master.setMaterial(1, changed.materials[1]);
    master.setLight(0, changed.lights[0]);
    EXPECT_EQ(differingBytes(master.renderFrame(), singleMachine(changed)), 0u);
}

// Lost update messages (fault injection drops every second one per client): each client sees
// the gap when a frame needs the missing update, resyncs from the frame's state, and every frame
// still equals the single-machine image of the state it was begun with.
TEST(Cluster, LostUpdatesAreDetectedAndResynced) {
    SceneDesc desc = demoScene(96, 72);
    ClusterSettings cs;
    cs.async = false;
    cs.dropEveryNthUpdate = 2;
    LocalCluster cluster(desc, cs, 2);
    Master& master = *cluster.master;
    ASSERT_TRUE(master.waitForClients(2, 30000));
    master.renderFrame();
    SceneDesc expect = desc;
    for (int f = 0; f < 5; ++f) {
        // Two update messages per frame: one of them is lost for each client.
        expect.lights[0].intensity = 20.0f + 15.0f * f;
        expect.materials[1].color = {0.2f + 0.1f * f, 0.5f, 0.3f};
        master.setLight(0, expect.lights[0]);
        // The master merges updates made within a couple of milliseconds into one message;
        // these two must travel apart so that one of them is lost.
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        master.setMaterial(1, expect.materials[1]);
        FrameReport r;
        const Image img = master.renderFrame(&r);
        EXPECT_EQ(differingBytes(img, singleMachine(expect)), 0u) << "frame " << r.frame;
    }
    EXPECT_GE(master.resyncs(), 5u) << "the losses must have been noticed and repaired";
    EXPECT_EQ(master.connectedClients(), 2);
}

TEST(Cluster, LateJoinerGetsTheCurrentStateFirst) {
    SceneDesc desc = demoScene(96, 72);
    ClusterSettings cs;
    cs.async = false;
    LocalCluster cluster(desc, cs, 1);
    Master& master = *cluster.master;
    ASSERT_TRUE(master.waitForClients(1, 30000));
    master.renderFrame();
    CameraDesc top = *desc.findCamera("top");
    master.setCamera(top);
    master.setLight(0, Light{LightType::Point, {0, 4, 2}, {}, {1, 1, 1}, 50.0f});
    master.renderFrame();
    // A client joining now must receive the snapshot with both updates, prove it (state hash)
    // and only then render; the frame must equal the single-machine image of the new state.
    cluster.clients.add(master.endpoint());
    ASSERT_TRUE(master.waitForClients(2, 30000));
    SceneDesc expect = desc;
    expect.cameras = {top};
    expect.lights[0] = Light{LightType::Point, {0, 4, 2}, {}, {1, 1, 1}, 50.0f};
    for (int f = 0; f < 3; ++f) {
        FrameReport r;
        const Image img = master.renderFrame(&r);
        EXPECT_EQ(differingBytes(img, singleMachine(expect)), 0u) << "frame " << r.frame;
    }
}

TEST(Cluster, AFrameWithoutAnyClientFailsInsteadOfHanging) {
    SceneDesc desc = demoScene(32, 24);
    ClusterSettings cs;
    cs.async = false;
    cs.timeoutMs = 500;
    Master master(desc, cs);
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_THROW(master.renderFrame(), std::runtime_error);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(30));
}

// Meshes travel by content hash: a client that cannot read the master's file (or reads a
// different file under that name) gets the bytes from the master, checks their hash and keeps
// them in its cache directory; a local file with the wrong content is never trusted.
TEST(Cluster, MeshesTravelByContentHash) {
    SceneDesc desc = demoScene(96, 72);
    const auto cache = test::scratchDir();
    for (MeshDesc& m : desc.meshes)
        if (m.name == "knot") m.source = (test::dataDir() / "meshes/box_quads.obj").string();  // same name, other content
    ClusterSettings cs;
    cs.async = false;
    {
        LocalCluster cluster(desc, cs, 0);
        cluster.clients.add(cluster.master->endpoint(), 1, cache);
        ASSERT_TRUE(cluster.master->waitForClients(1, 30000));
        EXPECT_EQ(differingBytes(cluster.master->renderFrame(), singleMachine(desc)), 0u);
    }
    size_t cached = 0;
    for (const auto& e : std::filesystem::directory_iterator(cache)) cached += e.path().extension() == ".rtmesh";
    EXPECT_EQ(cached, desc.meshes.size()) << "every mesh was fetched and cached";
    // A second client finds them all in its cache.
    LocalCluster again(desc, cs, 0);
    again.clients.add(again.master->endpoint(), 1, cache);
    ASSERT_TRUE(again.master->waitForClients(1, 30000));
    EXPECT_EQ(differingBytes(again.master->renderFrame(), singleMachine(desc)), 0u);
}

// A client written against the protocol by hand, to misbehave on purpose: it completes the
// handshake honestly (Ready with the right state hash) and asks for tiles, then hands every
// TileAssign to the test, which decides what the client does with the tiles. Bounded: at most
// 200 messages, 5 s per receive.
class RogueClient {
public:
    RogueClient(const std::string& endpoint, uint32_t wantTiles) : socket_(ctx_, zmq::socket_type::dealer), want_(wantTiles) {
        using namespace cluster;
        socket_.set(zmq::sockopt::linger, 0);
        socket_.set(zmq::sockopt::rcvtimeo, 5000);
        socket_.connect(endpoint);
        Header h;
        h.type = MsgType::Hello;
        socket_.send(zmq::buffer(encodeMessage(h, Hello{kProtocolVersion, 1, "rogue"})));
    }

    // Runs the conversation; onReady is called once the master accepted our state, onAssign for
    // each assignment until it returns false.
    template <class OnReady, class OnAssign> bool run(OnReady&& onReady, OnAssign&& onAssign) {
        using namespace cluster;
        bool ready = false;
        for (int i = 0; i < 200; ++i) {
            zmq::message_t msg;
            if (!socket_.recv(msg)) break;
            const auto* p = static_cast<const uint8_t*>(msg.data());
            const Header in = decodeHeader(p, msg.size());
            session_ = in.session;
            const uint8_t* payload = p + kHeaderSize;
            const size_t n = msg.size() - kHeaderSize;
            if (in.type == MsgType::SceneSnapshot && !ready) {
                const auto snap = decodePayload<SceneSnapshot>(payload, n);
                send(MsgType::Ready, 0, Ready{snap.updateSeq, stateHash(snap)});
                ready = true;
                onReady();
            } else if (in.type == MsgType::FrameBegin) {
                const auto fb = decodePayload<FrameBegin>(payload, n);
                send(MsgType::TileRequest, fb.frame, TileRequest{fb.frame, want_});
            } else if (in.type == MsgType::TileAssign) {
                if (!onAssign(decodePayload<TileAssign>(payload, n))) break;
            }
        }
        return ready;
    }

    template <class Msg> void send(cluster::MsgType type, uint32_t frame, const Msg& m) {
        cluster::Header h;
        h.type = type;
        h.session = session_;
        h.frame = frame;
        socket_.send(zmq::buffer(cluster::encodeMessage(h, m)));
    }

private:
    zmq::context_t ctx_;
    zmq::socket_t socket_;
    uint32_t want_;
    uint64_t session_ = 0;
};

// A client that answers its tiles with bytes that do not decode: the results are dropped, the
// tiles reopened and rendered by the honest client; the frame still completes, bit-identical.
TEST(Cluster, UndecodableResultsAreReRendered) {
    using namespace cluster;
    SceneDesc desc = demoScene(96, 72);
    desc.settings.tileSize = 8;
    desc.settings.supersample = 4;
    ClusterSettings cs;
    cs.async = false;
    LocalCluster cluster(desc, cs, 1);
    Master& master = *cluster.master;
    ASSERT_TRUE(master.waitForClients(1, 30000));

    RogueClient rogue(master.endpoint(), 4);
    std::thread frame;
    Image img;
    int lies = 0;
    rogue.run([&] { frame = std::thread([&] { img = master.renderFrame(); }); },
              [&](const TileAssign& a) {
                  for (uint32_t t : a.tiles) {
                      TileResult r;
                      r.frame = a.frame;
                      r.tile = t;
                      r.codec = TileCodec::Lz4;
                      r.pixels.assign(40, 0x7F);  // not an LZ4 block of an 8x8 tile
                      rogue.send(MsgType::TileResult, a.frame, r);
                      ++lies;
                  }
                  return false;
              });
    ASSERT_TRUE(frame.joinable());
    frame.join();
    ASSERT_GT(lies, 0);
    EXPECT_EQ(differingBytes(img, singleMachine(desc)), 0u);
    EXPECT_GE(master.droppedMessages(), uint64_t(lies));
}

// A client that completes the handshake, takes tiles and then goes silent (a PC that froze
// or lost its cable): the master must notice within its timeout, put the tiles back, and the
// frame must still be bit-identical.
TEST(Cluster, SilentClientLosesNoTile) {
    SceneDesc desc = demoScene(96, 72);
    desc.settings.tileSize = 8;
    desc.settings.supersample = 4;  // slow enough that the rogue's request lands mid-frame
    ClusterSettings cs;
    cs.async = false;
    cs.timeoutMs = 400;
    cs.heartbeatMs = 50;
    LocalCluster cluster(desc, cs, 1);
    Master& master = *cluster.master;
    ASSERT_TRUE(master.waitForClients(1, 30000));

    RogueClient rogue(master.endpoint(), 8);
    FrameReport first;
    Image firstImage;
    std::thread frame;
    const bool ready = rogue.run([&] { frame = std::thread([&] { firstImage = master.renderFrame(&first); }); },
                                 [](const cluster::TileAssign&) { return false; });  // holding tiles: go silent
    ASSERT_TRUE(ready);
    frame.join();  // completes only if the rogue's tiles were rendered by someone else
    EXPECT_EQ(differingBytes(firstImage, singleMachine(desc)), 0u);
    // The straggler rule re-issued the rogue's tiles long before its heartbeat timed out.
    EXPECT_GT(first.tilesReissued, 0u);
    // Then the heartbeat timeout removes it (bounded wait).
    for (int i = 0; i < 300 && master.connectedClients() != 1; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_EQ(master.connectedClients(), 1);
    FrameReport report;
    EXPECT_EQ(differingBytes(master.renderFrame(&report), singleMachine(desc)), 0u);
    EXPECT_EQ(report.clients.size(), 1u);
}

}  // namespace
}  // namespace rtwall
