// The flystick and the orientation: the one-euro filter on quaternions, the tracker's own
// timestamps, the wand in wall coordinates, its navigation (fly and orbit) from a scripted packet
// sequence, and its ray drawn per eye. Plain code, no sockets.
#include <rtwall/tracking.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace rtwall {
namespace {

using Quat = std::array<double, 4>;

Quat aboutAxis(double x, double y, double z, double degrees) {
    const double n = std::sqrt(x * x + y * y + z * z), h = degrees * std::numbers::pi / 360.0;
    return {std::cos(h), std::sin(h) * x / n, std::sin(h) * y / n, std::sin(h) * z / n};
}
double angleBetween(const Quat& a, const Quat& b) {
    const double d = std::fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
    return 2 * std::acos(std::min(1.0, d)) * 180 / std::numbers::pi;
}

TEST(Orientation, QuaternionsRoundTripRotations) {
    for (const Quat& q : {aboutAxis(1, 0, 0, 30), aboutAxis(0, 1, 0, 179), aboutAxis(1, 2, 3, -120), aboutAxis(0, 0, 1, 180)}) {
        const auto m = rotationOf(q);
        const Quat back = quaternionOf(m);
        EXPECT_LT(angleBetween(q, back), 1e-6);
        const auto again = rotationOf(back);
        for (size_t i = 0; i < 9; ++i) EXPECT_NEAR(again[i], m[i], 1e-12);
    }
    // Halfway from nothing to 90 degrees about y is 45 degrees about y, also from -q's side.
    const Quat half = slerp({1, 0, 0, 0}, aboutAxis(0, 1, 0, 90), 0.5);
    EXPECT_LT(angleBetween(half, aboutAxis(0, 1, 0, 45)), 1e-9);
    const Quat q90 = aboutAxis(0, 1, 0, 90);
    EXPECT_LT(angleBetween(slerp({1, 0, 0, 0}, {-q90[0], -q90[1], -q90[2], -q90[3]}, 0.5), aboutAxis(0, 1, 0, 45)), 1e-9);
}

TEST(Orientation, OneEuroSmoothsAStillHeadAndFollowsATurningOne) {
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.3);  // degrees of jitter about a random axis
    OneEuroRotationFilter filter(1.0, 0.1, 1.0);
    const Quat still = aboutAxis(0, 1, 0, 20);
    double rawError = 0, filteredError = 0;
    const int n = 600;
    for (int i = 0; i < n; ++i) {
        const Quat j = aboutAxis(noise(rng), noise(rng), noise(rng) + 1e-9, noise(rng));
        // still * j
        const Quat q{still[0] * j[0] - still[1] * j[1] - still[2] * j[2] - still[3] * j[3],
                     still[0] * j[1] + still[1] * j[0] + still[2] * j[3] - still[3] * j[2],
                     still[0] * j[2] - still[1] * j[3] + still[2] * j[0] + still[3] * j[1],
                     still[0] * j[3] + still[1] * j[2] - still[2] * j[1] + still[3] * j[0]};
        // Every other sample as -q: the same turn, which must not flip the filter.
        const Quat given = i % 2 ? Quat{-q[0], -q[1], -q[2], -q[3]} : q;
        const Quat f = filter(given, i / 60.0);
        EXPECT_NEAR(f[0] * f[0] + f[1] * f[1] + f[2] * f[2] + f[3] * f[3], 1.0, 1e-12);
        if (i >= 60) {
            rawError += angleBetween(q, still);
            filteredError += angleBetween(f, still);
        }
    }
    EXPECT_LT(filteredError, 0.35 * rawError) << "a still head's jitter is smoothed";
    // Turning at 90 degrees a second: the speed raises the cutoff (by beta per rad/s), so the
    // lag stays small; with the still head's beta it would lag by some 12 degrees.
    OneEuroRotationFilter turning(1.0, 5.0, 1.0);
    double worst = 0;
    for (int i = 0; i < 120; ++i) {
        const Quat q = aboutAxis(0, 1, 0, 90.0 * i / 60.0);
        const Quat f = turning(q, i / 60.0);
        if (i >= 30) worst = std::max(worst, angleBetween(q, f));
    }
    EXPECT_LT(worst, 3.0) << "degrees behind a head turning at 90 deg/s";
    EXPECT_GT(worst, 0.0);
}

DTrackFrame headAt(double x, std::optional<double> ts) {
    DTrackFrame f;
    f.timestamp = ts;
    DTrackBody b;
    b.quality = 1;
    b.position = {x, 0, 0};
    f.bodies.push_back(b);
    return f;
}

