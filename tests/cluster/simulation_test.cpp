// The cluster simulation against results computed by hand, and the tile profile file.
// Times are powers of two so that every sum is exact in floating point: the expectations are
// exact equalities, not tolerances.
#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>

namespace rtwall {
namespace {

// n tiles of 64x64 in one row, each costing `render` seconds and `bytes` bytes, no encode or
// decode cost unless given.
TileProfile uniformProfile(int tiles, double render, uint32_t bytes, double decode = 0) {
    TileProfile p;
    p.width = 64 * tiles;
    p.height = 64;
    p.tileSize = 64;
    p.renderSeconds = {std::vector<double>(size_t(tiles), render)};
    TileProfile::CodecCost c;
    c.codec.codec = TileCodec::Raw;
    c.bytes.assign(size_t(tiles), bytes);
    c.encodeSeconds.assign(size_t(tiles), 0.0);
    c.decodeSeconds.assign(size_t(tiles), decode);
    p.codecs = {c};
    return p;
}

SimConfig trivial() {
    SimConfig c;
    c.clients = 1;
    c.threadsPerClient = 1;
    c.prefetch = 1;
    c.clientLink.latencySeconds = 1.0 / 1024;
    c.decodeThreads = 1;
    c.frames = 3;
    c.warmupFrames = 1;
    c.housekeepingSeconds = 0;
    return c;
}

TEST(ClusterSimulation, OneClientPrefetchOneWaitsARoundTripPerTile) {
    // FrameBegin reaches the client at L, its request the master at 2L, the first tile the
    // client at 3L; each tile then takes c to render and L + L for its result and the next
    // assignment. The last of n results arrives at (2n + 2) L + n c.
    const int n = 8;
    const double L = 1.0 / 1024, c = 1.0 / 64;
    const SimReport r = simulateCluster(uniformProfile(n, c, 1000), trivial());
    ASSERT_EQ(r.frameSeconds.size(), 3u);
    for (double s : r.frameSeconds) EXPECT_EQ(s, (2 * n + 2) * L + n * c);
    EXPECT_EQ(r.fps, 1.0 / ((2 * n + 2) * L + n * c));
    EXPECT_EQ(r.bytesPerFrame, n * 1000.0);
    EXPECT_EQ(r.stolenPerFrame, 0.0);
    EXPECT_EQ(r.affinityHitFraction, 1.0);  // one client renders everything every frame
    ASSERT_EQ(r.clientUtilisation.size(), 1u);
    EXPECT_DOUBLE_EQ(r.clientUtilisation[0], n * c / ((2 * n + 2) * L + n * c));
}

TEST(ClusterSimulation, PrefetchHidesTheRoundTrip) {
    // With every tile in flight at once: 3L to the first assignment, n c of rendering, L back.
    const int n = 8;
    const double L = 1.0 / 1024, c = 1.0 / 64;
    SimConfig cfg = trivial();
    cfg.prefetch = n;
    const SimReport r = simulateCluster(uniformProfile(n, c, 1000), cfg);
    for (double s : r.frameSeconds) EXPECT_EQ(s, 4 * L + n * c);
}

TEST(ClusterSimulation, LinksMasterCostAndDecodeAddUpAsComputedByHand) {
    // Prefetch n, a 8 Mbit/s client link (1000 bytes take 1/1000 s... use 2^13 bytes at 2^16
    // bits/s = 1 s per tile is too slow; take 2^10 bytes at 2^20 bit/s = 1/128 s), a master link
    // twice as fast (never the bottleneck: its share ends when the client link's does), a
    // master cost m per message and a decode time d.
    const int n = 4;
    const double L = 1.0 / 1024, c = 1.0 / 64, tx = 1.0 / 128, m = 1.0 / 4096, d = 1.0 / 256;
    SimConfig cfg = trivial();
    cfg.prefetch = n;
    cfg.clientLink.bitsPerSecond = 1024.0 * 1024;
    cfg.masterBitsPerSecond = 2.0 * 1024 * 1024;
    cfg.masterSecondsPerMessage = m;
    const SimReport r = simulateCluster(uniformProfile(n, c, 1024, d), cfg);
    // The request is handled at 2L + m (it has 0 bytes), tiles reach the client at 3L + m.
    // Renders end at 3L + m + k c (k = 1..n); each result leaves within c (tx < c), arriving
    // L + tx later, handled m later, decoded d later. The last: 3L + m + n c + tx + L + m + d.
    for (double s : r.frameSeconds) EXPECT_EQ(s, 4 * L + 2 * m + n * c + tx + d);
    EXPECT_EQ(r.bytesPerFrame, n * 1024.0);
}

TEST(ClusterSimulation, TheLinkBoundsFramesPerSecond) {
    // Rendering is free and the master link carries 2^20 bit/s: a frame of 64 tiles of 2^12 bytes
    // (2^21 bits) cannot take less than 2 s, whatever the client count.
    SimConfig cfg = trivial();
    cfg.clients = 8;
    cfg.prefetch = 4;
    cfg.masterBitsPerSecond = 1024.0 * 1024;
    const SimReport r = simulateCluster(uniformProfile(64, 0.0, 4096), cfg);
    EXPECT_LE(r.fps, 0.5);
    EXPECT_GT(r.fps, 0.49);
    EXPECT_GT(r.masterLinkLoad, 0.99);
}

TEST(ClusterSimulation, MoreClientsRenderFasterUntilTheMasterIsTheLimit) {
    SimConfig cfg = trivial();
    cfg.prefetch = 4;
    cfg.masterSecondsPerMessage = 1.0 / 65536;
    const TileProfile p = uniformProfile(256, 1.0 / 256, 100);
    double last = 0;
    for (int clients : {1, 2, 4}) {
        cfg.clients = clients;
        const double fps = simulateCluster(p, cfg).fps;
        EXPECT_GT(fps, last * 1.8) << clients << " clients";
        last = fps;
    }
}

TEST(ClusterSimulation, SharedCoresAreWorkConserving) {
    // Local clients on the master's PC: with no latency and no master cost, the cores are busy
    // from the first assignment to the last result, so a frame of 8 tiles of cost c takes 8c on
    // one core whatever the client count, 4c on two cores for two or four clients (equal shares,
    // all finishing together), and 8 tiles on 2 clients without sharing also 4c. Prefetch 2:
    // every client starts with two tiles and gets one more per result.
    const double c = 1.0 / 64;
    const TileProfile p = uniformProfile(8, c, 1000);
    SimConfig cfg = trivial();
    cfg.clientLink.latencySeconds = 0;
    cfg.prefetch = 2;  // 4 clients x 2: every client starts with work
    cfg.housekeepingSeconds = 0;
    for (int clients : {1, 2, 4}) {
        cfg.clients = clients;
        cfg.hostCores = 1;
        for (double s : simulateCluster(p, cfg).frameSeconds) EXPECT_EQ(s, 8 * c) << clients << " clients on 1 core";
        cfg.hostCores = 2;
        const double two = clients == 1 ? 8 * c : 4 * c;  // one thread uses one core at most
        for (double s : simulateCluster(p, cfg).frameSeconds) EXPECT_EQ(s, two) << clients << " clients on 2 cores";
    }
    cfg.clients = 2;
    cfg.hostCores = 0;
    for (double s : simulateCluster(p, cfg).frameSeconds) EXPECT_EQ(s, 4 * c);
}

TEST(ClusterSimulation, SharedCoresSlowTheMasterWhenClientsSaturateThem) {
    // One core, one client rendering with a tile in reserve (prefetch 2): the master's network
    // thread handles each result while the next tile renders, and then gets only half the core.
    SimConfig cfg = trivial();
    cfg.prefetch = 2;
    cfg.masterSecondsPerMessage = 1.0 / 1024;
    const TileProfile p = uniformProfile(8, 1.0 / 64, 1000);
    const double alone = simulateCluster(p, cfg).fps;
    cfg.hostCores = 1;
    const double shared = simulateCluster(p, cfg).fps;
    EXPECT_LT(shared, alone);
    cfg.hostCores = 64;  // plenty of cores: the same as no sharing
    EXPECT_DOUBLE_EQ(simulateCluster(p, cfg).fps, alone);
}

TEST(ClusterSimulation, HostCostsBesidesRenderingAddUpAsComputedByHand) {
    // As OneClientPrefetchOneWaitsARoundTripPerTile, plus each result's network work on the
    // client (s per result + 2^-20 s per byte of its 1024 bytes, so s + 1/1024), on the master's
    // I/O thread (r), and the master's work per frame (f): every tile's round trip grows by
    // s + 1/1024 + r, the frame by f once. On one shared core nothing runs at the same time
    // (prefetch 1), so the figures are the same.
    const int n = 8;
    const double L = 1.0 / 1024, c = 1.0 / 64, s = 1.0 / 512, sb = 1.0 / (1024 * 1024), r = 1.0 / 256, f = 1.0 / 32;
    SimConfig cfg = trivial();
    cfg.clientSecondsPerResult = s;
    cfg.clientSecondsPerByte = sb;
    cfg.masterSecondsPerResult = r;
    cfg.masterSecondsPerFrame = f;
    const double expected = (2 * n + 2) * L + n * (c + s + 1024 * sb + r) + f;
    for (int cores : {0, 1}) {
        cfg.hostCores = cores;
        const SimReport rep = simulateCluster(uniformProfile(n, c, 1024), cfg);
        ASSERT_EQ(rep.frameSeconds.size(), 3u);
        for (double t : rep.frameSeconds) EXPECT_EQ(t, expected) << cores << " shared cores";
    }
    // The master's per-byte cost: 2^-18 s per byte, 1024 bytes, 1/256 s per result like r.
    cfg = trivial();
    cfg.masterSecondsPerByte = 1.0 / (256 * 1024);
    for (double t : simulateCluster(uniformProfile(n, c, 1024), cfg).frameSeconds) EXPECT_EQ(t, (2 * n + 2) * L + n * (c + r));
}

TEST(ClusterSimulation, HostCostsShareTheCoresWithRendering) {
    // No latency, one core, every tile assigned at once: the core is never idle from the first
    // render to the frame's end, so a frame is exactly the sum of its CPU work, n (c + s + r) + f,
    // although sends and the master's receives run beside the renders.
    const int n = 8;
    const double c = 1.0 / 64, s = 1.0 / 128, r = 1.0 / 256, f = 1.0 / 32;
    SimConfig cfg = trivial();
    cfg.clientLink.latencySeconds = 0;
    cfg.prefetch = n;
    cfg.hostCores = 1;
    cfg.clientSecondsPerResult = s;
    cfg.masterSecondsPerResult = r;
    cfg.masterSecondsPerFrame = f;
    for (double t : simulateCluster(uniformProfile(n, c, 1000), cfg).frameSeconds) EXPECT_DOUBLE_EQ(t, n * (c + s + r) + f);
    cfg.hostCores = 0;  // own cores: the sends and receives overlap the renders; only the last tile's show
    for (double t : simulateCluster(uniformProfile(n, c, 1000), cfg).frameSeconds) EXPECT_EQ(t, n * c + s + r + f);
}

TEST(ClusterSimulation, IsDeterministic) {
    SimConfig cfg = trivial();
    cfg.clients = 5;
    cfg.prefetch = 3;
    cfg.clientLink.spikeProbability = 0.1;
    cfg.clientLink.spikeSeconds = 0.01;
    TileProfile p = uniformProfile(40, 0.001, 500);
    for (size_t i = 0; i < 40; ++i) p.renderSeconds[0][i] = 0.0005 * double(1 + i % 7);
    const SimReport a = simulateCluster(p, cfg), b = simulateCluster(p, cfg);
    EXPECT_EQ(a.frameSeconds, b.frameSeconds);
    EXPECT_EQ(a.stolenPerFrame, b.stolenPerFrame);
}

// The trivial configuration changed by `change` (`what` says how) is refused, for four tiles.
void expectRejected(const char* what, const std::function<void(SimConfig&)>& change) {
    SimConfig cfg = trivial();
    change(cfg);
    EXPECT_THROW(simulateCluster(uniformProfile(4, 0.01, 10), cfg), InputError) << what;
}

TEST(ClusterSimulation, RejectsBadConfigurations) {
    expectRejected("no clients", [](SimConfig& c) { c.clients = 0; });
    expectRejected("a codec the profile lacks", [](SimConfig& c) { c.codec = 1; });
    expectRejected("a negative master cost", [](SimConfig& c) { c.masterSecondsPerResult = -1e-6; });
}

// ---- Display nodes (issue 19) ----------------------------------------------------------------

TEST(ClusterSimulationNodes, OneNodeWithoutLatencyEqualsTheMasterModel) {
    // Unlimited node and master links, no latency, no header bytes: a tile reaches the one node
    // when it would have reached the master, is decoded by as many threads at the same cost, and
    // the ack completes it in the scheduler at the same moment.
    const TileProfile p = uniformProfile(16, 1.0 / 64, 1024, 1.0 / 256);
    SimConfig master = trivial();
    master.clients = 2;
    master.prefetch = 4;
    master.clientLink.latencySeconds = 0;
    master.clientLink.bitsPerSecond = 1024.0 * 1024;
    SimConfig node = master;
    node.displayNodes = 1;
    node.nodeDecodeThreads = master.decodeThreads;
    const SimReport a = simulateCluster(p, master), b = simulateCluster(p, node);
    EXPECT_EQ(a.frameSeconds, b.frameSeconds);
    EXPECT_EQ(a.bytesPerFrame, b.bytesPerFrame);
    ASSERT_EQ(b.nodeBytesPerFrame.size(), 1u);
    EXPECT_EQ(b.nodeBytesPerFrame[0], b.bytesPerFrame);
    EXPECT_TRUE(a.nodeBytesPerFrame.empty());
    // With latency L, the barrier adds its round trip (NodeHave up, NodeSwap down): 2L a frame.
    const double L = 1.0 / 1024;
    master.clientLink.latencySeconds = node.clientLink.latencySeconds = L;
    const SimReport c = simulateCluster(p, master), d = simulateCluster(p, node);
    ASSERT_EQ(c.frameSeconds.size(), d.frameSeconds.size());
    for (size_t i = 0; i < c.frameSeconds.size(); ++i) EXPECT_DOUBLE_EQ(d.frameSeconds[i], c.frameSeconds[i] + 2 * L);
}

TEST(ClusterSimulationNodes, OneLinkBoundNodeRunsAsTheLinkBoundMaster) {
    // 64 tiles of 2^12 bytes over a 2^20 bit/s link: 2 s a frame, through the master's uplink or
    // the one node's (its ack travels ahead of the pixels, which does not change the link's time).
    const TileProfile p = uniformProfile(64, 0.0, 4096);
    SimConfig master = trivial();
    master.clients = 4;
    master.prefetch = 4;
    master.masterBitsPerSecond = 1024.0 * 1024;
    SimConfig node = master;
    node.masterBitsPerSecond = 0;
    node.displayNodes = 1;
    node.nodeBitsPerSecond = 1024.0 * 1024;
    const SimReport a = simulateCluster(p, master), b = simulateCluster(p, node);
    EXPECT_NEAR(b.fps, a.fps, 0.01 * a.fps);
    EXPECT_LE(b.fps, 0.5);
    EXPECT_GT(b.maxNodeLinkLoad, 0.98);
}

TEST(ClusterSimulationNodes, FramesPerSecondGrowWithNodesUpToTheirLinks) {
    // A frame of 16 x 4 tiles split into columns: each node's link carries its share, so
    // frames/s double with the nodes, never above what their links carry together.
    TileProfile p = uniformProfile(64, 0.0, 4096);
    p.width = 1024;
    p.height = 256;
    SimConfig cfg = trivial();
    cfg.clients = 8;
    cfg.prefetch = 4;
    cfg.clientLink.bitsPerSecond = 16.0 * 1024 * 1024;
    cfg.nodeBitsPerSecond = 1024.0 * 1024;
    double last = 0;
    for (int nodes : {1, 2, 4}) {
        cfg.displayNodes = nodes;
        const SimReport r = simulateCluster(p, cfg);
        const double linkBound = nodes * cfg.nodeBitsPerSecond / (8.0 * 64 * 4096);
        EXPECT_LE(r.fps, linkBound * 1.0001) << nodes << " nodes";
        EXPECT_GT(r.fps, 0.95 * linkBound) << nodes << " nodes";
        EXPECT_GT(r.fps, 1.9 * last) << nodes << " nodes";
        ASSERT_EQ(r.nodeBytesPerFrame.size(), size_t(nodes));
        for (double b : r.nodeBytesPerFrame) EXPECT_EQ(b, 64.0 * 4096 / nodes);
        last = r.fps;
    }
}

TEST(ClusterSimulationNodes, ATileOnTwoNodesCountsTwiceAndLoadsBothLinks) {
    // Four tiles, two of them under the bezel between the two nodes (mask 3).
    SimConfig cfg = trivial();
    cfg.prefetch = 4;
    cfg.displayNodes = 2;
    cfg.nodeBitsPerSecond = 1024.0 * 1024;
    cfg.tileNodes = {1, 3, 2, 3};
    const TileProfile p = uniformProfile(4, 0.0, 1024);
    const SimReport r = simulateCluster(p, cfg);
    EXPECT_EQ(r.bytesPerFrame, 6 * 1024.0);
    EXPECT_EQ(r.nodeBytesPerFrame, (std::vector<double>{3 * 1024.0, 3 * 1024.0}));
    cfg.tileNodes = {1, 1, 2, 2};
    const SimReport plain = simulateCluster(p, cfg);
    EXPECT_EQ(plain.bytesPerFrame, 4 * 1024.0);
    EXPECT_LT(r.fps, plain.fps);  // each node's link carries 3 tiles instead of 2
    // The client's link carries each copy: one client link at the nodes' rate is the limit.
    cfg.tileNodes = {1, 3, 2, 3};
    cfg.nodeBitsPerSecond = 0;
    cfg.clientLink.bitsPerSecond = 1024.0 * 1024;
    EXPECT_GT(simulateCluster(p, cfg).maxClientLinkLoad, 0.0);
    EXPECT_LE(simulateCluster(p, cfg).fps, 1024.0 * 1024 / (8 * 6 * 1024.0));
}

TEST(ClusterSimulationNodes, TheSwapWaitsForTheSlowestNode) {
    // Two tiles, one per node, free to render and send; node 1's decodes 4 times as long. The
    // frame is swapped when node 1 holds it; the barrier wait is the difference.
    TileProfile p = uniformProfile(2, 0.0, 1024);
    p.codecs[0].decodeSeconds = {1.0 / 256, 1.0 / 64};
    SimConfig cfg = trivial();
    cfg.prefetch = 2;
    cfg.clientLink.latencySeconds = 0;
    cfg.displayNodes = 2;
    cfg.tileNodes = {1, 2};
    const SimReport r = simulateCluster(p, cfg);
    for (double s : r.frameSeconds) EXPECT_EQ(s, 1.0 / 64);
    EXPECT_EQ(r.meanBarrierWait, 1.0 / 64 - 1.0 / 256);
}

TEST(ClusterSimulationNodes, ColumnMasksSplitTheWidthAndFanOutAtCutTiles) {
    // 3840 pixels in 64-pixel tiles: 960-pixel runs hold whole tiles, no tile goes to two nodes.
    const std::vector<uint64_t> four = columnNodeMasks(3840, 128, 64, 4);
    ASSERT_EQ(four.size(), 120u);
    for (size_t t = 0; t < four.size(); ++t) EXPECT_EQ(four[t], 1ull << ((t % 60) / 15)) << t;
    // 100 pixels in 32-pixel tiles on two nodes: the boundary at 50 cuts the tile [32, 64).
    EXPECT_EQ(columnNodeMasks(100, 32, 32, 2), (std::vector<uint64_t>{1, 3, 2, 2}));
    EXPECT_EQ(columnNodeMasks(100, 32, 32, 1), (std::vector<uint64_t>{1, 1, 1, 1}));
    EXPECT_THROW(columnNodeMasks(100, 32, 32, 0), InputError);
    EXPECT_THROW(columnNodeMasks(100, 32, 32, 65), InputError);
}

TEST(ClusterSimulationNodes, RejectsBadNodeConfigurations) {
    expectRejected("65 nodes", [](SimConfig& c) { c.displayNodes = 65; });
    expectRejected("3 masks for 4 tiles", [](SimConfig& c) {
        c.displayNodes = 2;
        c.tileNodes = {1, 2, 3};
    });
    expectRejected("node 2 of 2", [](SimConfig& c) {
        c.displayNodes = 2;
        c.tileNodes = {1, 2, 4, 1};
    });
    expectRejected("no node decode thread", [](SimConfig& c) {
        c.displayNodes = 2;
        c.nodeDecodeThreads = 0;
    });
}

TEST(TileProfile, WritesAndReadsBack) {
    TileProfile p = uniformProfile(3, 0.25, 77, 0.5);
    p.scene = "test";
    p.renderSeconds.push_back({0.125, 0.25, 0.5});
    const std::filesystem::path file = std::filesystem::path(RTWALL_BINARY_DIR) / "tile_profile_test.toml";
    writeTileProfile(p, file);
    const TileProfile q = readTileProfile(file);
    EXPECT_EQ(q.scene, "test");
    EXPECT_EQ(q.width, p.width);
    EXPECT_EQ(q.renderSeconds, p.renderSeconds);
    ASSERT_EQ(q.codecs.size(), 1u);
    EXPECT_EQ(q.codecs[0].bytes, p.codecs[0].bytes);
    EXPECT_EQ(q.codecs[0].decodeSeconds, p.codecs[0].decodeSeconds);
    EXPECT_EQ(q.codecs[0].codec.codec, TileCodec::Raw);
    std::filesystem::remove(file);
    EXPECT_THROW(readTileProfile(file), InputError);
}

TEST(TileProfile, RecordsEveryTileOfARealRender) {
    SceneDesc desc = builtinScene("knots", 5000);
    desc.settings.width = 96;
    desc.settings.height = 64;
    desc.settings.tileSize = 32;
    desc.settings.threads = 1;
    const Scene scene(desc);
    CodecSettings jpeg;
    jpeg.codec = TileCodec::Jpeg;
    Image lossless;
    std::vector<Image> decoded;
    const TileProfile p = profileTiles(scene, {desc.cameras.front(), desc.cameras.front()}, desc.settings,
                                       {CodecSettings{TileCodec::Raw}, jpeg}, &lossless, &decoded);
    ASSERT_EQ(p.renderSeconds.size(), 2u);
    EXPECT_EQ(p.tileCount(), 6u);
    EXPECT_EQ(p.codecs[0].bytes[0], 32u * 32 * 3);  // raw: the pixels
    EXPECT_EQ(decoded.at(0).rgb, lossless.rgb);      // raw round trip is exact
    const Image single = renderFrame(scene, Camera(desc.cameras.front(), 96, 64), desc.settings);
    EXPECT_EQ(lossless.rgb, single.rgb);  // tile by tile is the same image
    uint64_t bytes = 0;
    const Image viaJpeg = codecRoundTrip(lossless, 32, jpeg, &bytes);
    EXPECT_EQ(viaJpeg.rgb, decoded.at(1).rgb);
    uint64_t sum = 0;
    for (uint32_t b : p.codecs[1].bytes) sum += b;
    EXPECT_EQ(bytes, sum);
}

}  // namespace
}  // namespace rtwall
