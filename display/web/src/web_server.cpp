// WebServer: cpp-httplib's server (HTTP, or HTTPS through its OpenSSL build) in front of WebApi.
// Its own threads only: a fixed pool serves requests, the render loop is never called from
// here (WebApi goes through the backend's snapshot and command queue). Limits: the body size
// (413), a token bucket per client address (429), read and write timeouts (a browser that stops
// reading is dropped when a write times out), keep-alive bounded, a few event streams at most.
#include <rtwall/web.h>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <mutex>
#include <thread>
#include <unordered_map>

namespace rtwall {

namespace {

bool loopback(const std::string& address) {
    return address == "127.0.0.1" || address == "::1" || address == "localhost" || address.starts_with("127.");
}

std::string oneLine(const std::string& why) { return nlohmann::json{{"error", why}}.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace); }

}  // namespace

struct WebServer::Impl {
    Impl(WebApi& a, const WebSettings& s, Limits l, std::function<void(const std::string&)> f)
        : api(a), settings(s), limits(l), log(std::move(f)) {}
    WebApi& api;
    WebSettings settings;
    Limits limits;
    std::function<void(const std::string&)> log;
    std::unique_ptr<httplib::Server> server;
    std::thread thread;
    int port = 0;
    std::atomic<uint64_t> refused{0};
    std::atomic<int> streams{0};
    std::atomic<bool> stopping{false};

    // Per client address: a token bucket of 2 x requestsPerSecond, refilled at requestsPerSecond.
    struct Bucket {
        double tokens = 0;
        std::chrono::steady_clock::time_point at;
    };
    std::mutex bucketsMutex;
    std::unordered_map<std::string, Bucket> buckets;
    bool admit(const std::string& address) {
        const auto now = std::chrono::steady_clock::now();
        std::lock_guard<std::mutex> lock(bucketsMutex);
        if (buckets.size() > 4096) buckets.clear();  // an attacker cycling addresses: forget them all
        auto [it, added] = buckets.try_emplace(address);
        Bucket& b = it->second;
        const double rate = limits.requestsPerSecond, burst = 2.0 * rate;
        b.tokens = added ? burst : std::min(burst, b.tokens + rate * std::chrono::duration<double>(now - b.at).count());
        b.at = now;
        if (b.tokens < 1) return false;
        b.tokens -= 1;
        return true;
    }

    std::chrono::steady_clock::time_point lastSaid{};
    std::mutex logMutex;
    void refuse(httplib::Response& res, int status, const std::string& why, const httplib::Request& req) {
        res.status = status;
        res.set_content(oneLine(why), "application/json");
        counted(status, why, req);
    }
    // A refusal counted, and said at most once every 10 s.
    void counted(int status, const std::string& why, const httplib::Request& req) {
        ++refused;
        std::lock_guard<std::mutex> lock(logMutex);
        const auto now = std::chrono::steady_clock::now();
        if (now - lastSaid > std::chrono::seconds(10)) {  // said, but a flood is not a flood of lines
            lastSaid = now;
            log("web: " + std::to_string(status) + " for " + req.remote_addr + " " + req.method + " " + req.path.substr(0, 80) + ": " + why +
                " (" + std::to_string(refused.load()) + " refused so far)");
        }
    }

    WebRequest request(const httplib::Request& req) const {
        WebRequest q;
        q.method = req.method;
        q.path = req.path;
        for (const auto& [k, v] : req.params) q.params[k] = v;
        q.body = req.body;
        q.authorization = req.get_header_value("Authorization");
        q.cookie = req.get_header_value("Cookie");
        return q;
    }

    void serve(const httplib::Request& req, httplib::Response& res) {
        if (!admit(req.remote_addr)) return refuse(res, 429, "too many requests: at most " + std::to_string(limits.requestsPerSecond) + " a second", req);
        const WebRequest q = request(req);
        if (req.path == "/api/events") return events(q, req, res);
        WebResponse r = api.handle(q);
        if (r.status == 401) counted(401, "no token or a wrong one", req);
        res.status = r.status;
        for (const auto& [k, v] : r.headers) res.set_header(k, v);
        res.set_content(std::move(r.body), r.contentType);
    }

    // Server-sent events: "status" with /api/status's JSON after each new frame, at most the
    // thumbnail rate; a comment every second when nothing is new (the browser's reconnect timer).
    void events(const WebRequest& q, const httplib::Request& req, httplib::Response& res) {
        if (req.method != "GET") return refuse(res, 405, "the event stream is GET /api/events", req);
        if (!api.authorized(q)) return refuse(res, 401, "a token is needed", req);
        if (++streams > limits.maxStreams) {
            --streams;
            return refuse(res, 503, "too many event streams open (" + std::to_string(limits.maxStreams) + ")", req);
        }
        auto last = std::make_shared<uint64_t>(0);
        auto version = std::make_shared<uint64_t>(api.backend().snapshot()->stateVersion);
        auto sent = std::make_shared<std::chrono::steady_clock::time_point>();
        const auto every = std::chrono::duration<double>(1.0 / std::max(0.1, settings.thumbnailsPerSecond));
        res.set_header("Cache-Control", "no-store");
        res.set_chunked_content_provider(
            "text/event-stream",
            [this, last, version, sent, every](size_t, httplib::DataSink& sink) {
                if (stopping) return false;
                const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(every - (std::chrono::steady_clock::now() - *sent));
                if (wait.count() > 0) std::this_thread::sleep_for(std::min(wait, std::chrono::milliseconds(1000)));
                const std::shared_ptr<const ConsoleSnapshot> snap = api.backend().waitNewer(*last, std::chrono::milliseconds(1000));
                std::string chunk;
                if (snap->steps > *last) {
                    WebRequest s;
                    s.method = "GET";
                    s.path = "/api/status";
                    s.authorization = "Bearer " + api.token();
                    chunk = "event: status\ndata: " + api.handle(s).body + "\n\n";
                    if (snap->stateVersion != *version) {  // parts, sections, bookmarks, moves or measurements changed
                        chunk += "event: state\ndata: {\"version\": " + std::to_string(snap->stateVersion) + "}\n\n";
                        *version = snap->stateVersion;
                    }
                    *last = snap->steps;
                    *sent = std::chrono::steady_clock::now();
                } else {
                    chunk = ": nothing new\n\n";
                }
                return sink.write(chunk.data(), chunk.size());  // false (a write timed out, the client left): dropped
            },
            [this](bool) { --streams; });
    }
};