TEST(Orientation, TimestampsGiveTheVelocityDespiteArrivalJitter) {
    TrackingConfig c;
    c.roomScale = 1;
    c.predictionMs = 0.001;  // on (a hair), so the velocity is fitted
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> jitter(0.0, 0.008);
    // 0.5 m/s, measured every 1/60 s; the datagrams arrive 2..10 ms later, unevenly.
    HeadTracker stamped(c), arrival(c);
    double t = 0;
    for (int i = 0; i < 30; ++i) {
        const double ts = 40000.0 + i / 60.0, at = 1000.0 + i / 60.0 + 0.002 + jitter(rng);
        stamped.add(headAt(0.5 * i / 60.0, ts), at);
        arrival.add(headAt(0.5 * i / 60.0, std::nullopt), at);
        t = at;
    }
    EXPECT_NEAR(stamped.at(t).velocity.x, 0.5, 2e-4);
    EXPECT_GT(std::fabs(arrival.at(t).velocity.x - 0.5), 1e-3) << "the jitter this test is about";
    EXPECT_FALSE(stamped.at(t).latency) << "clocks that do not agree give no latency";
}

TEST(Orientation, SynchronisedClocksMeasureTheLatencyAndAgeFromTheMeasurement) {
    TrackingConfig c;
    c.roomScale = 1;
    c.predictionMs = 10;
    HeadTracker h(c);
    // Measured at 43200.000 UTC and 43200.010, arriving 7 ms later each.
    h.add(headAt(0.0, 43200.000), 500.007, 43200.007);
    h.add(headAt(0.005, 43200.010), 500.017, 43200.017);
    const TrackerState s = h.at(500.017);
    ASSERT_TRUE(s.latency);
    EXPECT_NEAR(*s.latency, 0.007, 1e-9);
    EXPECT_NEAR(s.age, 0.007, 1e-9);
    // 0.5 m/s predicted over the age and the 10 ms ahead: 0.005 + 0.5 * 0.017.
    EXPECT_NEAR(s.head.position.x, 0.005 + 0.5 * 0.017, 1e-6);
    EXPECT_NE(describeTracker(s).find("measured 7.0 ms before arrival"), std::string::npos) << describeTracker(s);
    // Across midnight: measured at 86399.995, arriving at 0.002 of the next day.
    HeadTracker m(c);
    m.add(headAt(0, 86399.995), 10.0, 0.002);
    ASSERT_TRUE(m.at(10.0).latency);
    EXPECT_NEAR(*m.at(10.0).latency, 0.007, 1e-6);
}

// The shipped room (z up, y towards the screen) and a flystick 6df2 in it.
TrackingConfig shippedRoom() {
    TrackingConfig c;
    c.roomRotate = {-90, 0, 0};
    c.roomTranslate = {0, -1.5, 2.5};
    c.flystick = 0;
    return c;
}
DTrackFrame flystickFrame(std::array<double, 3> mm, const std::array<double, 9>& rotation, std::vector<bool> buttons,
                          std::vector<double> joystick, double quality = 1) {
    DTrackFrame f;
    DTrackFlystick s;
    s.pose.id = 0;
    s.pose.quality = quality;
    s.pose.position = mm;
    s.pose.rotation = rotation;
    s.buttons = std::move(buttons);
    s.controllers = std::move(joystick);
    f.definedFlysticks = 1;
    f.flysticks.push_back(s);
    return f;
}
// The flystick as DTrack holds it pointing at the screen: its -z along the room's +y.
const std::array<double, 9> kPointingAtScreen{1, 0, 0, 0, 0, -1, 0, 1, 0};

