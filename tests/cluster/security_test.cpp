// CURVE on every link: only the clients whose public keys the master lists get in, and the
// master keeps serving frames whatever knocks at its port. Bounded: refused clients give up
// after their idle limit.
#include "test_util.h"

#include "protocol.h"

#include <rtwall/cluster.h>

#include <zmq.hpp>

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <future>
#include <random>

namespace rtwall {
namespace {

SceneDesc smallScene() {
    SceneDesc desc = loadSceneFile(test::sourceDir() / "configs/demo.toml");
    desc.settings.width = 64;
    desc.settings.height = 48;
    desc.settings.supersample = 1;
    return desc;
}

Image singleMachine(const SceneDesc& desc) {
    const Scene scene(desc);
    return renderFrame(scene, Camera(desc.cameras.front(), desc.settings.width, desc.settings.height), desc.settings);
}

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
    ClusterSettings cs;
    cs.async = false;
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
    ClusterSettings cs;
    cs.async = false;
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

    // Another protocol version: refused with a goodbye that names both versions.
    Header future;
    future.type = MsgType::Hello;
    future.version = kProtocolVersion + 1;
    rogue.send(zmq::buffer(encodeMessage(future, Hello{uint16_t(kProtocolVersion + 1), 1, "future"})));
    bool namedBoth = false;
    for (int i = 0; i < 20 && !namedBoth; ++i) {
        zmq::message_t msg;
        if (!rogue.recv(msg)) break;
        const auto* p = static_cast<const uint8_t*>(msg.data());
        const Header in = decodeHeader(p, msg.size());
        if (in.type != MsgType::Goodbye) continue;
        const Goodbye bye = decodePayload<Goodbye>(p + kHeaderSize, msg.size() - kHeaderSize);
        namedBoth = bye.reason.find(std::to_string(kProtocolVersion + 1)) != std::string::npos &&
                    bye.reason.find(std::to_string(kProtocolVersion)) != std::string::npos;
    }
    EXPECT_TRUE(namedBoth);

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
