// CURVE on every link: only the clients whose public keys the master lists get in, and the
// master keeps serving frames whatever knocks at its port. Bounded: refused clients give up
// after their idle limit.
#include "test_util.h"

#include <rtwall/cluster.h>

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