TEST(Wand, FlystickPoseButtonsAndJoystickInWallCoordinates) {
    HeadTracker h(shippedRoom());
    EXPECT_FALSE(h.at(0).wand.seen);
    // Through the writer and the parser, as the datagram carries it.
    DTrackParser parser;
    const std::optional<DTrackFrame> f =
        parser.parse(writeDTrackPacket(flystickFrame({200, 300, 1200}, kPointingAtScreen, {true, false, true}, {0.5, -1})));
    ASSERT_TRUE(f) << parser.error();
    EXPECT_FALSE(h.add(*f, 1.0)) << "no head in it";
    const WandState w = h.at(1.0).wand;
    ASSERT_TRUE(w.seen);
    EXPECT_TRUE(w.visible);
    EXPECT_NEAR(w.position.x, 0.2, 1e-6);
    EXPECT_NEAR(w.position.y, -0.3, 1e-6);  // 1.2 m above the floor, which is 1.5 m below the wall's centre
    EXPECT_NEAR(w.position.z, 2.2, 1e-6);
    EXPECT_NEAR(w.direction.z, -1.0, 1e-6) << "pointing at the screen is -z in wall coordinates";
    EXPECT_TRUE(w.button(0));
    EXPECT_FALSE(w.button(1));
    EXPECT_TRUE(w.button(2));
    EXPECT_FALSE(w.button(7));
    EXPECT_EQ(w.controller(0), 0.5);
    EXPECT_EQ(w.controller(1), -1.0);
    // Out of sight: the pose is kept, the buttons still count; after the timeout nothing counts.
    h.add(flystickFrame({0, 0, 0}, kPointingAtScreen, {false, true}, {0, 0}, -1), 1.1);
    EXPECT_FALSE(h.at(1.1).wand.visible);
    EXPECT_NEAR(h.at(1.1).wand.position.x, 0.2, 1e-6);
    EXPECT_TRUE(h.at(1.1).wand.button(1));
    EXPECT_TRUE(h.at(2.0).wand.stale);
    EXPECT_FALSE(h.at(2.0).wand.button(1));
    EXPECT_EQ(h.at(2.0).wand.controller(0), 0.0);
}

// A scripted flystick sequence (DTrack datagrams) through the tracker into the navigator: the
// joystick pushed forward flies along the wand, pulled back the other way, to the side turns.
TEST(Wand, JoystickFliesAlongTheWandAndTurns) {
    const TrackingConfig c = shippedRoom();
    HeadTracker h(c);
    DTrackParser parser;
    ViewPose start;
    start.position = {0, 0, 5};
    start.lookAt = {0, 0, 0};
    Navigator nav(start);
    nav.setMode(Navigator::Mode::Fly);
    // The wand pointing at the screen, tipped 45 degrees down (about the room's x axis).
    const double s = std::sqrt(0.5);
    const std::array<double, 9> tipped{1, 0, 0, 0, s, -s, 0, s, s};
    auto step = [&](const DTrackFrame& f, double t) {
        const std::optional<DTrackFrame> g = parser.parse(writeDTrackPacket(f));
        ASSERT_TRUE(g) << parser.error();
        h.add(*g, t);
        const WandState w = h.at(t).wand;
        Navigator::Wand nw;
        nw.x = w.controller(c.joystickX);
        nw.y = w.controller(c.joystickY);
        nw.direction = wallToWorld({0, 0.2f, 2.5f}, nav.pose()).direction(w.direction);
        nw.speed = 2.0;
        nw.turnDegrees = 90;
        nav.updateWand(nw, 0.5);
    };
    step(flystickFrame({0, 0, 1200}, tipped, {}, {0, 1}), 0.0);  // full forward for 0.5 s at 2 m/s: 1 m
    EXPECT_NEAR(nav.pose().position.x, 0, 1e-5);
    EXPECT_NEAR(nav.pose().position.y, -s, 1e-5);
    EXPECT_NEAR(nav.pose().position.z, 5 - s, 1e-5);
    EXPECT_NEAR(nav.pose().lookAt.y, -s, 1e-5) << "flying does not turn the view";
    step(flystickFrame({0, 0, 1200}, tipped, {}, {0, -0.5}), 0.5);  // half back: 0.5 m
    EXPECT_NEAR(nav.pose().position.y, -s / 2, 1e-5);
    EXPECT_NEAR(nav.pose().position.z, 5 - s / 2, 1e-5);
    step(flystickFrame({0, 0, 1200}, tipped, {}, {1, 0}), 1.0);  // right for 0.5 s at 90 deg/s: a 45-degree turn right
    const Float3 p = nav.pose().position, a = nav.pose().lookAt;
    const double dx = a.x - p.x, dz = a.z - p.z;
    EXPECT_NEAR(std::atan2(dx, -dz) * 180 / std::numbers::pi, 45, 1e-3);
    EXPECT_NEAR(p.z, 5 - s / 2, 1e-5) << "turning stays in place";
}

