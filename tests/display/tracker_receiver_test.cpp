// TrackerReceiver on loopback: DTrack datagrams sent to 127.0.0.1 reach the head, malformed ones
// are counted and said, and the receiver stops at once.
#include <rtwall/tracking.h>

#include <gtest/gtest.h>

#include <asio.hpp>

#include <chrono>
#include <thread>

namespace rtwall {
namespace {

void send(int port, const std::string& datagram) {
    asio::io_context io;
    asio::ip::udp::socket s(io, asio::ip::udp::v4());
    s.send_to(asio::buffer(datagram), asio::ip::udp::endpoint(asio::ip::make_address("127.0.0.1"), asio::ip::port_type(port)));
}

template <class Pred> bool waitFor(const TrackerReceiver& r, Pred pred) {
    for (int i = 0; i < 400; ++i) {  // 2 s at most
        if (pred(r.state())) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
}

TEST(TrackerReceiver, HeadFromDatagramsOnLoopback) {
    TrackingConfig c;
    c.enabled = true;
    c.address = "127.0.0.1";
    c.port = 0;
    c.timeoutMs = 60'000;
    TrackerReceiver r(c);
    ASSERT_GT(r.port(), 0);
    EXPECT_FALSE(r.state().seen);
    send(r.port(), "fr 1\r\nts 10.0\r\n6d 1 [0 1.000][250.000 100.000 2500.000][1 0 0 0 1 0 0 0 1]\r\n");
    ASSERT_TRUE(waitFor(r, [](const TrackerState& s) { return s.seen; }));
    TrackerState s = r.state();
    EXPECT_EQ(s.head.position.x, 0.25f);
    EXPECT_EQ(s.head.position.z, 2.5f);
    EXPECT_EQ(s.packets, 1u);
    send(r.port(), "fr 2\r\n6d 1 [0 1.000][250.000 100.000]\r\n");
    ASSERT_TRUE(waitFor(r, [](const TrackerState& t) { return t.dropped == 1; }));
    s = r.state();
    EXPECT_NE(s.lastError.find("line 2 ('6d'): body 1 of 1: position z: expected a number"), std::string::npos) << s.lastError;
    EXPECT_EQ(s.head.position.x, 0.25f);  // the bad one changed nothing
    send(r.port(), "fr 3\r\n6d 1 [0 1.000][-500.000 100.000 2500.000][1 0 0 0 1 0 0 0 1]\r\n");
    ASSERT_TRUE(waitFor(r, [](const TrackerState& t) { return t.head.position.x == -0.5f; }));
    // The bad datagram's line waits for the owner's thread (the session logs it in its step).
    const std::vector<std::string> log = r.takeMessages();
    ASSERT_EQ(log.size(), 1u);
    EXPECT_NE(log[0].find("(from 127.0.0.1)"), std::string::npos) << log[0];
    EXPECT_TRUE(r.takeMessages().empty()) << "taken once";
}

TEST(TrackerReceiver, APortInUseIsAnInputErrorNamingTheSource) {
    TrackingConfig c;
    c.address = "127.0.0.1";
    c.port = 0;
    TrackerReceiver first(c);
    c.port = first.port();
    c.source = "dtrack://127.0.0.1:" + std::to_string(c.port);
    try {
        TrackerReceiver second(c);
        ADD_FAILURE() << "bound twice";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("[tracking]: source 'dtrack://127.0.0.1:"), std::string::npos) << e.what();
    }
}

TEST(TrackerReceiver, TheSimulatorDrivesTheHeadOnLoopback) {
    TrackingConfig c;
    c.address = "127.0.0.1";
    c.port = 0;
    c.timeoutMs = 60'000;
    TrackerReceiver r(c);
    HeadPath path;
    path.keys = {{0.0, {0, 0, 2000}, {0, 0, 0}}, {0.2, {400, 0, 2000}, {0, 0, 0}}};  // 2 m/s along x
    const uint64_t sent = playHeadPath(path, r.port(), 100, 0.3);
    EXPECT_GE(sent, 30u);
    ASSERT_TRUE(waitFor(r, [sent](const TrackerState& s) { return s.packets == sent; })) << r.state().packets << " of " << sent;
    const TrackerState s = r.state();
    EXPECT_EQ(s.dropped, 0u);
    EXPECT_TRUE(s.seen);
    // The path loops; its last frames are past the end of the path and at its start again.
    EXPECT_GE(s.head.position.x, 0.0f);
    EXPECT_LE(s.head.position.x, 0.4f);
    EXPECT_EQ(s.head.position.z, 2.0f);
    // The simulator refuses what it cannot do.
    EXPECT_THROW(playHeadPath(path, 0, 100, 0.1), InputError);
    EXPECT_THROW(playHeadPath(path, r.port(), 0, 0.1), InputError);
}

}  // namespace
}  // namespace rtwall
