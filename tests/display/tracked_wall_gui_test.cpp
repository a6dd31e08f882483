// End to end under this binary's Xvfb (gl_presenter_test.cpp starts it): the tracker simulator
// drives `rtwall run` on a tracked stereo wall in windows, and the images follow the head. The
// head starts at the config's viewer (the frames are the static render's bytes), moves away (the
// frames change) and comes back (the static bytes again).
#include "cli_util.h"
#include "display_test_util.h"
#include "test_util.h"

#include <rtwall/tracking.h>

#include <asio.hpp>

#include <atomic>
#include <chrono>
#include <thread>

namespace rtwall {
namespace {

const std::string kScene = test::sceneText("tracked_box");

// The shipped tracked wall's geometry and room, with 80x60 projectors and a port of its own.
std::string wallText(int port) {
    std::string t = R"([wall]
name = "tracked test wall"
vsync = false
[grid]
columns = 2
rows = 2
screen_width = 80
screen_height = 60
[stereo]
mode = "passive"
viewer = [0.0, 0.2, 2.5]
lower_left = [-1.6, -1.2, 0.0]
lower_right = [1.6, -1.2, 0.0]
upper_left = [-1.6, 1.2, 0.0]
)";
    if (port > 0)
        t += "[tracking]\nsource = \"dtrack://127.0.0.1:" + std::to_string(port) +
             "\"\nroom_rotate = [-90, 0, 0]\nroom_translate = [0, -1.5, 2.5]\ntimeout_ms = 60000\n";
    return t;
}

std::string runText(const std::filesystem::path& dir, const std::string& wall, int frames) {
    return "scene = \"scene.toml\"\nwall = \"" + wall + "\"\n[cluster]\nclients = 2\n[run]\nframes = " + std::to_string(frames) +
           "\nwrite_every = 1\norbit = 0.0\nout = \"" + (dir / ("frames-" + wall)).string() + "\"\n";
}

// A stereo frame is one master frame (both eyes in one scheduler pass); files are named by the
// master's number.
std::string fileOf(int shown) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", shown);
    return name;
}

int freeUdpPort() {
    asio::io_context io;
    asio::ip::udp::socket s(io, asio::ip::udp::endpoint(asio::ip::address_v4::loopback(), 0));
    return s.local_endpoint().port();
}

TEST(TrackedWall, TheSimulatorDrivesRtwallRunAndTheImagesFollowTheHead) {
    const auto dir = test::scratchDir();
    test::writeFile(dir / "scene.toml", kScene);
    // The static render with the viewer, headless.
    test::writeFile(dir / "static.toml", wallText(0));
    const test::CliResult ref = test::runCli(RTWALL_EXE, "run " + test::writeFile(dir / "static-run.toml", runText(dir, "static.toml", 1)).string() + " --headless", 300);
    ASSERT_EQ(ref.status, 0) << ref.output;
    const Image atViewer = readPng(dir / "frames-static.toml" / fileOf(1));

    const int port = freeUdpPort();
    test::writeFile(dir / "tracked.toml", wallText(port));
    const int frames = 200;
    const auto run = test::writeFile(dir / "tracked-run.toml", runText(dir, "tracked.toml", frames));
    // The simulator: the head at the viewer (tracker room: on the floor's origin + 1.7 m up), then
    // 0.5 m to the right, then back; switched when the wall has shown enough frames of each.
    std::atomic<int> phase{0};
    std::atomic<bool> done{false};
    std::thread sim([&] {
        DTrackSender sender(port);
        for (uint64_t n = 1; !done; ++n) {
            DTrackFrame f;
            f.frame = n;
            DTrackBody b;
            b.quality = 1;
            b.position = {phase == 1 ? 500.0 : 0.0, 0.0, 1700.0};
            f.bodies.push_back(b);
            sender.send(f);
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
    });
    std::thread conductor([&] {
        const auto out = dir / "frames-tracked.toml";
        auto shown = [&](int n) { return std::filesystem::exists(out / fileOf(n)); };
        for (int i = 0; i < 60000 && !done; ++i) {  // 300 s at most
            if (phase == 0 && shown(30)) phase = 1;
            if (phase == 1 && shown(100)) phase = 2;
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
    });
    const test::CliResult r = test::runCli(RTWALL_EXE, "run " + run.string() + " --frames " + std::to_string(frames), 120);
    done = true;
    sim.join();
    conductor.join();
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("8 windows"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("tracker: listening for ART DTrack on udp 127.0.0.1:" + std::to_string(port)), std::string::npos) << r.output;
    ASSERT_EQ(phase.load(), 2) << "the wall did not show enough frames" << r.output;

    // Frames of the left eye, as the wall showed them: the viewer's bytes, then others, then back.
    auto frame = [&](int n) { return readPng(dir / "frames-tracked.toml" / fileOf(n)); };
    EXPECT_EQ(frame(20).rgb, atViewer.rgb) << "the head at the viewer shows the static render";
    int moved = 0;
    for (int n = 31; n <= 100; ++n) moved += frame(n).rgb != atViewer.rgb;
    EXPECT_GT(moved, 35) << "the images follow the head 0.5 m to the right";
    EXPECT_EQ(frame(frames).rgb, atViewer.rgb) << "and come back with it";
}

}  // namespace
}  // namespace rtwall
