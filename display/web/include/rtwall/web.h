// rtwall web: the operator console (issue 31, docs/web-console.md), the one public header.
//
// An HTTP server inside the master (`rtwall run --web`, the run config's [web]) serves a static
// page (display/web/site/, built into the binary) and a JSON API under /api/ that the page uses
// and scripts call. Three layers, each testable alone:
// - WebApi: a request in, a response out, no sockets: authentication, routing, JSON parsing and
//   every check of what a request asks. Its fuzz target drives it with a ConsoleBackend of its own.
// - ConsoleBackend: what the API reads and changes. The session's (sessionBackend) reads a
//   snapshot taken after each frame (WallSession::addStepObserver: the display pipeline's tap)
//   and changes the scene only through WallSession::post, the command queue the keys' and the
//   wand's changes share: one scene state, every change a differential update.
// - WebServer: cpp-httplib's server (HTTP or HTTPS), with the request size limit, timeouts, the
//   per-client rate limit and the live event stream; the render loop never waits on it.
#pragma once

#include <rtwall/wall.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rtwall {

// A request without its transport.
struct WebRequest {
    std::string method;  // GET, POST, DELETE
    std::string path;    // "/api/parts/3", without the query
    std::map<std::string, std::string> params;  // the query's
    std::string body;
    std::string authorization;  // the Authorization header ("Bearer TOKEN")
    std::string cookie;         // the Cookie header
};
struct WebResponse {
    int status = 200;
    std::string contentType = "application/json";
    std::string body;
    std::vector<std::pair<std::string, std::string>> headers;
};

// The assembly's tree as the console lists it: the scene's parts, or for a scene without any
// (a scene file's own instances) one entry per mesh name its instances have. Fixed for a run.
struct ConsolePart {
    std::string name, path;  // path: the pattern the part view is given (SceneDesc::partPath; a mesh's name)
    int parent = -1;         // index into the list
    std::vector<uint32_t> instances;  // every instance in it, its sub-parts' included
};
std::vector<ConsolePart> consoleParts(const SceneDesc& scene);

// What the console reads: taken on the session's thread after each step.
struct ConsoleSnapshot {
    uint32_t frame = 0;        // the newest presented frame's number
    uint64_t steps = 0;        // frames stepped
    double fps = 0;            // median of the last 10 steps
    double frameMs = 0;        // the last step's
    double linkMegabytesPerSecond = 0;  // tile bytes received, over the last 10 steps
    double tileLatencyMs = 0;  // the last frame's mean, assignment to result
    double affinity = 0;       // share of the last frame's tiles rendered by the tile's client of the frame before
    uint64_t tilesStolen = 0;  // in the last frame
    struct Client {
        uint32_t id = 0;
        uint64_t tiles = 0;
        double busy = 0;       // render time / frame time
        double megabytes = 0;
    };
    std::vector<Client> clients;
    std::string tracker;       // one line; empty: the wall has no tracking
    std::string operatingPoint;
    int wallWidth = 0, wallHeight = 0;
    bool stereo = false;
    bool onNodes = false;      // the pixels are on display nodes (the pictures come from them)
    bool flying = false;
    // Grows whenever the parts' visibility, sections, bookmarks, moved instances or measurements
    // change (by the console, the keys, the wand or --watch): the event stream's "state" event.
    uint64_t stateVersion = 0;
    std::array<double, 3> origin{};  // the scene's rebased origin (API coordinates are the file's)
    SessionState session;      // camera, bookmarks, sections, part view, moved instances, measurements
    // Per instance; shared by the snapshots of one scene state (it is copied only when that changed).
    std::shared_ptr<const std::vector<Visibility>> visibility = std::make_shared<const std::vector<Visibility>>();
};

