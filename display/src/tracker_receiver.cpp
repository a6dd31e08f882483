// The tracker's UDP datagrams on a thread of their own (standalone Asio), into a HeadTracker
// behind a small mutex that the frame loop takes only to copy the state.
#include <rtwall/tracking.h>

#include <asio.hpp>

#include <array>
#include <cmath>
#include <mutex>
#include <thread>

namespace rtwall {

struct TrackerReceiver::Impl {
    TrackingConfig config;
    asio::io_context io;
    asio::ip::udp::socket socket{io};
    asio::ip::udp::endpoint sender;
    std::array<char, DTrackParser::kMaxPacket + 1> buffer{};  // one byte more: an oversized datagram is seen as one
    DTrackParser parser;  // used by the thread only
    mutable std::mutex mutex;
    HeadTracker tracker;
    int port = 0;
    uint64_t reported = 0;  // drops already logged (the first of each run of them)
    std::vector<std::string> messages;  // for the owner's thread (takeMessages), under `mutex`
    uint64_t lostMessages = 0;
    std::thread thread;

    explicit Impl(const TrackingConfig& c) : config(c), tracker(c) {}

    void receive() {
        socket.async_receive_from(asio::buffer(buffer), sender, [this](const asio::error_code& ec, size_t bytes) {
            if (ec == asio::error::operation_aborted) return;
            if (!ec) take(std::string_view(buffer.data(), bytes));
            receive();
        });
    }

    // Seconds since 00:00 UTC now: what the tracker's timestamps count.
    static double utcOfDay() {
        return std::fmod(std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(), 86400.0);
    }

    void take(std::string_view datagram) {
        const double now = seconds(std::chrono::steady_clock::now()), utc = utcOfDay();
        std::optional<DTrackFrame> frame = parser.parse(datagram);
        std::lock_guard<std::mutex> lock(mutex);
        if (frame) {
            tracker.add(*frame, now, utc);
        } else {
            tracker.countDropped(parser.error());
            // One line per 100 bad datagrams at most: a misconfigured sender must not flood the log.
            if (reported++ % 100 == 0) say(parser.error() + " (from " + sender.address().to_string() + ")");
        }
    }

    // VRPN: a TCP session to the server (reconnected a second after it breaks), and the UDP
    // port it is offered for the reports.
    asio::ip::tcp::resolver resolver{io};
    asio::ip::tcp::socket tcp{io};
    asio::steady_timer retry{io};
    std::optional<VrpnParser> vrpn;
    std::array<char, 65536> tcpBuffer{};
    std::string outgoing;
    std::string lastConnectError;  // said once, not at every retry

    void connectVrpn() {
        resolver.async_resolve(config.address, std::to_string(config.port), [this](const asio::error_code& ec, asio::ip::tcp::resolver::results_type r) {
            if (ec == asio::error::operation_aborted) return;
            if (ec) return retryVrpn("cannot resolve '" + config.address + "': " + ec.message());
            asio::async_connect(tcp, r, [this](const asio::error_code& e, const asio::ip::tcp::endpoint&) {
                if (e == asio::error::operation_aborted) return;
                if (e) return retryVrpn("cannot connect: " + e.message());
                startVrpn();
            });
        });
    }

    void retryVrpn(const std::string& why) {
        asio::error_code ignored;
        tcp.close(ignored);
        socket.close(ignored);
        vrpn.reset();
        const std::string line = "tracker: VRPN " + config.server + ": " + why + " (trying again every second)";
        if (line != lastConnectError) {
            std::lock_guard<std::mutex> lock(mutex);
            say(line);
        }
        lastConnectError = line;
        retry.expires_after(std::chrono::seconds(1));
        retry.async_wait([this](const asio::error_code& ec) {
            if (!ec) connectVrpn();
        });
    }

    void startVrpn() {
        asio::error_code ec;
        tcp.set_option(asio::ip::tcp::no_delay(true), ec);
        vrpn.emplace(config);
        lastConnectError.clear();
        {
            std::lock_guard<std::mutex> lock(mutex);
            say("tracker: connected to VRPN " + config.server);
        }
        // Our cookie, then a UDP port offered for the reports (VRPN sends its trackers' reports
        // by UDP where it can), on the address the server reached us at.
        outgoing = vrpnCookie();
        const asio::ip::address local = tcp.local_endpoint(ec).address();
        if (!ec) socket.open(local.is_v4() ? asio::ip::udp::v4() : asio::ip::udp::v6(), ec);
        if (!ec) socket.bind(asio::ip::udp::endpoint(local, 0), ec);
        if (!ec) {
            const std::string host = local.to_string();
            outgoing += vrpnMessage(socket.local_endpoint().port(), -3, 0, std::string_view(host.c_str(), host.size() + 1));
            receiveVrpnUdp();
        }
        asio::async_write(tcp, asio::buffer(outgoing), [this](const asio::error_code& e, size_t) {
            if (e && e != asio::error::operation_aborted) retryVrpn("cannot write: " + e.message());
        });
        readVrpn();
    }

