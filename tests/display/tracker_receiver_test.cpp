// TrackerReceiver on loopback: DTrack datagrams sent to 127.0.0.1 reach the head, malformed ones
// are counted and said, and the receiver stops at once.
#include <rtwall/tracking.h>

#include <gtest/gtest.h>

#include <asio.hpp>

#include <algorithm>
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

// VRPN over loopback: a server of this test's own (the bytes VRPN 07 sends) on 127.0.0.1. The
// receiver sends its cookie and offers a UDP port; the server's TCP reports and its UDP report
// reach the head; a closed connection is said and tried again.
TEST(TrackerReceiver, VrpnServerOnLoopbackOverTcpAndUdp) {
    asio::io_context io;
    asio::ip::tcp::acceptor acceptor(io, asio::ip::tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
    const int port = acceptor.local_endpoint().port();
    TrackingConfig c;
    c.enabled = true;
    c.kind = TrackingSource::Vrpn;
    c.server = "Tracker0@127.0.0.1:" + std::to_string(port);
    c.device = c.buttonDevice = c.analogDevice = "Tracker0";
    c.address = "127.0.0.1";
    c.port = port;
    c.roomScale = 1;
    c.flystick = 1;
    c.timeoutMs = 60'000;
    TrackerReceiver r(c);
    EXPECT_EQ(r.port(), port);

    asio::ip::tcp::socket peer(io);
    acceptor.accept(peer);
    // The client's cookie, then its UDP offer: port in the sender field, the address with a NUL.
    std::string cookie(24, '\0');
    asio::read(peer, asio::buffer(cookie));
    EXPECT_EQ(cookie.substr(0, 14), "vrpn: ver. 07.");
    EXPECT_EQ(cookie[18], '0');
    std::string header(24, '\0');
    asio::read(peer, asio::buffer(header));
    auto u32 = [&](size_t at) {
        return uint32_t(uint8_t(header[at])) << 24 | uint32_t(uint8_t(header[at + 1])) << 16 | uint32_t(uint8_t(header[at + 2])) << 8 |
               uint32_t(uint8_t(header[at + 3]));
    };
    EXPECT_EQ(int32_t(u32(16)), -3) << "a UDP description";
    const uint32_t udpPort = u32(12), payload = u32(0) - 24;
    std::string address((payload + 7) / 8 * 8, '\0');
    asio::read(peer, asio::buffer(address));
    EXPECT_EQ(std::string(address.c_str()), "127.0.0.1");
    ASSERT_GT(udpPort, 0u);

    std::string session = vrpnCookie() + vrpnName(0, -1, "Tracker0") + vrpnName(0, -2, "vrpn_Tracker Pos_Quat") +
                          vrpnName(1, -2, "vrpn_Button Change");
    session += vrpnMessage(0, 0, 100.0, vrpnPosQuat(0, {0.5, 1.25, 2.0}, {0, 0, 0, 1}));
    session += vrpnMessage(0, 1, 100.0, vrpnButtonChange(0, 1));
    asio::write(peer, asio::buffer(session));
    ASSERT_TRUE(waitFor(r, [](const TrackerState& s) { return s.seen && s.wand.button(0); }));
    EXPECT_EQ(r.state().head.position.y, 1.25f);
    // A report by UDP, as a VRPN server sends its trackers' reports once offered a port.
    asio::ip::udp::socket udp(io, asio::ip::udp::v4());
    udp.send_to(asio::buffer(vrpnMessage(0, 0, 100.5, vrpnPosQuat(0, {-0.75, 1.25, 2.0}, {0, 0, 0, 1}))),
                asio::ip::udp::endpoint(asio::ip::make_address("127.0.0.1"), asio::ip::port_type(udpPort)));
    ASSERT_TRUE(waitFor(r, [](const TrackerState& s) { return s.head.position.x == -0.75f; }));
    // A malformed report: dropped, said once.
    asio::write(peer, asio::buffer(vrpnMessage(0, 1, 101.0, vrpnButtonChange(0, 5))));
    ASSERT_TRUE(waitFor(r, [](const TrackerState& s) { return s.dropped == 1; }));
    EXPECT_NE(r.state().lastError.find("button 0 to state 5"), std::string::npos) << r.state().lastError;
    // The server goes away: said, and the receiver comes back to the next server on the port.
    peer.close();
    acceptor.non_blocking(true);  // bounded: the receiver tries again after a second
    asio::ip::tcp::socket again(io);
    std::vector<std::string> said;
    bool reconnected = false;
    for (int i = 0; i < 600 && !reconnected; ++i) {  // 3 s at most
        for (std::string& l : r.takeMessages()) said.push_back(std::move(l));
        asio::error_code ec;
        acceptor.accept(again, ec);
        reconnected = !ec;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    EXPECT_TRUE(reconnected) << "the receiver connects again";
    for (std::string& l : r.takeMessages()) said.push_back(std::move(l));
    EXPECT_TRUE(std::any_of(said.begin(), said.end(), [](const std::string& l) { return l.find("tracker: connected to VRPN Tracker0@127.0.0.1") != std::string::npos; }));
    EXPECT_TRUE(std::any_of(said.begin(), said.end(), [](const std::string& l) { return l.find("tracker: VRPN Tracker0@127.0.0.1:" ) != std::string::npos && l.find("the server closed the connection") != std::string::npos; }));
    EXPECT_TRUE(std::any_of(said.begin(), said.end(), [](const std::string& l) { return l.find("vrpn message: vrpn_Button Change from 'Tracker0': button 0 to state 5") != std::string::npos; }));
}

// Issue 27: the frame loop reads the buttons once a frame. The clicks a flystick made between
// two reads, counted from the events after the last one the reader acted on.
int clicksSince(const TrackerState& s, uint64_t& seen, int button) {
    int n = 0;
    for (const ButtonEvent& e : s.wand.eventsAfter(seen)) n += e.button == button && e.pressed;
    seen = s.wand.lastEvent();
    return n;
}

DTrackFrame flystickButtons(std::vector<bool> buttons, uint64_t frame) {
    DTrackFrame f;
    f.frame = frame;
    DTrackFlystick w;
    w.pose.quality = 1;
    w.buttons = std::move(buttons);
    f.definedFlysticks = 1;
    f.flysticks.push_back(w);
    return f;
}

TEST(TrackerReceiver, DTrackClicksBetweenTwoReadsAreEachSeen) {
    TrackingConfig c;
    c.address = "127.0.0.1";
    c.port = 0;
    c.flystick = 0;
    c.timeoutMs = 60'000;
    TrackerReceiver r(c);
    DTrackSender sender(r.port());
    uint64_t seen = 0, frame = 0;
    sender.send(flystickButtons({false, false}, ++frame));
    ASSERT_TRUE(waitFor(r, [&](const TrackerState& s) { return s.packets == frame; }));
    EXPECT_EQ(clicksSince(r.state(), seen, 0), 0);
    // Pressed and let go between two reads: the state says "up", the click is one.
    sender.send(flystickButtons({true, false}, ++frame));
    sender.send(flystickButtons({false, false}, ++frame));
    ASSERT_TRUE(waitFor(r, [&](const TrackerState& s) { return s.packets == frame; }));
    TrackerState s = r.state();
    EXPECT_FALSE(s.wand.button(0));
    EXPECT_EQ(clicksSince(s, seen, 0), 1);
    EXPECT_EQ(clicksSince(r.state(), seen, 0), 0) << "a click is seen once";
    // Four clicks of the trigger and one of button 1 between two reads.
    for (int i = 0; i < 4; ++i) {
        sender.send(flystickButtons({true, i == 2}, ++frame));
        sender.send(flystickButtons({false, false}, ++frame));
    }
    ASSERT_TRUE(waitFor(r, [&](const TrackerState& t) { return t.packets == frame; }));
    s = r.state();
    uint64_t seen1 = seen;
    EXPECT_EQ(clicksSince(s, seen, 0), 4);
    EXPECT_EQ(clicksSince(s, seen1, 1), 1);
    EXPECT_EQ(s.dropped, 0u);
}

// The same through VRPN, whose buttons come as "vrpn_Button Change" messages: two clicks in one
// TCP write, then one by UDP, each between two reads.
TEST(TrackerReceiver, VrpnClicksBetweenTwoReadsAreEachSeen) {
    asio::io_context io;
    asio::ip::tcp::acceptor acceptor(io, asio::ip::tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
    const int port = acceptor.local_endpoint().port();
    TrackingConfig c;
    c.enabled = true;
    c.kind = TrackingSource::Vrpn;
    c.server = "Wand@127.0.0.1:" + std::to_string(port);
    c.device = c.buttonDevice = c.analogDevice = "Wand";
    c.address = "127.0.0.1";
    c.port = port;
    c.roomScale = 1;
    c.flystick = 1;
    c.timeoutMs = 60'000;
    TrackerReceiver r(c);
    asio::ip::tcp::socket peer(io);
    acceptor.accept(peer);
    // The client's cookie and its UDP offer (the port in the sender field; VrpnServerOnLoopbackOverTcpAndUdp
    // reads them in detail).
    std::string cookie(24, '\0'), header(24, '\0');
    asio::read(peer, asio::buffer(cookie));
    asio::read(peer, asio::buffer(header));
    const auto u32 = [&](size_t at) {
        return uint32_t(uint8_t(header[at])) << 24 | uint32_t(uint8_t(header[at + 1])) << 16 | uint32_t(uint8_t(header[at + 2])) << 8 |
               uint32_t(uint8_t(header[at + 3]));
    };
    const uint32_t udpPort = u32(12);
    std::string address((u32(0) - 24 + 7) / 8 * 8, '\0');
    asio::read(peer, asio::buffer(address));

    std::string session = vrpnCookie() + vrpnName(0, -1, "Wand") + vrpnName(0, -2, "vrpn_Tracker Pos_Quat") +
                          vrpnName(1, -2, "vrpn_Button Change");
    session += vrpnMessage(0, 0, 100.0, vrpnPosQuat(1, {0.5, 1.0, 1.5}, {0, 0, 0, 1}));
    asio::write(peer, asio::buffer(session));
    ASSERT_TRUE(waitFor(r, [](const TrackerState& s) { return s.wand.seen; }));
    uint64_t seen = 0;
    EXPECT_EQ(clicksSince(r.state(), seen, 0), 0);
    std::string clicks;
    for (int i = 0; i < 2; ++i)
        clicks += vrpnMessage(0, 1, 100.1 + i * 0.01, vrpnButtonChange(0, 1)) + vrpnMessage(0, 1, 100.105 + i * 0.01, vrpnButtonChange(0, 0));
    asio::write(peer, asio::buffer(clicks));
    ASSERT_TRUE(waitFor(r, [](const TrackerState& s) { return s.wand.lastEvent() == 4; }));
    TrackerState s = r.state();
    EXPECT_FALSE(s.wand.button(0));
    EXPECT_EQ(clicksSince(s, seen, 0), 2);
    asio::ip::udp::socket udp(io, asio::ip::udp::v4());
    udp.send_to(asio::buffer(vrpnMessage(0, 1, 100.2, vrpnButtonChange(0, 1)) + vrpnMessage(0, 1, 100.21, vrpnButtonChange(0, 0))),
                asio::ip::udp::endpoint(asio::ip::make_address("127.0.0.1"), asio::ip::port_type(udpPort)));
    ASSERT_TRUE(waitFor(r, [](const TrackerState& t) { return t.wand.lastEvent() == 6; }));
    EXPECT_EQ(clicksSince(r.state(), seen, 0), 1);
    EXPECT_EQ(r.state().dropped, 0u);
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