// What the API reads and changes. Thread-safe: called from the server's threads.
class ConsoleBackend {
public:
    virtual ~ConsoleBackend() = default;
    virtual std::shared_ptr<const ConsoleSnapshot> snapshot() = 0;  // never null
    virtual const std::vector<ConsolePart>& parts() = 0;
    virtual const SceneDesc* scene() = 0;  // for checking patterns and ids: the instances' parts and meshes (fixed); may be null
    // Runs `command` on the session's thread at its next step; false when that did not happen
    // within `timeout` (the command may still run later: it must own what it touches).
    virtual bool run(std::function<void(WallSession&)> command, std::chrono::milliseconds timeout) = 0;
    // The live thumbnail (JPEG; both eyes side by side on a stereo wall), and the frame it shows;
    // null before the first one or where there are no pixels. Asking keeps thumbnails coming.
    virtual std::shared_ptr<const std::vector<uint8_t>> thumbnail(uint32_t* frame = nullptr) = 0;
    // The wall's frame at its full resolution (eye 0 left or mono, 1 right); nothing within the
    // timeout, or where it cannot be had (then `why` says why, in a few words).
    virtual std::optional<Image> screenshot(int eye, std::chrono::milliseconds timeout, std::string* why = nullptr) = 0;
    // Blocks until a snapshot newer than `frame` is published or the timeout passes (the event stream).
    virtual std::shared_ptr<const ConsoleSnapshot> waitNewer(uint64_t steps, std::chrono::milliseconds timeout) = 0;
};

// The session's backend: publishes a snapshot after every step (WallSession::addStepObserver)
// and a thumbnail at most `settings.thumbnailsPerSecond` while someone asked in the last 5 s.
// Construct it on the session's thread before the loop; it must outlive the server using it and
// the session must outlive it.
std::unique_ptr<ConsoleBackend> sessionBackend(WallSession& session, const WebSettings& settings);

// The API and the page (docs/web-console.md lists every route and its answers).
class WebApi {
public:
    // commandTimeout: how long a change waits for the wall's next step; screenshotInterval: the
    // least time between two full-resolution screenshots (a quicker one waits).
    WebApi(ConsoleBackend& backend, std::string token, std::chrono::milliseconds commandTimeout = std::chrono::milliseconds(5000),
           std::chrono::milliseconds screenshotInterval = std::chrono::milliseconds(500));
    WebResponse handle(const WebRequest& request);
    // Whether the request carries the token (Bearer or the cookie); constant time in the token.
    bool authorized(const WebRequest& request) const;
    const std::string& token() const { return token_; }
    ConsoleBackend& backend() { return backend_; }

private:
    ConsoleBackend& backend_;
    std::string token_;
    std::chrono::milliseconds timeout_, shotInterval_;
    // Full-resolution screenshots: one at a time (429 for another meanwhile), at most two a
    // second (a quick second one waits): a PNG of the wall costs CPU the local clients need.
    std::atomic<bool> shooting_{false};
    std::atomic<int64_t> lastShot_{0};  // steady clock, nanoseconds
};

// A random token (32 characters of [A-Za-z0-9] from std::random_device).
std::string makeWebToken();
// The page's files (display/web/site/, built in): path ("/index.html") to type and contents.
struct SiteFile {
    const char* type;
    std::string_view body;
};
const SiteFile* siteFile(const std::string& path);

// What a WebServer would refuse, before anything starts: a non-loopback address without TLS or
// `insecure`, half a TLS pair, TLS files that are not there. One-line InputError.
void checkWebSettings(const WebSettings& settings);

// The server. Throws InputError (one line) for a bind it refuses (another address than loopback
// without TLS or `insecure`), a TLS file it cannot read, or an address it cannot bind.
class WebServer {
public:
    struct Limits {
        size_t maxBody = 4 << 20;          // bytes (413 above)
        int requestsPerSecond = 50;        // per client address, with a burst of twice that (429 above)
        int threads = 8;                   // requests served at once (more wait in the queue)
        int maxStreams = 4;                // event streams open at once (503 above)
        std::chrono::milliseconds readTimeout{5000}, writeTimeout{3000};  // a client that stops reading is dropped
    };
    WebServer(WebApi& api, const WebSettings& settings, Limits limits, std::function<void(const std::string&)> log);
    WebServer(WebApi& api, const WebSettings& settings, std::function<void(const std::string&)> log)
        : WebServer(api, settings, Limits{}, std::move(log)) {}
    ~WebServer();
    int port() const;
    std::string url() const;  // the page, with the token: opening it once sets the cookie
    uint64_t refused() const;  // requests answered 401, 413 or 429, and streams refused

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace rtwall
