// libFuzzer target for the VRPN client's parser (display/src/vrpn.cpp): every byte a VRPN server,
// or anybody who answers on its address, can send to the wall over TCP or UDP.
//
// The input is read three ways: as the TCP stream in one piece, as the same stream split where
// its first byte says (the frames must be the same), and as a UDP datagram. Besides the
// sanitizers it checks that a dropped message or a broken stream says why in one line starting
// with "vrpn message: " or "vrpn session: ", that every frame's numbers are finite with unit
// rotations, and that nothing is read after the stream broke.
//
// Build with CMake: -DCMAKE_CXX_COMPILER=clang++ -DRTWALL_FUZZ=ON, target fuzz_vrpn. Run (new
// inputs go to the first directory, the committed seeds are only read):
//   build-fuzz/tests/fuzz/fuzz_vrpn -max_total_time=120 build-fuzz/tests/fuzz/corpus/vrpn tests/fuzz/corpus/vrpn
#include <rtwall/tracking.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace rtwall;

namespace {
[[noreturn]] void finding(const char* what, const std::string& detail) {
    std::fprintf(stderr, "fuzz_vrpn: %s: %s\n", what, detail.c_str());
    std::abort();
}

TrackingConfig config() {
    TrackingConfig c;
    c.kind = TrackingSource::Vrpn;
    c.device = c.buttonDevice = c.analogDevice = "Tracker0";
    c.headBody = 0;
    c.flystick = 1;
    c.roomScale = 1;
    return c;
}

void checkLine(const VrpnParser& p) {
    const std::string& e = p.error();
    if (e.empty()) return;
    if ((e.rfind("vrpn message: ", 0) != 0 && e.rfind("vrpn session: ", 0) != 0) || e.find('\n') != std::string::npos ||
        e.find('\r') != std::string::npos)
        finding("a dropped message's reason is not one 'vrpn ...: ' line", e);
    if (p.failed() && e.rfind("vrpn session: ", 0) != 0) finding("a broken session is not said as one", e);
}

void checkFrames(const std::vector<DTrackFrame>& frames) {
    auto body = [](const DTrackBody& b) {
        for (double v : b.position)
            if (!std::isfinite(v)) finding("a position is not finite", std::to_string(v));
        if (b.quality < 0) return;
        for (int c = 0; c < 3; ++c) {
            double n = 0;
            for (int r = 0; r < 3; ++r) n += b.rotation[size_t(3 * r + c)] * b.rotation[size_t(3 * r + c)];
            if (!(std::fabs(n - 1) < 1e-9)) finding("a rotation's column is not a unit vector", std::to_string(n));
        }
    };
    for (const DTrackFrame& f : frames) {
        for (const DTrackBody& b : f.bodies) body(b);
        for (const DTrackFlystick& s : f.flysticks) {
            body(s.pose);
            if (s.buttons.size() > size_t(VrpnParser::kMaxChannels) || s.controllers.size() > size_t(VrpnParser::kMaxChannels))
                finding("more buttons or channels than a device has", std::to_string(s.buttons.size()));
            for (double v : s.controllers)
                if (!(v >= -1 && v <= 1)) finding("a controller outside [-1, 1]", std::to_string(v));
        }
    }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    VrpnParser whole(config());
    std::vector<DTrackFrame> a;
    whole.feed(bytes, a);
    checkLine(whole);
    checkFrames(a);

    VrpnParser split(config());
    std::vector<DTrackFrame> b;
    const size_t cut = size ? data[0] % (size + 1) : 0;
    split.feed(bytes.substr(0, cut), b);
    split.feed(bytes.substr(cut), b);
    if (a != b || whole.failed() != split.failed() || whole.dropped() != split.dropped())
        finding("a split stream reads differently", std::to_string(cut));
    if (whole.failed()) {
        const size_t before = a.size();
        whole.feed(bytes, a);
        if (a.size() != before) finding("frames read after the stream broke", whole.error());
    }

    // As a UDP datagram, after a handshake that names the usual sender and types.
    VrpnParser udp(config());
    std::vector<DTrackFrame> c;
    udp.feed(vrpnCookie() + vrpnName(0, -1, "Tracker0") + vrpnName(0, -2, "vrpn_Tracker Pos_Quat") +
                 vrpnName(1, -2, "vrpn_Button Change") + vrpnName(2, -2, "vrpn_Button States") + vrpnName(3, -2, "vrpn_Analog Channel"),
             c);
    udp.datagram(bytes, c);
    checkLine(udp);
    checkFrames(c);
    if (udp.failed()) finding("a datagram broke the TCP session", udp.error());
    return 0;
}