    void readVrpn() {
        tcp.async_read_some(asio::buffer(tcpBuffer), [this](const asio::error_code& ec, size_t bytes) {
            if (ec == asio::error::operation_aborted || !vrpn) return;
            if (ec) return retryVrpn(ec == asio::error::eof ? "the server closed the connection" : "connection lost: " + ec.message());
            takeVrpn(std::string_view(tcpBuffer.data(), bytes), false);
            if (vrpn->failed()) return retryVrpn(vrpn->error().substr(std::string("vrpn session: ").size()));
            readVrpn();
        });
    }

    void receiveVrpnUdp() {
        socket.async_receive_from(asio::buffer(buffer), sender, [this](const asio::error_code& ec, size_t bytes) {
            if (ec == asio::error::operation_aborted || !vrpn) return;
            if (!ec) takeVrpn(std::string_view(buffer.data(), bytes), true);
            receiveVrpnUdp();
        });
    }

    void takeVrpn(std::string_view bytes, bool datagram) {
        const double now = seconds(std::chrono::steady_clock::now()), utc = utcOfDay();
        std::vector<DTrackFrame> frames;
        const uint64_t droppedBefore = vrpn->dropped();
        if (datagram) vrpn->datagram(bytes, frames);
        else vrpn->feed(bytes, frames);
        std::lock_guard<std::mutex> lock(mutex);
        for (const DTrackFrame& f : frames) tracker.add(f, now, utc);
        for (uint64_t i = droppedBefore; i < vrpn->dropped(); ++i) {
            tracker.countDropped(vrpn->error());
            if (reported++ % 100 == 0) say(vrpn->error());
        }
    }

    // Under `mutex`.
    void say(std::string line) {
        if (messages.size() < 16) messages.push_back(std::move(line));
        else ++lostMessages;
    }
    // The receiving thread: runs the socket's handlers until stopped; an error ends it with a line.
    void start() {
        thread = std::thread([this] {
            try {
                io.run();
            } catch (const std::exception& e) {
                std::lock_guard<std::mutex> lock(mutex);
                say(std::string("tracker receiver stopped: ") + e.what());
            }
        });
    }
};

TrackerReceiver::TrackerReceiver(const TrackingConfig& config) : impl_(std::make_unique<Impl>(config)) {
    Impl& s = *impl_;
    if (config.kind == TrackingSource::Vrpn) {
        s.port = config.port;
        s.connectVrpn();
        s.start();
        return;
    }
    asio::error_code ec;
    const asio::ip::address address = asio::ip::make_address(config.address, ec);
    if (!ec) {
        const asio::ip::udp::endpoint endpoint(address, asio::ip::port_type(config.port));
        s.socket.open(endpoint.protocol(), ec);
        if (!ec) s.socket.bind(endpoint, ec);
    }
    if (ec) throw InputError("[tracking]: source '" + config.source + "': cannot listen on UDP " + config.address + ":" +
                             std::to_string(config.port) + ": " + ec.message());
    s.port = s.socket.local_endpoint().port();
    s.receive();
    s.start();
}

TrackerReceiver::~TrackerReceiver() {
    impl_->io.stop();
    impl_->thread.join();
}

int TrackerReceiver::port() const { return impl_->port; }

std::vector<std::string> TrackerReceiver::takeMessages() {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    std::vector<std::string> out = std::move(impl_->messages);
    impl_->messages.clear();
    if (impl_->lostMessages > 0)
        out.push_back("tracker: " + std::to_string(impl_->lostMessages) + " more lines about dropped datagrams not shown");
    impl_->lostMessages = 0;
    return out;
}

double TrackerReceiver::seconds(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(t.time_since_epoch()).count();
}

TrackerState TrackerReceiver::state(std::chrono::steady_clock::time_point now) const {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->tracker.at(seconds(now));
}

TrackerState TrackerReceiver::state() const { return state(std::chrono::steady_clock::now()); }

}  // namespace rtwall
