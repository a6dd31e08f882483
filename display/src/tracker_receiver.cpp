// The tracker's UDP datagrams on a thread of their own (standalone Asio), into a HeadTracker
// behind a small mutex that the frame loop takes only to copy the state.
#include <rtwall/tracking.h>

#include <asio.hpp>

#include <array>
#include <mutex>
#include <thread>

namespace rtwall {

struct TrackerReceiver::Impl {
    TrackingConfig config;
    std::function<void(const std::string&)> log;
    asio::io_context io;
    asio::ip::udp::socket socket{io};
    asio::ip::udp::endpoint sender;
    std::array<char, DTrackParser::kMaxPacket + 1> buffer{};  // one byte more: an oversized datagram is seen as one
    DTrackParser parser;  // used by the thread only
    mutable std::mutex mutex;
    HeadTracker tracker;
    int port = 0;
    uint64_t reported = 0;  // drops already logged (the first of each run of them)
    std::thread thread;

    explicit Impl(const TrackingConfig& c) : config(c), tracker(c) {}

    void receive() {
        socket.async_receive_from(asio::buffer(buffer), sender, [this](const asio::error_code& ec, size_t bytes) {
            if (ec == asio::error::operation_aborted) return;
            if (!ec) take(std::string_view(buffer.data(), bytes));
            receive();
        });
    }

    void take(std::string_view datagram) {
        const double now = seconds(std::chrono::steady_clock::now());
        std::optional<DTrackFrame> frame = parser.parse(datagram);
        std::string message;
        {
            std::lock_guard<std::mutex> lock(mutex);
            if (frame) {
                tracker.add(*frame, now);
            } else {
                tracker.countDropped(parser.error());
                // One line per 100 bad datagrams at most: a misconfigured sender must not flood the log.
                if (reported++ % 100 == 0) message = parser.error() + " (from " + sender.address().to_string() + ")";
            }
        }
        if (!message.empty() && log) log(message);
    }
};

TrackerReceiver::TrackerReceiver(const TrackingConfig& config, std::function<void(const std::string&)> log)
    : impl_(std::make_unique<Impl>(config)) {
    Impl& s = *impl_;
    s.log = std::move(log);
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
    s.thread = std::thread([&s] {
        try {
            s.io.run();
        } catch (const std::exception& e) {
            if (s.log) s.log(std::string("tracker receiver stopped: ") + e.what());
        }
    });
}

TrackerReceiver::~TrackerReceiver() {
    impl_->io.stop();
    impl_->thread.join();
}

int TrackerReceiver::port() const { return impl_->port; }

double TrackerReceiver::seconds(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(t.time_since_epoch()).count();
}

TrackerState TrackerReceiver::state(std::chrono::steady_clock::time_point now) const {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    return impl_->tracker.at(seconds(now));
}

TrackerState TrackerReceiver::state() const { return state(std::chrono::steady_clock::now()); }

}  // namespace rtwall
