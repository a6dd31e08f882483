// CURVE on every link: only the clients whose public keys the master lists get in, and the
// master keeps serving frames whatever knocks at its port. Bounded: refused clients give up
// after their idle limit.
#include "local_cluster.h"
#include "test_util.h"

#include "codec.h"
#include "protocol.h"
#include "scene_state.h"
#include "security.h"

#include <rtwall/cluster.h>

#include <zmq.hpp>

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <future>
#include <memory>
#include <random>
#include <thread>

namespace rtwall {
namespace {

SceneDesc smallScene() { return test::quickDemo(64, 48); }

using test::singleMachine;

// Runs a client on a thread; it returns 1 when it gives up on the master.
std::future<int> startClient(const std::string& endpoint, const std::filesystem::path& key,
                             const std::filesystem::path& serverKey, int giveUpMs) {
    ClientSettings cs;
    cs.connect = endpoint;
    cs.threads = 1;
    cs.keyFile = key;
    cs.serverKeyFile = serverKey;
    cs.exitAfterIdleMs = giveUpMs;
    return std::async(std::launch::async, [cs] { return runClient(cs); });
}

uint16_t portOf(const std::string& endpoint) { return uint16_t(std::stoi(endpoint.substr(endpoint.rfind(':') + 1))); }

TEST(Security, OnlyListedClientsGetIn) {
    const auto dir = test::scratchDir();
    for (const char* name : {"master", "good", "stranger"}) writeNewKeyPair(dir / name);
    // The key pair printed in ZeroMQ's documentation: public knowledge, so never trusted.
    test::writeFile(dir / "published.key", "public = \"Yne@$w-vo<fVvi]a<NY6T1ed:M$fCG*[IaLV{hID\"\n"
                                           "secret = \"D:)Q[IlAW!ahhC2ac:9*A}h:p?([4%wOTJ%JR%cs\"\n");
    const SceneDesc desc = smallScene();
    ClusterSettings cs = test::inStep();
    cs.keyFile = dir / "master.key";
    cs.clientKeys = {dir / "good.pub"};
    auto master = std::make_unique<Master>(desc, cs);
    const std::string ep = master->endpoint();

    auto good = startClient(ep, dir / "good.key", dir / "master.pub", 4000);
    ASSERT_TRUE(master->waitForClients(1, 30000));

    auto stranger = startClient(ep, dir / "stranger.key", dir / "master.pub", 1500);
    auto published = startClient(ep, dir / "published.key", dir / "master.pub", 1500);
    auto wrongServer = startClient(ep, dir / "good.key", dir / "stranger.pub", 1500);  // it must not trust this master
    auto plain = startClient(ep, {}, {}, 1500);  // the NULL mechanism

    // Random bytes at the port, from a raw TCP socket on loopback.
    {
        const int fd = socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in addr{};
        addr.sin_family = AF_INET;
        addr.sin_port = htons(portOf(ep));
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
        std::mt19937 rng(99);
        std::vector<uint8_t> junk(8192);
        for (auto& b : junk) b = uint8_t(rng());
        (void)!write(fd, junk.data(), junk.size());
        close(fd);
    }

    for (int f = 0; f < 3; ++f) EXPECT_EQ(master->renderFrame().rgb, singleMachine(desc).rgb) << "frame " << f;
    EXPECT_EQ(stranger.get(), 1);
    EXPECT_EQ(published.get(), 1);
    EXPECT_EQ(wrongServer.get(), 1);
    EXPECT_EQ(plain.get(), 1);
    EXPECT_EQ(master->connectedClients(), 1) << "only the listed client holds the scene";
    EXPECT_GE(master->refusedConnections(), 2u) << "the stranger and the published key were refused by ZAP";
    EXPECT_EQ(master->renderFrame().rgb, singleMachine(desc).rgb) << "and the master still serves frames";
    master.reset();
    EXPECT_EQ(good.get(), 0);
}

TEST(Security, NoInsecureDefault) {
    ClusterSettings cs;
    cs.bind = "tcp://0.0.0.0:0";
    const std::string msg = test::inputErrorOf([&] { Master m(smallScene(), cs); });
    EXPECT_NE(msg.find("without CURVE keys"), std::string::npos) << msg;
    cs.insecure = true;
    EXPECT_NO_THROW(Master(smallScene(), cs));
}

TEST(Security, KeyFilesAreCheckedAndPrivate) {
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "k");
    EXPECT_EQ(std::filesystem::status(dir / "k.key").permissions() & std::filesystem::perms::all,
              std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
    test::writeFile(dir / "bad.key", "public = \"short\"\nsecret = \"short\"\n");
    ClusterSettings cs;
    cs.keyFile = dir / "bad.key";
    cs.clientKeys = {dir / "k.pub"};
    const std::string msg = test::inputErrorOf([&] { Master m(smallScene(), cs); });
    EXPECT_NE(msg.find("bad.key"), std::string::npos) << msg;
    EXPECT_NE(msg.find("Z85"), std::string::npos) << msg;
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// Truncated, mislabelled, wrong-version, oversized and replayed messages from a peer that
// speaks ZeroMQ but lies: none of them changes a frame, each is dropped (and counted), and the
// master goes on serving.
TEST(Attack, MalformedMessagesReachNothing) {
    using namespace cluster;
    const SceneDesc desc = smallScene();
    const Image expected = singleMachine(desc);
    ClusterSettings cs = test::inStep();
    auto master = std::make_unique<Master>(desc, cs);
    auto honest = startClient(master->endpoint(), {}, {}, 4000);
    ASSERT_TRUE(master->waitForClients(1, 30000));
    EXPECT_EQ(master->renderFrame().rgb, expected.rgb);

    zmq::context_t ctx;
    zmq::socket_t rogue(ctx, zmq::socket_type::dealer);
    rogue.set(zmq::sockopt::linger, 0);
    rogue.set(zmq::sockopt::rcvtimeo, 3000);
    rogue.connect(master->endpoint());
    const uint64_t dropped0 = master->droppedMessages();

    // A truncated Hello: the header's length says more than the frame holds.
    Header h;
    h.type = MsgType::Hello;
    std::vector<uint8_t> hello = encodeMessage(h, Hello{kProtocolVersion, 1, "rogue"});
    rogue.send(zmq::buffer(hello.data(), hello.size() - 3));
    // Bytes that are not a message at all, and a header with a type out of range.
    rogue.send(zmq::str_buffer("hello, master"));
    std::vector<uint8_t> badType = hello;
    badType[6] = 99;
    rogue.send(zmq::buffer(badType));
    // A result before any handshake, with a made-up session.
    Header forged;
    forged.type = MsgType::TileResult;
    forged.session = 0x1234;
    forged.frame = 2;
    TileResult fake;
    fake.frame = 2;
    fake.tile = 0;
    fake.codec = TileCodec::Raw;
    fake.pixels.assign(size_t(desc.settings.tileSize) * desc.settings.tileSize * 3, 255);
    rogue.send(zmq::buffer(encodeMessage(forged, fake)));

    // Another protocol version, newer or older (12: a client from before the camera travelled
    // only in FrameBegin): refused with a one-line goodbye that names both versions.
    for (const uint16_t theirs : {uint16_t(kProtocolVersion + 1), uint16_t(12)}) {
        Header other;
        other.type = MsgType::Hello;
        other.version = theirs;
        rogue.send(zmq::buffer(encodeMessage(other, Hello{theirs, 1, "other"})));
        std::string reason;
        for (int i = 0; i < 20 && reason.empty(); ++i) {
            zmq::message_t msg;
            if (!rogue.recv(msg)) break;
            const auto* p = static_cast<const uint8_t*>(msg.data());
            const Header in = decodeHeader(p, msg.size());
            if (in.type != MsgType::Goodbye) continue;
            reason = decodePayload<Goodbye>(p + kHeaderSize, msg.size() - kHeaderSize).reason;
        }
        EXPECT_EQ(reason, "protocol version " + std::to_string(theirs) + " is not the master's " +
                              std::to_string(kProtocolVersion));
    }

    // A message larger than ZMQ_MAXMSGSIZE: the transport drops the connection, not the master.
    std::vector<uint8_t> huge(16 << 20, 0xAB);
    rogue.send(zmq::buffer(huge), zmq::send_flags::dontwait);

    for (int f = 0; f < 3; ++f) EXPECT_EQ(master->renderFrame().rgb, expected.rgb) << "frame " << f;
    EXPECT_GE(master->droppedMessages(), dropped0 + 4) << "truncated, garbage, bad type and forged: all counted";
    EXPECT_EQ(master->connectedClients(), 1);
    master.reset();
    EXPECT_EQ(honest.get(), 0);
}

}  // namespace
}  // namespace rtwall


namespace rtwall {
namespace {

// An authenticated client (its key is on the master's list) that renders its tiles honestly and
// also replays messages it sent before, byte for byte: every result again at once, and in the
// next frame (after the scene changed) every result, Ready and TileRequest of the last one.
// CURVE's nonces stop a replay by anyone else on the wire (libzmq rejects a repeated or older
// nonce); this is the peer itself, so only the application can tell: each replay must be
// dropped and counted exactly once, and no old tile may reach the new frame.
class ReplayingClient {
public:
    ReplayingClient(const std::string& endpoint, const cluster::KeyPair& keys, const std::string& serverKey,
                    SceneDesc desc)
        : socket_(ctx_, zmq::socket_type::dealer), desc_(std::move(desc)) {
        using namespace cluster;
        socket_.set(zmq::sockopt::linger, 0);
        socket_.set(zmq::sockopt::curve_serverkey, serverKey);
        socket_.set(zmq::sockopt::curve_publickey, keys.publicKey);
        socket_.set(zmq::sockopt::curve_secretkey, keys.secretKey);
        socket_.connect(endpoint);
        camera_ = desc_.cameras.front();
        rebuild();
        Header h;
        h.type = MsgType::Hello;
        sendRaw(encodeMessage(h, Hello{kProtocolVersion, 1, "replayer"}));
    }

