// ART DTrack ASCII output: recorded-format frames, every kind of malformed line, and round trips
// through the simulator's writer.
#include <rtwall/tracking.h>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace rtwall {
namespace {

using namespace std::string_literals;

// A frame as DTrack 2 sends it to a wall with a head target (body 0), a hand target (body 1), a
// Flystick 2 (6 buttons, a joystick: 2 controllers; a second one is defined but not seen) and
// two single markers; a glove line the wall does not use.
const std::string kRecorded =
    "fr 21753\r\n"
    "ts 39596.024831\r\n"
    "6dcal 4\r\n"
    "6d 2 [0 1.000][326.848 -187.216 1650.503][-0.940508 -0.339238 0.019025 0.333599 -0.932296 -0.139880 0.065189 "
    "-0.126054 0.989880] [1 0.870][-120.000 310.500 1020.250][0.866025 0.500000 0.000000 -0.500000 0.866025 0.000000 "
    "0.000000 0.000000 1.000000]\r\n"
    "6df2 2 1 [1 1.000 6 2][461.600 -241.200 1053.400][1.000000 0.000000 0.000000 0.000000 0.984808 0.173648 0.000000 "
    "-0.173648 0.984808][37 -0.500000 1.000000]\r\n"
    "3d 2 [84 1.000][-98.523 275.151 1411.106] [85 0.500][-54.002 311.772 1373.544]\r\n"
    "gl 1 [0 1.000 1 3][1.0 2.0 3.0][1 0 0 0 1 0 0 0 1][0.1 0.2 0.3][1 0 0 0 1 0 0 0 1][10 20 30 1 2 3]\r\n";

DTrackFrame parseOk(const std::string& packet) {
    DTrackParser p;
    std::optional<DTrackFrame> f = p.parse(packet);
    EXPECT_TRUE(f.has_value()) << p.error();
    return f ? *f : DTrackFrame{};
}

TEST(DTrack, ParsesARecordedFrame) {
    const DTrackFrame f = parseOk(kRecorded);
    EXPECT_EQ(f.frame, 21753u);
    ASSERT_TRUE(f.timestamp);
    EXPECT_DOUBLE_EQ(*f.timestamp, 39596.024831);
    EXPECT_EQ(f.calibratedBodies, 4);
    ASSERT_EQ(f.bodies.size(), 2u);
    const DTrackBody* head = f.body(0);
    ASSERT_NE(head, nullptr);
    EXPECT_DOUBLE_EQ(head->quality, 1.0);
    EXPECT_DOUBLE_EQ(head->position[0], 326.848);
    EXPECT_DOUBLE_EQ(head->position[1], -187.216);
    EXPECT_DOUBLE_EQ(head->position[2], 1650.503);
    // b0 b1 b2 is the first column: R[0][0], R[1][0], R[2][0].
    EXPECT_DOUBLE_EQ(head->rotation[0], -0.940508);
    EXPECT_DOUBLE_EQ(head->rotation[3], -0.339238);
    EXPECT_DOUBLE_EQ(head->rotation[6], 0.019025);
    EXPECT_DOUBLE_EQ(head->rotation[1], 0.333599);
    EXPECT_DOUBLE_EQ(head->rotation[8], 0.989880);
    const DTrackBody* hand = f.body(1);
    ASSERT_NE(hand, nullptr);
    EXPECT_DOUBLE_EQ(hand->quality, 0.87);
    // 30 degrees about z: the body's x axis (first column) points to (cos 30, sin 30, 0).
    EXPECT_DOUBLE_EQ(hand->rotation[0], 0.866025);
    EXPECT_DOUBLE_EQ(hand->rotation[3], 0.5);
    EXPECT_DOUBLE_EQ(hand->rotation[1], -0.5);
    EXPECT_EQ(f.body(2), nullptr);

    EXPECT_EQ(f.definedFlysticks, 2);
    ASSERT_EQ(f.flysticks.size(), 1u);
    const DTrackFlystick* stick = f.flystick(1);
    ASSERT_NE(stick, nullptr);
    EXPECT_DOUBLE_EQ(stick->pose.position[2], 1053.4);
    // 37 = 0b100101: buttons 0, 2 and 5.
    EXPECT_EQ(stick->buttons, (std::vector<bool>{true, false, true, false, false, true}));
    EXPECT_EQ(stick->controllers, (std::vector<double>{-0.5, 1.0}));
    EXPECT_EQ(f.flystick(0), nullptr);

    ASSERT_EQ(f.markers.size(), 2u);
    EXPECT_EQ(f.markers[1].id, 85);
    EXPECT_DOUBLE_EQ(f.markers[1].quality, 0.5);
    EXPECT_DOUBLE_EQ(f.markers[1].position[2], 1373.544);
    EXPECT_EQ(f.skipped, std::vector<std::string>{"gl"});
}

TEST(DTrack, AcceptsWhatDTrackSendsBesidesTheCommonFrame) {
    // DTrack 1's 6d adds Euler angles after the position; the matrix is used.
    DTrackFrame f = parseOk("fr 7\n6d 1 [3 1.000][1.0 2.0 3.0 -160.4704 -3.6963 -7.0062][1 0 0 0 1 0 0 0 1]\n");
    ASSERT_EQ(f.bodies.size(), 1u);
    EXPECT_EQ(f.bodies[0].id, 3);
    EXPECT_DOUBLE_EQ(f.bodies[0].position[1], 2.0);
    // A flystick out of view: quality -1, zeros for the pose.
    f = parseOk("fr 8\r\n6df2 1 1 [0 -1.000 8 2][0.000 0.000 0.000][0 0 0 0 0 0 0 0 0][0 0.000000 0.000000]\r\n");
    ASSERT_EQ(f.flysticks.size(), 1u);
    EXPECT_LT(f.flysticks[0].pose.quality, 0);
    // 40 buttons: two words; button 39 is bit 7 of the second.
    f = parseOk("6df2 1 1 [0 1.0 40 0][0 0 0][1 0 0 0 1 0 0 0 1][1 128]");
    ASSERT_EQ(f.flysticks[0].buttons.size(), 40u);
    EXPECT_TRUE(f.flysticks[0].buttons[0]);
    EXPECT_TRUE(f.flysticks[0].buttons[39]);
    EXPECT_EQ(std::count(f.flysticks[0].buttons.begin(), f.flysticks[0].buttons.end(), true), 2);
    // Empty lists, brackets with spaces, tabs, trailing NUL bytes, no fr line.
    f = parseOk("6d 0\r\n3d 0\r\n6df2 0 0\r\n");
    EXPECT_TRUE(f.bodies.empty());
    f = parseOk("6d 1 [ 0 1.0 ] [ 1 2 3 ] [ 1 0 0 0 1 0 0 0 1 ]\t\r\n\0\0"s);
    EXPECT_EQ(f.bodies.size(), 1u);
    EXPECT_FALSE(f.frame.has_value());
}

TEST(DTrack, WriterRoundTrips) {
    const DTrackFrame f = parseOk(kRecorded);
    const std::string written = writeDTrackPacket(f);
    DTrackFrame again = parseOk(written);
    again.skipped = f.skipped;  // the writer sends only what it knows
    EXPECT_EQ(again, f) << written;
    EXPECT_EQ(writeDTrackPacket(again), written);
    // Lines end in CR LF, as DTrack's do.
    EXPECT_NE(written.find("fr 21753\r\nts 39596.024831\r\n"), std::string::npos) << written;
}

struct BadCase {
    const char* packet;
    const char* says;  // a part of the one-line message
};

TEST(DTrack, EveryMalformedPacketIsDroppedWithOneLine) {
    const std::vector<BadCase> cases = {
        {"", "empty"},
        {"\r\n  \r\n", "empty"},
        {"fr\r\n", "line 1 ('fr'): the frame counter: expected an integer, found nothing"},
        {"fr -3\r\n", "the frame counter: -3 is out of range"},
        {"fr 12a\r\n", "the frame counter: expected an integer, found '12a'"},
        {"fr 1 2\r\n", "unexpected"},
        {"fr 1\r\nfr 2\r\n", "line 2 ('fr'): a second 'fr' line in one frame"},
        {"ts nan\r\n", "the timestamp: expected a number, found 'nan'"},
        {"ts inf\r\n", "expected a number"},
        {"ts -1.5\r\n", "the timestamp: -1.5 is out of range"},
        {"ts 100000\r\n", "out of range"},
        {"6dcal x\r\n", "the number of calibrated bodies"},
        {"fr 1\r\n\r\nts 2\r\n", "line 2: empty"},
        {"Fr 1\r\n", "line 1: not a DTrack line: 'Fr 1'"},
        {"[0 1.0]\r\n", "not a DTrack line"},
        {"fr 1\x01\r\n", "a byte that is not printable ASCII in 'fr 1\\x01'"},
        {"fr 1\r\n6d 1 [0 1.0]\xff\r\n", "line 2: a byte that is not printable ASCII"},
        {"6d\r\n", "line 1 ('6d'): the number of bodies: expected an integer, found nothing"},
        {"6d -1\r\n", "the number of bodies: -1 is out of range"},
        {"6d 257\r\n", "out of range [0, 256]"},
        {"6d 2 [0 1.000][1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "body 2 of 2: missing (the line ends after 1)"},
        {"6d 0 [0 1.000][1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "more than the 0 bodies it announces"},
        {"6d 1 0 1.000][1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "expected '[' before body 1 of 1, found '0'"},
        {"6d 1 [0 1.000 [1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "expected ']' after body 1 of 1's quality, found '['"},
        {"6d 1 [0][1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "body 1 of 1: quality: expected a number, found ']'"},
        {"6d 1 [-2 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "body 1 of 1: id: -2 is out of range"},
        {"6d 1 [0 1.5][1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "quality: 1.5 is out of range [-1, 1]"},
        {"6d 1 [0 1.0][1 2][1 0 0 0 1 0 0 0 1]\r\n", "position z: expected a number, found ']'"},
        {"6d 1 [0 1.0][1 2 3 4][1 0 0 0 1 0 0 0 1]\r\n", "angle theta: expected a number, found ']'"},
        {"6d 1 [0 1.0][1 2 1e9][1 0 0 0 1 0 0 0 1]\r\n", "position z: 1e+09 is out of range"},
        {"6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0 0]\r\n", "rotation b8: expected a number, found ']'"},
        {"6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1 0]\r\n", "expected ']' after body 1 of 1's rotation, found '0'"},
        {"6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1\r\n", "expected ']' after body 1 of 1's rotation, found the line's end"},
        {"6d 1 [0 1.0][1 2 3][1 0 0 0 2 0 0 0 1]\r\n", "rotation b4: 2 is out of range"},
        {"6d 1 [0 1.0][1 2 3][1 0 0 0 0.5 0 0 0 1]\r\n", "the rotation b0..b8 is not orthonormal (columns 1 and 1)"},
        {"6d 1 [0 1.0][1 2 3][1 0 0 1 0 0 0 0 1]\r\n", "not orthonormal (columns 0 and 1)"},
        {"6d 1 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 -1]\r\n", "is a reflection"},
        {"6d 2 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1] [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "body 2 of 2: id 0 appears twice"},
        {"6df2 1\r\n", "the number of flysticks: expected an integer, found nothing"},
        {"6df2 1 2\r\n", "the number of flysticks: 2 is out of range [0, 1]"},
        {"6df2 1 1 [1 1.0 0 0][0 0 0][1 0 0 0 1 0 0 0 1][]\r\n", "flystick 1 of 1: id: 1 is out of range [0, 0]"},
        {"6df2 1 1 [0 1.0 6][0 0 0][1 0 0 0 1 0 0 0 1][0]\r\n", "number of controllers: expected an integer, found ']'"},
        {"6df2 1 1 [0 1.0 6 0][0 0 0][1 0 0 0 1 0 0 0 1][64]\r\n", "button word 0 (64) sets buttons beyond the 6 it has"},
        {"6df2 1 1 [0 1.0 6 0][0 0 0][1 0 0 0 1 0 0 0 1][1.5]\r\n", "button word 0: expected an integer, found '1.5'"},
        {"6df2 1 1 [0 1.0 6 0][0 0 0][1 0 0 0 1 0 0 0 1][4294967296]\r\n", "button word 0: 4294967296 is out of range"},
        {"6df2 1 1 [0 1.0 6 2][0 0 0][1 0 0 0 1 0 0 0 1][1 0.5]\r\n", "controller 1: expected a number, found ']'"},
        {"6df2 1 1 [0 1.0 6 1][0 0 0][1 0 0 0 1 0 0 0 1][1 1.2]\r\n", "controller 0: 1.2 is out of range [-1, 1]"},
        {"6df2 1 1 [0 1.0 6 1][0 0 0][1 0 0 0 1 0 0 0 1][1 0.5 0.5]\r\n",
         "expected ']' after flystick 1 of 1's 6 buttons and 1 controllers, found '0.5'"},
        {"6df2 1 1 [0 1.0 300 0][0 0 0][1 0 0 0 1 0 0 0 1][]\r\n", "number of buttons: 300 is out of range [0, 256]"},
        {"6df2 2 2 [0 1.0 0 0][0 0 0][1 0 0 0 1 0 0 0 1][] [0 1.0 0 0][0 0 0][1 0 0 0 1 0 0 0 1][]\r\n", "id 0 appears twice"},
        {"3d 1 [84 1.0][1 2]\r\n", "marker 1 of 1: position z: expected a number"},
        {"3d 1 [84 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\r\n", "more than the 1 markers it announces"},
        {"3d 1 [84 1.0 7][1 2 3]\r\n", "expected ']' after marker 1 of 1's quality, found '7'"},
    };
    for (const BadCase& c : cases) {
        const std::string packet = c.packet;
        DTrackParser p;
        EXPECT_FALSE(p.parse(packet).has_value()) << packet;
        EXPECT_EQ(p.dropped(), 1u);
        EXPECT_EQ(p.parsed(), 0u);
        EXPECT_NE(p.error().find(c.says), std::string::npos) << "packet: " << packet << "\nerror: " << p.error() << "\nwanted: " << c.says;
        EXPECT_EQ(p.error().rfind("dtrack packet: ", 0), 0u) << p.error();
        EXPECT_EQ(p.error().find('\n'), std::string::npos) << p.error();
    }
    // Over a datagram's size.
    DTrackParser p;
    EXPECT_FALSE(p.parse(std::string(DTrackParser::kMaxPacket + 1, ' ')));
    EXPECT_NE(p.error().find("more than a UDP datagram holds"), std::string::npos) << p.error();
}

TEST(DTrack, EveryTruncationAndByteFlipIsAFrameOrOneLine) {
    // The ways a datagram goes wrong in practice (cut short, a bit flipped): never a crash, and a
    // drop always says why in one line. Prefixes that end on a line's end are whole frames.
    DTrackParser p;
    size_t dropped = 0;
    for (size_t n = 0; n <= kRecorded.size(); ++n) {
        if (!p.parse(std::string_view(kRecorded).substr(0, n))) {
            ++dropped;
            ASSERT_EQ(p.error().find('\n'), std::string::npos) << n;
            ASSERT_FALSE(p.error().empty());
        }
    }
    EXPECT_GT(dropped, kRecorded.size() / 2);
    for (size_t i = 0; i < kRecorded.size(); ++i)
        for (unsigned char bit : {0x01, 0x10, 0x80}) {
            std::string flipped = kRecorded;
            flipped[i] = char(static_cast<unsigned char>(flipped[i]) ^ bit);
            if (!p.parse(flipped)) {
                ASSERT_EQ(p.error().find('\n'), std::string::npos) << i;
            }
        }
    EXPECT_EQ(p.parsed() + p.dropped(), kRecorded.size() + 1 + 3 * kRecorded.size());
}

}  // namespace
}  // namespace rtwall
