// rtwall bench faults: what a fault costs. With local client processes on loopback:
//  - a client killed (SIGKILL) or frozen (SIGSTOP) a third into a frame: time from the fault to
//    the master noticing, and from then to the frame completing;
//  - the frame time while that client is missing, against the frame time with it;
//  - for the frozen one, the time from SIGCONT until it is back (rejoin: reconnect and proof);
//  - the throughput cost of CURVE against no encryption (replaying clients, so the master and
//    the link are what is measured).
#include "bench.h"
#include "bench_util.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <toml++/toml.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <future>
#include <cstdio>
#include <filesystem>
#include <thread>

namespace rtwall::bench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

double medianFrameTime(Master& master, int frames) {
    std::vector<double> t;
    for (int i = 0; i < frames; ++i) t.push_back(secondsOf([&] { master.renderFrame(); }));
    return median(t);
}

toml::table faultRun(const SceneDesc& desc, int signal, int clients, int frames, int timeoutMs) {
    ClusterSettings cs;
    cs.async = false;
    cs.heartbeatMs = std::max(10, timeoutMs / 8);
    cs.timeoutMs = timeoutMs;
    Master master(desc, cs);
    LocalClients procs(clients, master.endpoint(), 1);
    if (!master.waitForClients(clients, 120'000)) throw InputError("local clients did not join");
    master.renderFrame();
    const double before = medianFrameTime(master, frames);

    Clock::time_point frameDoneAt;
    auto frame = std::async(std::launch::async, [&] {
        master.renderFrame();
        frameDoneAt = Clock::now();
    });
    std::this_thread::sleep_for(std::chrono::duration<double>(before / 3));
    const auto faultAt = Clock::now();
    kill(procs.pids().back(), signal);
    auto detectedAt = faultAt;
    while (master.connectedClients() == clients && seconds(Clock::now() - faultAt) < 60)
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    detectedAt = Clock::now();
    frame.get();
    const double after = medianFrameTime(master, frames);
    // A frozen client that wakes up notices the master's silence after the master's timeout
    // (it learns it in Welcome), reconnects and proves its state: the time until it is back.
    double rejoin = -1;
    if (signal == SIGSTOP) {
        const auto resumedAt = Clock::now();
        kill(procs.pids().back(), SIGCONT);
        if (master.waitForClients(clients, 30'000)) rejoin = seconds(Clock::now() - resumedAt);
        kill(procs.pids().back(), SIGKILL);
    }
    toml::table out{{"fault", signal == SIGKILL ? "SIGKILL" : "SIGSTOP"},
                       {"clients", clients},
                       {"timeout_ms", timeoutMs},
                       {"detection_s", seconds(detectedAt - faultAt)},
                       // Negative when the frame finished (stragglers re-issued) before the timeout.
                       {"completion_after_detection_s", seconds(frameDoneAt - detectedAt)},
                       {"completion_after_fault_s", seconds(frameDoneAt - faultAt)},
                       {"frame_s_before", before},
                       {"frame_s_without_client", after},
                       {"extra_frame_fraction", after / before - 1.0}};
    if (signal == SIGSTOP) out.insert("rejoin_after_resume_s", rejoin);  // -1: not back within 30 s
    return out;
}

toml::table curveRun(const SceneDesc& desc, bool curve, TileCodec codec, int clients, int frames,
                     const std::string& bind, const std::string& netns, const std::filesystem::path& keyDir) {
    ClusterSettings cs;
    cs.async = true;
    cs.prefetch = 8;
    cs.bind = bind;
    cs.insecure = !curve;
    cs.codec.codec = codec;
    std::vector<std::string> extra;
    if (curve) {
        cs.keyFile = keyDir / "master.key";
        cs.clientKeys = {keyDir / "client.pub"};
        extra = {"--key", (keyDir / "client.key").string(), "--server-key", (keyDir / "master.pub").string()};
    }
    Master master(desc, cs);
    LocalClients procs(clients, master.endpoint(), 1, true, netns, extra);
    if (!master.waitForClients(clients, 120'000)) throw InputError("local clients did not join");
    master.renderFrame();
    master.renderFrame();
    const double t = medianFrameTime(master, frames);
    return toml::table{{"curve", curve}, {"codec", tileCodecName(codec)}, {"clients", clients}, {"fps", 1.0 / t}};
}

void print(std::FILE* text, const toml::array& faults, const toml::array& curve) {
    for (const auto& f : faults) {
        const toml::table& t = *f.as_table();
        std::fprintf(text, "%s with %lld clients, timeout %lld ms: detected after %.3f s, frame done %.3f s after the fault; "
                     "frame %.3f s before, %.3f s without the client (%+.0f%%)\n",
                     t["fault"].value_or(""), (long long)t["clients"].value_or(0), (long long)t["timeout_ms"].value_or(0),
                     t["detection_s"].value_or(0.0), t["completion_after_fault_s"].value_or(0.0),
                     t["frame_s_before"].value_or(0.0), t["frame_s_without_client"].value_or(0.0),
                     100.0 * t["extra_frame_fraction"].value_or(0.0));
        if (t.contains("rejoin_after_resume_s"))
            std::fprintf(text, "  resumed with SIGCONT: back in %.3f s\n", t["rejoin_after_resume_s"].value_or(-1.0));
    }
    for (const auto& c : curve) {
        const toml::table& t = *c.as_table();
        std::fprintf(text, "1600x1200 %s, CURVE %s: %.1f fps\n", t["codec"].value_or(""),
                     t["curve"].value_or(false) ? "on " : "off", t["fps"].value_or(0.0));
    }
}

}  // namespace

toml::table faults(const FaultsOptions& o) {
    SceneDesc desc = builtinScene("knots", 300'000);
    desc.settings.width = 640;
    desc.settings.height = 480;
    desc.settings.tileSize = 16;
    toml::array faults;
    for (int sig : {SIGKILL, SIGSTOP}) faults.push_back(faultRun(desc, sig, o.clients, o.frames, o.timeoutMs));

    const auto keyDir = std::filesystem::temp_directory_path() / ("rtwall-bench-keys-" + std::to_string(getpid()));
    std::filesystem::create_directories(keyDir);
    writeNewKeyPair(keyDir / "master");
    writeNewKeyPair(keyDir / "client");
    SceneDesc big = builtinScene("knots", 200'000);
    big.settings.width = 1600;
    big.settings.height = 1200;
    big.settings.tileSize = 64;
    big.settings.shading = ShadingMode::EyeLight;
    toml::array curve;
    for (TileCodec c : {TileCodec::Raw, TileCodec::Lz4})
        for (bool on : {false, true})
            curve.push_back(curveRun(big, on, c, 2, std::max(5, o.frames), o.bind, o.netns, keyDir));
    std::filesystem::remove_all(keyDir);
    if (o.text) print(o.text, faults, curve);
    return toml::table{{"benchmark", "faults"}, {"link", o.link}, {"faults", faults}, {"curve", curve}};
}

}  // namespace rtwall::bench
