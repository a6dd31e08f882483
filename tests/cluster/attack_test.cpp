// Issue 16's adversarial tests. A master under attack (raw bytes, ZMTP garbage, multi-frame and
// truncated messages of every type, oversized frames, replays, a client that joins and lies),
// with and without CURVE, while real clients render: their frames stay bit-identical to one
// machine's and the master counts what it dropped, kind by kind. And the other side: a hostile
// master cannot crash, hang or mislead a client. Bounded: a few seconds each (`rtwall bench
// attack` runs the same attack for longer).
#include "adversary.h"
#include "codec.h"
#include "fake_master.h"
#include "local_cluster.h"
#include "protocol.h"
#include "test_util.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <random>
#include <thread>

namespace rtwall {
namespace {

using Clock = std::chrono::steady_clock;

// Random bytes of length n.
std::vector<uint8_t> junk(std::mt19937_64& rng, size_t n) {
    std::vector<uint8_t> b(n);
    for (auto& x : b) x = uint8_t(rng());
    return b;
}

// Garbage of every kind from a hostile master to `peer`: bytes, multi-frame messages, a valid
// FrameBegin inside a multi-frame one, every type with a payload that does not decode, truncated
// messages, types only clients send and a FrameBegin of another session. Returns how many
// messages the client must drop.
uint64_t sendGarbage(test::FakeMaster& fake, const std::string& peer, std::mt19937_64& rng) {
    using namespace cluster;
    Header h;
    h.session = test::FakeMaster::kSession;
    uint64_t sent = 0;
    for (int i = 0; i < 10; ++i, ++sent) fake.resend(peer, junk(rng, 1 + rng() % 100));
    for (int i = 0; i < 10; ++i, ++sent) fake.sendParts(peer, {{'x'}, {'y'}});
    // A FrameBegin that would throw the work away, inside a two-frame message: not obeyed.
    fake.sendParts(peer, {encodeMessage(h, FrameBegin{99, 0, TilePixels::Srgb8, {FrameView{}}}), {'z'}});
    ++sent;
    for (uint16_t t = 1; t <= kMaxMsgType; ++t) {
        Header bad = h;
        bad.type = MsgType(t);
        std::vector<uint8_t> m = encodeMessage(bad, Goodbye{"x"});  // a payload of the wrong shape
        m[6] = uint8_t(t);
        std::vector<uint8_t> payload = junk(rng, 8 + rng() % 64);
        m.resize(kHeaderSize);
        m.insert(m.end(), payload.begin(), payload.end());
        for (int b = 0; b < 4; ++b) m[24 + b] = uint8_t(payload.size() >> (8 * b));
        if (MsgType(t) != MsgType::Heartbeat && MsgType(t) != MsgType::Goodbye) {
            fake.resend(peer, m);
            ++sent;
        }
        std::vector<uint8_t> truncated = encodeMessage(h, FrameBegin{7, 0, TilePixels::Srgb8, {FrameView{}}});
        truncated.pop_back();
        fake.resend(peer, truncated);
        ++sent;
    }
    // Types only clients send, and a FrameBegin of another session.
    fake.send(peer, TileRequest{1, 4});
    fake.send(peer, Ready{0, {1, 2}});
    Header other = h;
    other.session = 0xBAD;
    fake.resend(peer, encodeMessage(other, FrameBegin{42, 0, TilePixels::Srgb8, {FrameView{}}}));
    return sent + 3;
}

// Tile 0 of frame `frame` asked of the client at `peer` (the frame begun first): its result
// (within 20 s) has one machine's pixels. Fatal failures: call it in ASSERT_NO_FATAL_FAILURE.
void expectTileRenderedRight(test::FakeMaster& fake, const std::string& peer, const SceneDesc& desc, uint32_t frame) {
    using namespace cluster;
    fake.send(peer, FrameBegin{frame, 0, TilePixels::Srgb8, test::oneView(desc)}, frame);
    const auto request = fake.expect(MsgType::TileRequest, 10000);
    ASSERT_TRUE(request);
    EXPECT_EQ(decodePayload<TileRequest>(request->payload.data(), request->payload.size()).frame, frame);
    fake.send(peer, TileAssign{frame, {0}}, frame);
    std::optional<TileResult> result;
    for (auto end = Clock::now() + std::chrono::seconds(20); !result && Clock::now() < end;) {
        const auto r = fake.expect(MsgType::TileResult, 1000);
        if (!r) continue;
        TileResult tr = decodePayload<TileResult>(r->payload.data(), r->payload.size());
        if (tr.frame == frame) result = std::move(tr);
    }
    ASSERT_TRUE(result) << "no result for the real tile";
    const TileRect rect = makeTiles(desc.settings.width, desc.settings.height, desc.settings.tileSize)[0];
    std::vector<uint8_t> got(size_t(rect.width()) * rect.height() * 3), want(got.size());
    decodeTile(result->codec, result->pixels.data(), result->pixels.size(), rect.width(), rect.height(), got.data(),
               size_t(rect.width()) * 3);
    const Scene scene(desc);
    renderTile(scene, Camera(desc.cameras.front(), desc.settings.width, desc.settings.height), rect, frame, desc.settings,
               {want.data(), size_t(rect.width()) * 3});
    EXPECT_EQ(got, want);
}

class MasterUnderAttack : public ::testing::TestWithParam<bool> {};

TEST_P(MasterUnderAttack, FramesStayBitIdenticalAndEveryMessageIsCounted) {
    const bool curve = GetParam();
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "master");
    writeNewKeyPair(dir / "client");
    const SceneDesc desc = test::quickDemo(96, 72, 8);
    const Image expected = test::singleMachine(desc, 0);
    ClusterSettings cs = test::inStep();
    if (curve) {
        cs.keyFile = dir / "master.key";
        cs.clientKeys = {dir / "client.pub"};
    }
    test::StoppableCluster cluster(desc, cs);
    Master& master = *cluster.master;
    for (int i = 0; i < 2; ++i) {
        ClientSettings c;
        if (curve) {
            c.keyFile = dir / "client.key";
            c.serverKeyFile = dir / "master.pub";
        }
        cluster.start(c);
    }
    ASSERT_TRUE(master.waitForClients(2, 30000));
    ASSERT_EQ(master.renderFrame().rgb, expected.rgb);

