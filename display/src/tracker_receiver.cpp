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

    void take(std::string_view datagram) {
        const double now = seconds(std::chrono::steady_clock::now());
        std::optional<DTrackFrame> frame = parser.parse(datagram);
        std::lock_guard<std::mutex> lock(mutex);
        if (frame) {
            tracker.add(*frame, now);
        } else {
            tracker.countDropped(parser.error());
            // One line per 100 bad datagrams at most: a misconfigured sender must not flood the log.
            if (reported++ % 100 == 0) say(parser.error() + " (from " + sender.address().to_string() + ")");
        }
    }

    // Under `mutex`.
    void say(std::string line) {
        if (messages.size() < 16) messages.push_back(std::move(line));
        else ++lostMessages;
    }
};

TrackerReceiver::TrackerReceiver(const TrackingConfig& config) : impl_(std::make_unique<Impl>(config)) {
    Impl& s = *impl_;
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
            std::lock_guard<std::mutex> lock(s.mutex);
            s.say(std::string("tracker receiver stopped: ") + e.what());
        }
    });
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