TEST(Wand, OrbitTurnsAboutTheCentreAndApproachesIt) {
    ViewPose start;
    start.position = {0, 1, 10};
    start.lookAt = {0, 1, 0};
    Navigator nav(start);
    nav.setMode(Navigator::Mode::Orbit);
    Navigator::Wand w;
    w.centre = {0, 0, 0};
    w.x = 1;
    w.turnDegrees = 90;
    ASSERT_TRUE(nav.updateWand(w, 1.0));  // a quarter turn to the right: from +z round to -x
    EXPECT_NEAR(nav.pose().position.x, -10, 1e-4);
    EXPECT_NEAR(nav.pose().position.z, 0, 1e-4);
    EXPECT_NEAR(nav.pose().position.y, 1, 1e-6);
    EXPECT_NEAR(nav.pose().lookAt.x, 0, 1e-4);
    w.x = 0;
    w.y = 1;
    w.speed = 4;
    nav.updateWand(w, 1.0);  // 4 units towards the centre
    EXPECT_NEAR(nav.pose().position.x, -10 + 4 * 10 / std::sqrt(101.0), 1e-4);
    for (int i = 0; i < 10; ++i) nav.updateWand(w, 1.0);
    const Float3 p = nav.pose().position;
    EXPECT_GT(p.x * p.x + p.y * p.y + p.z * p.z, 0.0) << "never past the centre";
    EXPECT_LT(p.x * p.x + p.y * p.y + p.z * p.z, 0.01);
    EXPECT_FALSE(nav.updateWand(Navigator::Wand{}, 1.0)) << "a joystick at rest moves nothing";
}

// Issue 27: the buttons are read once a frame, but every change the datagrams carried is kept
// in order, so a click between two reads is one press and one release.
int presses(const std::vector<ButtonEvent>& events, int button) {
    return int(std::count_if(events.begin(), events.end(), [&](const ButtonEvent& e) { return e.button == button && e.pressed; }));
}

TEST(Wand, EveryPressAndReleaseBetweenTwoReadsIsKeptInOrder) {
    HeadTracker h(shippedRoom());
    auto add = [&](std::vector<bool> buttons, double t) { h.add(flystickFrame({0, 0, 1200}, kPointingAtScreen, std::move(buttons), {}), t); };
    add({false, false}, 0.00);
    EXPECT_TRUE(h.at(0.0).wand.events.empty()) << "released buttons are no change";
    uint64_t seen = h.at(0.0).wand.lastEvent();
    // Between two reads: a click of the trigger (two datagrams), and button 1 pressed with it.
    add({true, false}, 0.01);
    add({false, true}, 0.02);
    WandState w = h.at(0.03).wand;
    EXPECT_FALSE(w.button(0)) << "the state alone has lost the click";
    const std::vector<ButtonEvent> got = w.eventsAfter(seen);
    const std::vector<ButtonEvent> want{{1, 0, true}, {2, 0, false}, {3, 1, true}};
    EXPECT_EQ(got, want);
    seen = w.lastEvent();
    EXPECT_TRUE(h.at(0.03).wand.eventsAfter(seen).empty()) << "read once";
    // Three clicks between two reads are three presses.
    for (int i = 0; i < 3; ++i) {
        add({true, true}, 0.04 + 0.02 * i);
        add({false, true}, 0.05 + 0.02 * i);
    }
    EXPECT_EQ(presses(h.at(0.1).wand.eventsAfter(seen), 0), 3);
    EXPECT_EQ(h.at(0.1).wand.eventsAfter(seen).size(), 6u);
    // A flystick that lists fewer buttons has the others up.
    seen = h.at(0.1).wand.lastEvent();
    add({}, 0.11);
    EXPECT_EQ(h.at(0.11).wand.eventsAfter(seen), (std::vector<ButtonEvent>{{seen + 1, 1, false}}));
}

TEST(Wand, ButtonEventsAreBoundedAndALostWandLetsGo) {
    HeadTracker h(shippedRoom());
    const double frame = 1.0 / 60;
    for (int i = 0; i < 100; ++i) h.add(flystickFrame({0, 0, 1200}, kPointingAtScreen, {i % 2 == 0}, {}), i * frame);
    uint64_t lost = 0;
    const std::vector<ButtonEvent> e = h.at(100 * frame).wand.eventsAfter(0, &lost);
    ASSERT_EQ(e.size(), WandState::kMaxButtonEvents);
    EXPECT_EQ(lost, 100 - WandState::kMaxButtonEvents);
    EXPECT_EQ(e.back().seq, 100u);
    EXPECT_FALSE(e.back().pressed);
    // Held when the wand is lost, still held when it is back after the timeout: the readers took
    // it as let go meanwhile, so the events say so and it is pressed anew.
    h.add(flystickFrame({0, 0, 1200}, kPointingAtScreen, {true}, {}), 2.0);
    EXPECT_TRUE(h.at(2.0).wand.button(0));
    EXPECT_FALSE(h.at(3.0).wand.button(0)) << "stale";
    h.add(flystickFrame({0, 0, 1200}, kPointingAtScreen, {true}, {}), 3.0);
    EXPECT_EQ(h.at(3.0).wand.eventsAfter(100), (std::vector<ButtonEvent>{{101, 0, true}, {102, 0, false}, {103, 0, true}}));
}