    const MasterCounters before = master.counters();
    testing::AttackOptions ao;
    ao.endpoint = master.endpoint();
    ao.seconds = 3;
    ao.messagesPerSecond = 1500;
    ao.seed = 16;
    ao.unversionedJunk = false;  // its ZMTP 1.0 messages could not be counted here (see AttackOptions)
    if (curve) ao.serverKeyFile = dir / "master.pub";
    std::atomic<bool> attacking{true};
    auto attack = std::async(std::launch::async, [&] {
        const testing::AttackReport r = testing::attackMaster(ao);
        attacking = false;
        return r;
    });
    int frames = 0, identical = 0;
    double worst = 0;
    while (attacking) {
        const auto t0 = Clock::now();
        const auto img = cluster.frameWithin(30);
        if (!img) {
            ADD_FAILURE() << "a frame under attack did not complete in 30 s";
            break;
        }
        worst = std::max(worst, std::chrono::duration<double>(Clock::now() - t0).count());
        ++frames;
        identical += img->rgb == expected.rgb;
    }
    const testing::AttackReport sent = attack.get();
    // The master reads what is still queued: wait (bounded) until every kind has caught up.
    auto caughtUp = [&] {
        const MasterCounters d = master.counters() - before;
        return d.malformed >= sent.malformed && d.unknownPeer >= sent.unknownPeer && d.refused >= sent.refused &&
               d.stale >= sent.stale && d.replayed + d.unexpected >= sent.replayedOrUnexpected &&
               d.stalledTiles >= sent.stallReports;
    };
    for (int i = 0; i < 500 && !caughtUp(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const MasterCounters d = master.counters() - before;
    std::printf("attack (CURVE %s): %llu app-level messages (%llu malformed, %llu from no client, %llu refused, %llu in a "
                "session), %llu raw connections, %llu oversized, %llu CURVE strangers; master: %s; %d frames, %d "
                "bit-identical, worst %.0f ms\n",
                curve ? "on" : "off", (unsigned long long)sent.appMessages(), (unsigned long long)sent.malformed,
                (unsigned long long)sent.unknownPeer, (unsigned long long)sent.refused, (unsigned long long)sent.inSession(),
                (unsigned long long)sent.rawConnections, (unsigned long long)sent.oversized,
                (unsigned long long)sent.curveAttempts, describeCounters(d).c_str(), frames, identical, worst * 1e3);
    EXPECT_GT(frames, 0);
    EXPECT_EQ(identical, frames) << "frames rendered under attack are one machine's";
    EXPECT_GT(sent.rawConnections, 0u);
    EXPECT_GT(sent.oversized + sent.curveAttempts, 0u);
    EXPECT_GE(d.failedHandshakes, 1u) << "ZMTP garbage breaks handshakes, and is counted";
    // The attacker's own session may end (an oversized message on its connection makes ZeroMQ
    // close it: "its connection is gone"); the real clients' may not.
    EXPECT_LE(d.clientsDropped, sent.joined) << "no real client was dropped";
    if (!curve) {
        ASSERT_GT(sent.appMessages(), 1000u);
        EXPECT_EQ(sent.joined, 1u) << "without keys, anyone local can join: the lies come from inside the session";
        EXPECT_EQ(d.malformed, sent.malformed);
        EXPECT_EQ(d.unknownPeer, sent.unknownPeer);
        EXPECT_EQ(d.refused, sent.refused);
        EXPECT_EQ(d.replayed + d.unexpected, sent.replayedOrUnexpected);
        EXPECT_GE(d.stale, sent.stale) << "real clients may add late results of their own";
        EXPECT_EQ(d.stalledTiles, sent.stallReports);
        EXPECT_EQ(master.connectedClients(), 3 - int(d.clientsDropped)) << "both real clients, and the attacker unless it was dropped";
    } else {
        EXPECT_EQ(sent.joined, 0u);
        // With CURVE nothing of the attacker reaches the application (the real clients may
        // still send a late result now and then: stale).
        EXPECT_EQ(d.malformed + d.unknownPeer + d.replayed + d.unexpected + d.undecodableTiles, 0u) << describeCounters(d);
        EXPECT_GE(d.refused, 1u) << "ZAP refused the attacker's keys";
        EXPECT_EQ(master.connectedClients(), 2);
    }
}

INSTANTIATE_TEST_SUITE_P(Issue16, MasterUnderAttack, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& p) { return std::string(p.param ? "Curve" : "NoKeys"); });

// The client side: a master that sends garbage of every kind before and inside a session
// (bytes, multi-frame messages, a valid FrameBegin inside a multi-frame one, truncated messages,
// every type with a payload that does not decode or from another session, types only clients
// send, assignments without end for tiles that do not exist) neither crashes nor hangs the
// client, nor makes it do anything: afterwards it renders the tile it is given, correctly, and
// when the master goes silent it gives up in time.
TEST(HostileMaster, GarbageNeitherCrashesNorHangsAClient) {
    using namespace cluster;
    SceneDesc desc = builtinScene("knots", 2000);
    desc.settings.width = 64;
    desc.settings.height = 48;
    desc.settings.tileSize = 16;
    test::FakeMaster fake;
    auto counters = std::make_shared<ClientCounters>();
    ClientSettings cs;
    cs.counters = counters;
    auto client = test::startClient(fake, 3000, cs);
    const auto hello = fake.expect(MsgType::Hello, 10000);
    ASSERT_TRUE(hello);
    const std::string peer = hello->peer;

    std::mt19937_64 rng(15);
    sendGarbage(fake, peer, rng);  // before the handshake: nothing of it counts as a master

    // A proper handshake: welcome, state, the meshes it asks for.
    fake.send(peer, Welcome{7, CodecSettings{}, 4, 100, 5000});
    SceneSnapshot snap;
    std::map<Hash128, std::vector<uint8_t>> meshBytes;
    for (const MeshDesc& md : desc.meshes) {
        std::vector<uint8_t> bytes = encodeMesh(*md.mesh);
        const Hash128 hash = hashBytes(bytes.data(), bytes.size());
        snap.meshes.push_back({md.name, md.source, hash, bytes.size()});
        meshBytes[hash] = std::move(bytes);
    }
    snap.materials = desc.materials;
    snap.instances = desc.instances;
    snap.lights = desc.lights;
    snap.settings = desc.settings;
    snap.bvh = desc.bvh;
    snap.origin = desc.origin;
    fake.onOther = [&](const test::FakeMaster::Received& r) {
        if (r.header.type != MsgType::MeshRequest) return;
        const MeshRequest req = decodePayload<MeshRequest>(r.payload.data(), r.payload.size());
        if (auto it = meshBytes.find(req.hash); it != meshBytes.end()) fake.send(peer, MeshData{req.hash, it->second});
    };
    fake.send(peer, snap);
    const auto ready = fake.expect(MsgType::Ready, 30000);
    ASSERT_TRUE(ready) << "the client never proved the state";
    EXPECT_EQ(decodePayload<Ready>(ready->payload.data(), ready->payload.size()).stateHash, stateHash(snap));

    // In the session: garbage again, and assignments without end for tiles that do not exist.
    const uint64_t dropped0 = counters->droppedMessages.load();
    const uint64_t inSession = sendGarbage(fake, peer, rng);
    fake.send(peer, FrameBegin{5, 0, TilePixels::Srgb8, test::oneView(desc)}, 5);
    ASSERT_TRUE(fake.expect(MsgType::TileRequest, 10000));
    std::vector<uint32_t> bogus(kMaxTilesPerMessage);
    for (uint32_t i = 0; i < bogus.size(); ++i) bogus[i] = 1000 + i;
    for (int i = 0; i < 20; ++i) fake.send(peer, TileAssign{5, bogus}, 5);
    fake.send(peer, Heartbeat{});
    for (int i = 0; i < 200 && counters->droppedMessages.load() < dropped0 + inSession; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_GE(counters->droppedMessages.load(), dropped0 + inSession) << "every piece of garbage dropped and counted";
    EXPECT_GT(counters->droppedAssignments.load(), 0u) << "its queue has a bound";

    // It still works: the next frame, one real tile, rendered right.
    ASSERT_NO_FATAL_FAILURE(expectTileRenderedRight(fake, peer, desc, 6));

    // The master falls silent: the client gives up after its idle limit, it does not hang.
    EXPECT_EQ(client.wait_for(std::chrono::seconds(20)), std::future_status::ready);
    EXPECT_EQ(client.get(), 1);
}

}  // namespace
}  // namespace rtwall
