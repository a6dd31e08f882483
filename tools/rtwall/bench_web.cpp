// rtwall bench web (issue 31): what the operator console costs the wall, and what attackers
// cost it. One wall session (local clients on threads, the built-in knot field) with its console;
// its frame times measured quiet, with a page open (the event stream and the thumbnail at its
// rate), and under attack (a flood of requests, requests without the token, oversized bodies,
// screenshots, readers that never read), phase after phase in one run: ratios, not absolutes.
// With --nodes the wall is on two display nodes and the pictures come from them (and take a
// time of their own: picture_ms, screenshot_picture_ms).
#include "bench_cli.h"

#include <rtwall/web.h>

#include <httplib.h>

#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <optional>
#include <tuple>
#include <thread>

namespace rtwall::cli {

namespace {

struct WebBenchOptions {
    FILE* text = stdout;
    int frames = 60;
    int width = 640, height = 480;
    int clients = 2;
    int attackers = 4;
    bool nodes = false;  // the wall on two display nodes (threads of this process): the pictures come from them
};

double cpuSeconds(int who) {
    rusage u{};
    getrusage(who, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

toml::table stats(std::vector<double> ms) {
    std::sort(ms.begin(), ms.end());
    const double med = ms.empty() ? 0 : ms[ms.size() / 2];
    const double p95 = ms.empty() ? 0 : ms[std::min(ms.size() - 1, size_t(double(ms.size()) * 0.95))];
    return toml::table{{"median", med}, {"p95", p95}};
}

toml::table benchWeb(const WebBenchOptions& o) {
    RunConfig c = steppedRunConfig(std::filesystem::temp_directory_path() / "rtwall-bench-web", o.clients);
    c.scene = "builtin:knots";
    c.width = o.width;
    c.height = o.height;
    if (o.nodes) {
        // A 2x2 wall of the bench's size, its columns on display nodes "left" and "right".
        c.loadedWall = parseWallConfig("[wall]\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = " + std::to_string(o.width / 2) +
                                           "\nscreen_height = " + std::to_string(o.height / 2) +
                                           "\n[[node]]\nname = \"left\"\ncolumns = [0, 0]\n[[node]]\nname = \"right\"\n"
                                           "columns = [1, 1]\n[headless]\nwrite_every = 0\n",
                                       "bench web --nodes");
    }
    WallSession session(c);
    WebSettings w;
    w.enabled = true;
    w.port = 0;
    w.token = makeWebToken();
    std::unique_ptr<ConsoleBackend> backend = sessionBackend(session, w);
    WebApi api(*backend, w.token);
    WebServer server(api, w, [](const std::string&) {});
    const int port = server.port();
    for (int i = 0; i < 5; ++i) session.step();  // warm

    std::array<double, 3> cpuMark{};  // at the last phase's start: process CPU, attackers' CPU; its seconds
    std::atomic<double> attackerCpu{0};  // CPU seconds of the attacking threads, added as each ends
    auto measure = [&](const char* phase) {
        std::vector<double> ms;
        const double cpu0 = cpuSeconds(RUSAGE_SELF), attackers0 = attackerCpu;
        const auto start = std::chrono::steady_clock::now();
        for (int i = 0; i < o.frames; ++i) {
            const auto t0 = std::chrono::steady_clock::now();
            if (!session.step()) break;
            ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        }
        toml::table t = stats(ms);
        // The wall's and the server's CPU per second (the attackers' own threads taken out: on one
        // PC they steal the clients' cores too, which a remote attacker would not).
        cpuMark = {cpu0, attackers0, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
        if (o.text) std::fprintf(o.text, "%-9s frame %.1f ms median, %.1f ms p95 (%d frames)\n", phase, t["median"].value_or(0.0),
                                 t["p95"].value_or(0.0), o.frames);
        return t;
    };
    auto cpuOfPhase = [&](const char* phase, toml::table& into) {
        const double wall = cpuMark[2];
        const double cpu = cpuSeconds(RUSAGE_SELF) - cpuMark[0] - (attackerCpu - cpuMark[1]);
        into.insert("cpu_per_second", wall > 0 ? cpu / wall : 0.0);
        if (o.text) std::fprintf(o.text, "%-9s the wall and the server used %.2f CPU seconds a second\n", phase, wall > 0 ? cpu / wall : 0.0);
    };
    toml::table out;
    out.insert("frames", o.frames);
    out.insert("on_nodes", o.nodes);
    toml::table quietMs = measure("quiet");
    cpuOfPhase("quiet", quietMs);
    out.insert("quiet_ms", quietMs);
    if (o.nodes) {
        // The nodes' pictures, asked with the wall idle: a thumbnail's (480 wide, the console's)
        // and a screenshot's (every pixel), the ask to the last node's last part.
        for (const auto& [name, width, count] : {std::tuple{"picture_ms", 480, 20}, std::tuple{"screenshot_picture_ms", kNodePictureEveryPixel, 5}}) {
            std::vector<double> ms;
            for (int i = 0; i < count; ++i) {
                const auto t0 = std::chrono::steady_clock::now();
                const std::optional<NodePicture> pic = session.nodePicture(width, std::chrono::seconds(10));
                if (!pic || !pic->missing.empty() || pic->left.rgb.empty()) throw std::runtime_error("the display nodes gave no picture");
                ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
            }
            toml::table t = stats(ms);
            if (o.text) std::fprintf(o.text, "%-9s %s %.1f ms median, %.1f ms p95 (%d)\n", "nodes", name, t["median"].value_or(0.0),
                                     t["p95"].value_or(0.0), count);
            out.insert(name, t);
        }
    }

    std::atomic<bool> stop{false};
    std::atomic<uint64_t> requests{0}, answered{0}, refused{0};
    auto client = [&](bool token) {
        auto h = std::make_unique<httplib::Client>("127.0.0.1", port);
        h->set_read_timeout(10, 0);
        if (token) h->set_bearer_token_auth(w.token.c_str());
        return h;
    };
    // A page: the event stream and a thumbnail per status, as console.js does.
    std::vector<std::thread> threads;
    threads.emplace_back([&] {
        auto h = client(true);
        while (!stop) {
            ++requests;
            if (auto r = h->Get("/api/thumbnail.jpg"); r && r->status == 200) ++answered;
            if (auto r = h->Get("/api/status"); r && r->status == 200) ++answered;
            ++requests;
            std::this_thread::sleep_for(std::chrono::milliseconds(250));
        }
    });
    out.insert("page_ms", measure("page"));

    // Attackers, all at once: floods with and without the token, oversized bodies, screenshots.
    for (int a = 0; a < o.attackers; ++a)
        threads.emplace_back([&, a] {
            auto h = client(a % 4 != 1);
            const std::string oversized(5 << 20, '[');
            while (!stop) {
                httplib::Result r = a % 4 == 2 ? h->Post("/api/sections", oversized, "application/json")
                                  : a % 4 == 3 ? h->Get("/api/screenshot.png")
                                               : h->Get("/api/status");
                ++requests;
                if (r && r->status == 200) ++answered;
                else ++refused;
            }
            double mine = cpuSeconds(RUSAGE_THREAD), was = attackerCpu;
            while (!attackerCpu.compare_exchange_weak(was, was + mine)) {
            }
        });
    toml::table attacked = measure("attacked");
    stop = true;
    for (std::thread& t : threads) t.join();
    cpuOfPhase("attacked", attacked);
    out.insert("attacked_ms", attacked);
    out.insert("requests", int64_t(requests.load()));
    out.insert("answered", int64_t(answered.load()));
    out.insert("refused", int64_t(refused.load()));
    const double quiet = out["quiet_ms"]["median"].value_or(1.0);
    out.insert("page_ratio", out["page_ms"]["median"].value_or(0.0) / quiet);
    out.insert("attacked_ratio", out["attacked_ms"]["median"].value_or(0.0) / quiet);
    if (o.text)
        std::fprintf(o.text, "frame time with a page open %.2fx, under attack %.2fx the quiet one; %llu requests, %llu answered 200\n",
                     out["page_ratio"].value_or(0.0), out["attacked_ratio"].value_or(0.0), (unsigned long long)requests.load(),
                     (unsigned long long)answered.load());
    return out;
}

}  // namespace

void addBenchWeb(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<WebBenchOptions>(bench, "web", "What the operator console and attackers on it cost the wall's frames");
    cmd->add_option("--frames", o.frames, "Frames measured per phase (quiet, a page open, attacked)")->check(CLI::Range(5, 100000));
    addSizeOptions(cmd, o.width, o.height, 16, 8192);
    cmd->add_option("--clients", o.clients, "Local render clients (threads)")->check(CLI::Range(1, 64));
    cmd->add_flag("--nodes", o.nodes, "The wall on two display nodes (threads of this process): the thumbnail and screenshots come from them");
    cmd->add_option("--attackers", o.attackers, "Attacking connections (flood, no token, oversized bodies, screenshots, in turn)")
        ->check(CLI::Range(0, 64));
    callBenchmark(cmd, run, a, benchWeb);
}

}  // namespace rtwall::cli