    // Handles what arrives for up to `ms` (or until `done` says stop); bounded by the time.
    template <class Done> void pump(int ms, Done&& done) {
        using namespace cluster;
        const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
        while (std::chrono::steady_clock::now() < end && !done()) {
            zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
            zmq::poll(&item, 1, std::chrono::milliseconds(20));
            heartbeat();
            zmq::message_t msg;
            while (socket_.recv(msg, zmq::recv_flags::dontwait)) handle(msg);
        }
    }

    uint64_t replays() const { return replays_; }
    uint64_t results() const { return results_; }

private:
    void handle(const zmq::message_t& msg) {
        using namespace cluster;
        const auto* p = static_cast<const uint8_t*>(msg.data());
        const Header in = decodeHeader(p, msg.size());
        const uint8_t* payload = p + kHeaderSize;
        const size_t n = msg.size() - kHeaderSize;
        switch (in.type) {
        case MsgType::Welcome: session_ = in.session; break;
        case MsgType::SceneSnapshot: {
            const auto snap = decodePayload<SceneSnapshot>(payload, n);
            state_ = snap.updateSeq;
            remember(send(MsgType::Ready, 0, Ready{snap.updateSeq, stateHash(snap)}));
            break;
        }
        case MsgType::Update: {
            const auto u = decodePayload<Update>(payload, n);
            for (const Change& c : u.changes) applyChange(desc_, c);
            state_ = u.seq;
            rebuild();
            break;
        }
        case MsgType::FrameBegin: {
            const auto fb = decodePayload<FrameBegin>(payload, n);
            if (fb.updateSeq != state_) break;  // the test makes one update at a time: never happens
            camera_ = fb.views.front().camera;  // a mono frame's one view (protocol 13: the only camera)
            // Everything sent for the last frame, again: results, Ready and requests.
            for (const auto& bytes : sent_) {
                sendRaw(bytes);
                ++replays_;
            }
            sent_.clear();
            remember(send(MsgType::TileRequest, fb.frame, TileRequest{fb.frame, 4}));
            break;
        }
        case MsgType::TileAssign: {
            const auto a = decodePayload<TileAssign>(payload, n);
            for (uint32_t t : a.tiles) {
                const std::vector<uint8_t> bytes = render(a.frame, t);
                sendRaw(bytes);
                sendRaw(bytes);  // a replay within the frame: a duplicate
                ++replays_;
                ++results_;
                sent_.push_back(bytes);
            }
            break;
        }
        default: break;
        }
    }

