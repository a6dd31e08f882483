// rtwall bench attack | chaos (issue 16): the master under attack and under chaos, for longer
// than the tests run them. Figures, not assertions: messages sent by kind and what the master
// counted, frames completed and how many were bit-identical to one machine, frame times.
#include "bench.h"
#include "bench_util.h"

#include <adversary.h>
#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <toml++/toml.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <future>
#include <cstdio>
#include <thread>

namespace rtwall::bench {

namespace {

using Clock = std::chrono::steady_clock;

SceneDesc benchScene() {
    SceneDesc desc = builtinScene("knots", 200'000);
    desc.settings.width = 320;
    desc.settings.height = 240;
    desc.settings.tileSize = 16;
    return desc;
}

toml::table countersTable(const MasterCounters& c) {
    return toml::table{{"malformed", int64_t(c.malformed)},
                       {"unknown_peer", int64_t(c.unknownPeer)},
                       {"stale", int64_t(c.stale)},
                       {"replayed", int64_t(c.replayed)},
                       {"unexpected", int64_t(c.unexpected)},
                       {"undecodable_tiles", int64_t(c.undecodableTiles)},
                       {"refused", int64_t(c.refused)},
                       {"failed_handshakes", int64_t(c.failedHandshakes)},
                       {"failed_sends", int64_t(c.failedSends)},
                       {"lost_hand_outs", int64_t(c.lostHandOuts)},
                       {"stalled_tiles", int64_t(c.stalledTiles)},
                       {"clients_dropped", int64_t(c.clientsDropped)}};
}


struct FrameStats {
    int frames = 0, identical = 0;
    std::vector<double> seconds;
    double median() const { return rtwall::median(seconds); }
    double worst() const { return seconds.empty() ? 0 : *std::max_element(seconds.begin(), seconds.end()); }
};

// Frames until `done` says stop; each compared with one machine's.
template <class Done> FrameStats renderWhile(Master& master, const Image& expected, Done&& done) {
    FrameStats st;
    while (!done()) {
        Image img;
        st.seconds.push_back(secondsOf([&] { img = master.renderFrame(); }));
        ++st.frames;
        st.identical += img.rgb == expected.rgb;
    }
    return st;
}

toml::table attackRun(const SceneDesc& desc, const Image& expected, bool curve, int clients, double seconds, int rate,
                      uint64_t seed, const std::filesystem::path& keyDir) {
    ClusterSettings cs;
    cs.async = false;
    cs.localClients = clients;
    if (curve) {
        cs.keyFile = keyDir / "master.key";
        cs.clientKeys = {};
    }
    Master master(desc, cs);
    LocalClients procs(clients, master.endpoint(), 1, false, {}, master.localClientArgs());
    if (!master.waitForClients(clients, 120'000)) throw InputError("local clients did not join");
    master.renderFrame();
    // Undisturbed, then under attack, for the same time.
    auto until = [](double s) {
        const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
        return [end] { return Clock::now() >= end; };
    };
    const FrameStats calm = renderWhile(master, expected, until(seconds));
    const MasterCounters before = master.counters();
    testing::AttackOptions ao;
    ao.endpoint = master.endpoint();
    ao.seconds = seconds;
    ao.messagesPerSecond = rate;
    ao.seed = seed;
    if (curve) ao.serverKeyFile = keyDir / "master.pub";
    std::atomic<bool> attacking{true};
    auto attack = std::async(std::launch::async, [&] {
        const testing::AttackReport r = testing::attackMaster(ao);
        attacking = false;
        return r;
    });
    const FrameStats hit = renderWhile(master, expected, [&] { return !attacking.load(); });
    const testing::AttackReport sent = attack.get();
    // Let the master read what is still queued.
    auto counted = [&] {
        const MasterCounters d = master.counters() - before;
        return d.dropped() + d.refused + d.stalledTiles;
    };
    for (int i = 0; i < 100 && counted() < sent.appMessages(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const MasterCounters delta = master.counters() - before;
    return toml::table{
        {"curve", curve},
        {"clients", clients},
        {"seconds", seconds},
        {"sent", toml::table{{"malformed", int64_t(sent.malformed)},
                             {"unknown_peer", int64_t(sent.unknownPeer)},
                             {"refused", int64_t(sent.refused)},
                             {"in_session", int64_t(sent.inSession())},
                             {"in_session_stale", int64_t(sent.stale)},
                             {"in_session_replayed_or_unexpected", int64_t(sent.replayedOrUnexpected)},
                             {"in_session_stall_reports", int64_t(sent.stallReports)},
                             {"unversioned_connections", int64_t(sent.unversionedConnections)},
                             {"app_messages", int64_t(sent.appMessages())},
                             {"raw_connections", int64_t(sent.rawConnections)},
                             {"oversized", int64_t(sent.oversized)},
                             {"curve_attempts", int64_t(sent.curveAttempts)},
                             {"joined", int64_t(sent.joined)}}},
        {"counted", countersTable(delta)},
        {"frames_undisturbed", calm.frames},
        {"frames_undisturbed_identical", calm.identical},
        {"frame_s_undisturbed_median", calm.median()},
        {"frames_attacked", hit.frames},
        {"frames_attacked_identical", hit.identical},
        {"frame_s_attacked_median", hit.median()},
        {"frame_s_attacked_worst", hit.worst()},
    };
}

void print(std::FILE* text, const toml::array& runs) {
    for (const auto& r : runs) {
        const toml::table& t = *r.as_table();
        const toml::table& sent = *t["sent"].as_table();
        const toml::table& counted = *t["counted"].as_table();
        std::fprintf(text, "CURVE %s, %lld clients: %lld app-level messages sent (%lld malformed, %lld from no client, "
                     "%lld in a session), %lld raw connections, %lld oversized; master counted %lld malformed, %lld "
                     "unknown peer, %lld stale, %lld repeated, %lld unexpected, %lld refused, %lld failed handshakes\n",
                     t["curve"].value_or(false) ? "on " : "off", (long long)t["clients"].value_or(0),
                     (long long)sent["app_messages"].value_or(0), (long long)sent["malformed"].value_or(0),
                     (long long)sent["unknown_peer"].value_or(0), (long long)sent["in_session"].value_or(0),
                     (long long)sent["raw_connections"].value_or(0), (long long)sent["oversized"].value_or(0),
                     (long long)counted["malformed"].value_or(0), (long long)counted["unknown_peer"].value_or(0),
                     (long long)counted["stale"].value_or(0), (long long)counted["replayed"].value_or(0),
                     (long long)counted["unexpected"].value_or(0), (long long)counted["refused"].value_or(0),
                     (long long)counted["failed_handshakes"].value_or(0));
        std::fprintf(text, "  frames: %lld undisturbed (%lld identical, median %.1f ms), %lld under attack (%lld identical, "
                     "median %.1f ms, worst %.1f ms)\n",
                     (long long)t["frames_undisturbed"].value_or(0), (long long)t["frames_undisturbed_identical"].value_or(0),
                     1e3 * t["frame_s_undisturbed_median"].value_or(0.0), (long long)t["frames_attacked"].value_or(0),
                     (long long)t["frames_attacked_identical"].value_or(0), 1e3 * t["frame_s_attacked_median"].value_or(0.0),
                     1e3 * t["frame_s_attacked_worst"].value_or(0.0));
    }
}

}  // namespace

toml::table attack(const AttackOptions& o) {
    const SceneDesc desc = benchScene();
    const Scene scene(desc);
    const Image expected = renderFrame(scene, Camera(desc.cameras.front(), desc.settings.width, desc.settings.height), desc.settings);
    const auto keyDir = std::filesystem::temp_directory_path() / ("rtwall-attack-keys-" + std::to_string(getpid()));
    writeNewKeyPair(keyDir / "master");
    toml::array runs;
    try {
        for (bool curve : {false, true})
            runs.push_back(attackRun(desc, expected, curve, o.clients, o.seconds, o.rate, o.seed, keyDir));
    } catch (...) {
        std::filesystem::remove_all(keyDir);
        throw;
    }
    std::filesystem::remove_all(keyDir);
    if (o.text) print(o.text, runs);
    return toml::table{{"benchmark", "attack"}, {"runs", runs}};
}

toml::table chaos(const ChaosOptions& o) {
    testing::ChaosOptions co;
    std::error_code ec;
    co.exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    co.clients = o.clients;
    co.seconds = o.seconds;
    co.seed = o.seed;
    co.faultIntervalMs = o.intervalMs;
    co.faultMaxMs = o.maxMs;
    co.timeoutMs = o.timeoutMs;
    co.framesAfter = o.framesAfter;
    co.linkCuts = o.linkCuts;
    const testing::ChaosReport r = testing::runChaos(benchScene(), co);
    if (!r.error.empty()) throw InputError("bench chaos: " + r.error);
    if (o.text)
        std::fprintf(o.text, "%llu faults (%llu frozen, %llu killed, %llu restarted, %llu links cut) over %.0f s with %d clients: "
                     "%llu frames, %llu bit-identical, %llu failed; worst frame %.2f s; after the last fault: first frame "
                     "%.2f s, worst %.2f s\nmaster: %s\n",
                     (unsigned long long)r.faults, (unsigned long long)r.stops, (unsigned long long)r.kills,
                     (unsigned long long)r.restarts, (unsigned long long)r.linkCuts, o.seconds, o.clients,
                     (unsigned long long)r.frames, (unsigned long long)r.framesIdentical, (unsigned long long)r.framesFailed,
                     r.worstFrameSeconds, r.firstFrameAfterLastFault, r.worstAfterLastFault,
                     describeCounters(r.counters).c_str());
    return toml::table{{"benchmark", "chaos"},
                       {"clients", o.clients},
                       {"seconds", o.seconds},
                       {"seed", int64_t(o.seed)},
                       {"link_cuts", o.linkCuts},
                       {"faults", int64_t(r.faults)},
                       {"stops", int64_t(r.stops)},
                       {"kills", int64_t(r.kills)},
                       {"restarts", int64_t(r.restarts)},
                       {"cuts", int64_t(r.linkCuts)},
                       {"frames", int64_t(r.frames)},
                       {"frames_identical", int64_t(r.framesIdentical)},
                       {"frames_failed", int64_t(r.framesFailed)},
                       {"worst_frame_s", r.worstFrameSeconds},
                       {"first_frame_after_last_fault_s", r.firstFrameAfterLastFault},
                       {"worst_frame_after_last_fault_s", r.worstAfterLastFault},
                       {"counters", countersTable(r.counters)}};
}

bool chaosPassed(const toml::table& r) {
    return r["frames_failed"].value_or(int64_t(-1)) == 0 && r["frames_identical"].value_or(int64_t(-1)) == r["frames"].value_or(int64_t(-2));
}

}  // namespace rtwall::bench