void checkWebSettings(const WebSettings& w) {
    const bool tls = !w.certificate.empty() || !w.key.empty();
    if (!loopback(w.address) && !tls && !w.insecure)
        throw InputError("web: " + w.address + " is not loopback: give [web] certificate and key (TLS), or --web-insecure");
    if (tls && (w.certificate.empty() || w.key.empty())) throw InputError("web: give both a certificate and a key (TLS), or neither");
    if (tls)
        for (const std::filesystem::path& f : {w.certificate, w.key})
            if (!std::filesystem::is_regular_file(f)) throw InputError("web: " + f.string() + ": no such file (TLS)");
}

WebServer::WebServer(WebApi& api, const WebSettings& settings, Limits limits, std::function<void(const std::string&)> log)
    : impl_(std::make_unique<Impl>(api, settings, limits, std::move(log))) {
    Impl& s = *impl_;
    checkWebSettings(settings);
    const bool tls = !settings.certificate.empty();
    if (tls) {
        s.server = std::make_unique<httplib::SSLServer>(settings.certificate.c_str(), settings.key.c_str());
        if (!s.server->is_valid()) throw InputError("web: " + settings.certificate.string() + ", " + settings.key.string() + ": not a usable certificate and key (PEM)");
    } else {
        s.server = std::make_unique<httplib::Server>();
    }
    httplib::Server& h = *s.server;
    const int threads = limits.threads;
    h.new_task_queue = [threads] { return new httplib::ThreadPool(size_t(threads)); };
    h.set_payload_max_length(limits.maxBody);
    h.set_read_timeout(limits.readTimeout);
    h.set_write_timeout(limits.writeTimeout);
    h.set_keep_alive_max_count(100);
    h.set_keep_alive_timeout(2);
    // SO_REUSEADDR only: httplib's default adds SO_REUSEPORT, with which a second wall on the
    // same port would silently share it and take half the requests.
    h.set_socket_options([](socket_t sock) {
        int yes = 1;
        setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    auto serve = [&s](const httplib::Request& req, httplib::Response& res) { s.serve(req, res); };
    h.Get(".*", serve);
    h.Post(".*", serve);
    h.Delete(".*", serve);
    h.set_error_handler([&s](const httplib::Request& req, httplib::Response& res) {
        if (!res.body.empty()) return;
        if (res.status == 413) {
            ++s.refused;
            res.set_content(oneLine("the body is larger than " + std::to_string(s.limits.maxBody) + " bytes"), "application/json");
        } else {
            res.set_content(oneLine("bad request: " + req.method.substr(0, 10) + " " + req.path.substr(0, 80)), "application/json");
        }
    });
    h.set_exception_handler([&s](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        std::string why = "internal error";
        try {
            std::rethrow_exception(ep);
        } catch (const std::exception& e) {
            why += std::string(": ") + e.what();
        } catch (...) {
        }
        res.status = 500;
        res.set_content(oneLine(why), "application/json");
        s.log("web: " + why);
    });
    if (settings.port == 0) s.port = h.bind_to_any_port(settings.address);
    else s.port = h.bind_to_port(settings.address, settings.port) ? settings.port : -1;
    if (s.port <= 0)
        throw InputError("web: cannot listen on " + settings.address + ":" + std::to_string(settings.port) +
                         " (in use, or not an address of this machine)");
    s.thread = std::thread([&h] { h.listen_after_bind(); });
    // Until it listens: a stop() before that would be missed and the join would wait forever.
    for (int i = 0; i < 5000 && !h.is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (!loopback(settings.address) && !tls)
        s.log("web: WARNING: serving " + settings.address + " without TLS (--web-insecure): the token travels in clear text");
}

WebServer::~WebServer() {
    impl_->stopping = true;
    impl_->server->stop();
    if (impl_->thread.joinable()) impl_->thread.join();
}

int WebServer::port() const { return impl_->port; }

std::string WebServer::url() const {
    const WebSettings& w = impl_->settings;
    const std::string host = w.address.find(':') != std::string::npos ? "[" + w.address + "]" : w.address;
    return std::string(w.certificate.empty() ? "http" : "https") + "://" + host + ":" + std::to_string(impl_->port) +
           "/?token=" + impl_->api.token();
}

uint64_t WebServer::refused() const { return impl_->refused; }

}  // namespace rtwall