    std::vector<uint8_t> render(uint32_t frame, uint32_t tile) {
        using namespace cluster;
        const TileRect r = tiles_.at(tile);
        std::vector<uint8_t> pixels(size_t(r.width()) * r.height() * 3);
        renderTile(*scene_, Camera(camera_, desc_.settings.width, desc_.settings.height), r, frame, desc_.settings,
                   {pixels.data(), size_t(r.width()) * 3});
        TileResult result;
        result.frame = frame;
        result.tile = tile;
        result.codec = TileCodec::Lz4;  // the master's default
        encodeTile(CodecSettings{}, pixels.data(), r.width(), r.height(), size_t(r.width()) * 3, result.pixels);
        return message(MsgType::TileResult, frame, result);
    }

    void rebuild() {
        scene_ = std::make_unique<Scene>(desc_);
        tiles_ = makeTiles(desc_.settings.width, desc_.settings.height, desc_.settings.tileSize);
    }

    void heartbeat() {
        if (session_ && std::chrono::steady_clock::now() - lastSent_ > std::chrono::milliseconds(100))
            send(cluster::MsgType::Heartbeat, 0, cluster::Heartbeat{});
    }

    template <class Msg> std::vector<uint8_t> message(cluster::MsgType type, uint32_t frame, const Msg& m) const {
        cluster::Header h;
        h.type = type;
        h.session = session_;
        h.frame = frame;
        h.sceneVersion = state_;
        return cluster::encodeMessage(h, m);
    }
    template <class Msg> std::vector<uint8_t> send(cluster::MsgType type, uint32_t frame, const Msg& m) {
        std::vector<uint8_t> bytes = message(type, frame, m);
        sendRaw(bytes);
        return bytes;
    }
    void sendRaw(const std::vector<uint8_t>& bytes) {
        socket_.send(zmq::buffer(bytes), zmq::send_flags::dontwait);
        lastSent_ = std::chrono::steady_clock::now();
    }
    void remember(std::vector<uint8_t> bytes) { sent_.push_back(std::move(bytes)); }