// The ray drawn into each eye's image: a point on the screen's plane is drawn where it is for
// both eyes; a point in front of the screen is drawn apart for the two eyes (crossed parallax).
TEST(Wand, RayIsDrawnPerEyeWithTheRightParallax) {
    WallConfig wall;
    wall.width = 320;
    wall.height = 240;
    wall.stereo.mode = StereoMode::Passive;
    wall.stereo.lowerLeft = {-1.6f, -1.2f, 0};
    wall.stereo.lowerRight = {1.6f, -1.2f, 0};
    wall.stereo.upperLeft = {-1.6f, 1.2f, 0};
    ScreenConfig sc;
    sc.viewport = {0, 0, 320, 240};
    wall.screens = {sc};
    HeadPose head;
    head.position = {0, 0, 2};
    auto drawn = [&](int eye, Float3 a, Float3 b) {
        Image img;
        img.width = 320;
        img.height = 240;
        img.rgb.assign(320 * 240 * 3, 0);
        drawWandRay(wall, head, eye, a, b, img);
        std::vector<std::pair<int, int>> pixels;
        for (int y = 0; y < 240; ++y)
            for (int x = 0; x < 320; ++x)
                if (img.rgb[(size_t(y) * 320 + size_t(x)) * 3] != 0) pixels.emplace_back(x, y);
        return pixels;
    };
    // A ray along the screen itself (z = 0), from its centre to the right edge's middle: a
    // horizontal line through the middle row, the same for both eyes and for the mono head.
    auto meanX = [](const std::vector<std::pair<int, int>>& px) {
        double s = 0;
        for (const auto& p : px) s += p.first;
        return s / double(px.size());
    };
    auto meanY = [](const std::vector<std::pair<int, int>>& px) {
        double s = 0;
        for (const auto& p : px) s += p.second;
        return s / double(px.size());
    };
    const auto onScreen = drawn(0, {0, 0, 0}, {1.6f, 0, 0});
    ASSERT_FALSE(onScreen.empty());
    for (int eye : {1, -1}) {
        // The same line within the rounding of the last pixel (the eyes' float arithmetic differs).
        const auto other = drawn(eye, {0, 0, 0}, {1.6f, 0, 0});
        EXPECT_NEAR(meanX(other), meanX(onScreen), 1.0);
        EXPECT_NEAR(meanY(other), meanY(onScreen), 0.5);
    }
    for (const auto& [x, y] : onScreen) {
        EXPECT_GE(x, 159);
        EXPECT_TRUE(y == 119 || y == 120 || y == 121) << y;
    }
    EXPECT_NEAR(double(onScreen.size()), 2 * 160, 4);
    // A vertical ray half-way between the eyes and the screen: each eye sees it on the other
    // side (crossed), by the eye separation: 0.065 m at the screen, 6.5 pixels of 0.01 m.
    const auto left = drawn(0, {0, -0.2f, 1}, {0, 0.2f, 1}), right = drawn(1, {0, -0.2f, 1}, {0, 0.2f, 1});
    ASSERT_FALSE(left.empty());
    ASSERT_FALSE(right.empty());
    EXPECT_NEAR(meanX(left) - meanX(right), 6.5, 1.0) << "the left eye sees it to the right";
    // 0.4 m long half-way to the eye: 0.8 m on the screen, 80 pixels (plus the thickness).
    int top = 240, bottom = 0;
    for (const auto& p : left) top = std::min(top, p.second), bottom = std::max(bottom, p.second);
    EXPECT_NEAR(bottom - top, 81, 2);
    // Behind the eye: nothing; partly behind: only the part in front.
    EXPECT_TRUE(drawn(0, {0, 0, 3}, {0.5f, 0, 4}).empty());
    EXPECT_FALSE(drawn(0, {0, 0, 3}, {0, 0, -1}).empty());
    // A frame at half the wall's resolution is drawn at its scale.
    Image half;
    half.width = 160;
    half.height = 120;
    half.rgb.assign(160 * 120 * 3, 0);
    drawWandRay(wall, head, 0, {0, 0, 0}, {1.6f, 0, 0}, half);
    EXPECT_NE(half.rgb[(size_t(60) * 160 + 120) * 3], 0);
}

}  // namespace
}  // namespace rtwall
