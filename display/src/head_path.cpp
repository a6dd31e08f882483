// Head paths (the tracker simulator's input) and sending DTrack datagrams on loopback.
#include <rtwall/toml_reader.h>
#include <rtwall/tracking.h>

#include <asio.hpp>

#include <cmath>
#include <numbers>
#include <thread>

namespace rtwall {

HeadPath readHeadPath(const std::filesystem::path& file) {
    using namespace toml_reader;
    const toml::table root = parseFile(file);
    Reader top(file, root, "");
    HeadPath path;
    path.body = top.integer("body", 0, 0, 1'000'000);
    forEachTable(top, file, "key", [&](Reader& r, const toml::table&) {
        HeadKey k;
        k.time = r.number("time", 0.0, 0.0, 1e6);
        if (!r.has("time")) r.fail(nullptr, "missing required key 'time'");
        if (!path.keys.empty() && !(k.time > path.keys.back().time))
            r.fail(r.find("time"), "key 'time': must be later than the key before (" + std::to_string(path.keys.back().time) + " s)");
        k.position = r.vec3d("position", {}, true);
        for (double v : k.position)
            if (std::fabs(v) > 1e7) r.fail(r.find("position"), "key 'position': millimetres within 10 km");
        k.rotate = r.vec3d("rotate", {0, 0, 0});
        for (double a : k.rotate)
            if (std::fabs(a) > 360) r.fail(r.find("rotate"), "key 'rotate': angles are degrees in [-360, 360]");
        r.finish();
        path.keys.push_back(k);
    });
    top.finish();
    if (path.keys.empty()) top.fail(nullptr, "a head path needs at least one [[key]]");
    return path;
}

namespace {
std::array<double, 9> rotationOf(const std::array<double, 3>& degrees) {
    TrackingConfig c;  // the room transform's rotation is the same composition: x, then y, then z
    c.roomRotate = degrees;
    return roomTransform(c).rotation;
}
}  // namespace

DTrackFrame headPathFrame(const HeadPath& path, double time, uint64_t frame) {
    DTrackFrame f;
    f.frame = frame;
    f.timestamp = std::fmod(std::max(0.0, time), 86400.0);
    DTrackBody b;
    b.id = path.body;
    b.quality = 1.0;
    const std::vector<HeadKey>& k = path.keys;
    HeadKey at = k.back();
    if (time <= k.front().time) {
        at = k.front();
    } else {
        for (size_t i = 1; i < k.size(); ++i)
            if (time <= k[i].time) {
                const double u = (time - k[i - 1].time) / (k[i].time - k[i - 1].time);
                for (int j = 0; j < 3; ++j) {
                    at.position[size_t(j)] = k[i - 1].position[size_t(j)] + u * (k[i].position[size_t(j)] - k[i - 1].position[size_t(j)]);
                    at.rotate[size_t(j)] = k[i - 1].rotate[size_t(j)] + u * (k[i].rotate[size_t(j)] - k[i - 1].rotate[size_t(j)]);
                }
                break;
            }
    }
    b.position = at.position;
    b.rotation = rotationOf(at.rotate);
    f.bodies.push_back(b);
    return f;
}

struct DTrackSender::Impl {
    asio::io_context io;
    asio::ip::udp::socket socket{io, asio::ip::udp::v4()};
    asio::ip::udp::endpoint to;
};

DTrackSender::DTrackSender(int port) : impl_(std::make_unique<Impl>()) {
    if (port < 1 || port > 65535) throw InputError("tracker simulator: port " + std::to_string(port) + " is not in [1, 65535]");
    // Loopback only: the simulator must never reach a real wall's or anybody else's network.
    impl_->to = asio::ip::udp::endpoint(asio::ip::address_v4::loopback(), asio::ip::port_type(port));
}

DTrackSender::~DTrackSender() = default;

void DTrackSender::send(std::string_view datagram) {
    asio::error_code ec;  // nobody listening (ICMP port unreachable) is not the sender's problem
    impl_->socket.send_to(asio::buffer(datagram.data(), datagram.size()), impl_->to, 0, ec);
}

void DTrackSender::send(const DTrackFrame& frame) { send(writeDTrackPacket(frame)); }

uint64_t playHeadPath(const HeadPath& path, int port, double rate, double seconds, const std::atomic<bool>* stop) {
    if (!(rate > 0 && rate <= 10'000)) throw InputError("tracker simulator: rate " + std::to_string(rate) + " is not in (0, 10000] Hz");
    DTrackSender sender(port);
    const auto start = std::chrono::steady_clock::now();
    const double length = path.duration();
    uint64_t sent = 0;
    for (;; ++sent) {
        const double t = double(sent) / rate;
        if (t > seconds || (stop && stop->load())) break;
        std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(t)));
        DTrackFrame f = headPathFrame(path, length > 0 ? std::fmod(t, length + 1.0 / rate) : 0.0, sent + 1);
        // Stamped as DTrack stamps its frames: the time of day (UTC) of the measurement, on this
        // PC's clock, so the wall sees a tracker whose clock agrees with its own.
        f.timestamp = std::fmod(std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(), 86400.0);
        sender.send(f);
    }
    return sent;
}

}  // namespace rtwall