    zmq::context_t ctx_;
    zmq::socket_t socket_;
    SceneDesc desc_;
    CameraDesc camera_;
    std::unique_ptr<Scene> scene_;
    std::vector<TileRect> tiles_;
    uint64_t session_ = 0;
    uint32_t state_ = 0;
    std::vector<std::vector<uint8_t>> sent_;  // this frame's messages, replayed in the next
    uint64_t replays_ = 0, results_ = 0;
    std::chrono::steady_clock::time_point lastSent_{};
};

TEST(Attack, ReplayedMessagesOfAnAuthenticatedPeerAreDroppedAndCounted) {
    const auto dir = test::scratchDir();
    writeNewKeyPair(dir / "master");
    writeNewKeyPair(dir / "replayer");
    SceneDesc desc = smallScene();
    desc.settings.tileSize = 16;
    ClusterSettings cs = test::inStep();
    cs.stragglerFactor = 1e9;  // no re-issues: every duplicate below is a replay
    cs.keyFile = dir / "master.key";
    cs.clientKeys = {dir / "replayer.pub"};
    Master master(desc, cs);
    ReplayingClient peer(master.endpoint(), cluster::readKeyPair(dir / "replayer.key"),
                         cluster::readPublicKey(dir / "master.pub"), desc);
    peer.pump(30000, [&] { return master.connectedClients() == 1; });
    ASSERT_EQ(master.connectedClients(), 1);
    const uint64_t dropped0 = master.droppedMessages();

    // Frame 1 with the scene as loaded; each result arrives twice.
    FrameReport r1, r2;
    Image f1;
    std::atomic<bool> done{false};
    std::thread t1([&] {
        f1 = master.renderFrame(&r1);
        done = true;
    });
    peer.pump(60000, [&] { return done.load(); });
    t1.join();
    EXPECT_EQ(f1.rgb, singleMachine(desc).rgb);

    // The scene changes; in frame 2 the peer first replays everything it sent in frame 1. A
    // frame-1 tile that got in would show the old light.
    desc.lights[0].intensity *= 3.0f;
    master.setLight(0, desc.lights[0]);
    Image f2;
    done = false;
    std::thread t2([&] {
        f2 = master.renderFrame(&r2);
        done = true;
    });
    peer.pump(60000, [&] { return done.load(); });
    t2.join();
    EXPECT_EQ(f2.rgb, singleMachine(desc).rgb) << "no replayed tile of frame 1 reached frame 2";
    ASSERT_GT(peer.results(), 0u);
    // Let the last duplicates of frame 2 arrive: the master keeps counting them as dropped.
    const uint64_t expected = peer.replays();
    auto counted = [&] { return master.droppedMessages() - dropped0 + r1.duplicatesDropped + r2.duplicatesDropped; };
    peer.pump(5000, [&] { return counted() >= expected; });
    EXPECT_EQ(counted(), expected) << "every replay dropped and counted once: " << r1.duplicatesDropped << " + "
                                   << r2.duplicatesDropped << " duplicates in frame reports, "
                                   << master.droppedMessages() - dropped0 << " dropped";
    EXPECT_EQ(master.connectedClients(), 1);
    EXPECT_EQ(master.resyncs(), 0u) << "a replayed Ready or request costs no state transfer";
}

}  // namespace
}  // namespace rtwall
