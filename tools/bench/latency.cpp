// rtwall bench latency: motion-to-photon latency of a tracked wall (issue 18). A WallSession
// (master and loopback client threads, headless presenter) on a tracked wall whose DTrack
// datagrams come from a sender thread in this process on 127.0.0.1: a head going round a
// horizontal circle at a constant 0.5 m/s, at the tracker's rate. Per datagram: the time from
// its sending (loopback: its arrival, to within microseconds) to the end of the first step()
// whose shown frame was made with a head pose that includes it (WallSession::shownTrackerPackets;
// "presented": the headless presenter has taken the frame). That includes waiting for the frame
// in progress when it arrived (up to a frame); per frame, the time from the arrival of the newest
// datagram it was made with to its presentation is the target (one frame time + 10 ms
// with async off: that frame's render and transfer, nothing queued before it). Per shown frame: the distance
// between the head it was made for (predicted or not) and the true head on the circle at the
// moment it was presented. Mono and stereo, asynchronous rendering off and on, prediction off
// and on (on: prediction_ms = the median time from a frame's head pose to its presentation,
// measured with it off; the tracker adds the pose's age itself), at a few image sizes
// (frame rates). Medians and p95, and the share of datagrams and frames over the targets.
// With --nodes (and --reproject), also on two display nodes (threads here, headless, each
// warping its own screens on the CPU): a photon is a node's answer to a refresh's pose
// (NodeShown, as the master receives it: an upper bound by one loopback hop), and
// pose_to_node_ms is the pose's way from the master to that answer.
#include "bench.h"
#include "bench_util.h"

#include <rtwall/tracking.h>
#include <rtwall/wall.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>
#include <unistd.h>

namespace rtwall::bench {

namespace {

using Clock = std::chrono::steady_clock;

constexpr double kPi = 3.14159265358979323846;

double quantile(std::vector<double> v, double q) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
}

// The true head: a horizontal circle of `radius` m about the viewer's position, at `speed` m/s.
struct Circle {
    Float3 centre{0.0f, 0.2f, 2.5f};  // wall coordinates: the shipped 2x2 wall's viewer
    double radius = 0.3, speed = 0.5;
    std::array<double, 3> at(double t) const {
        const double a = speed / radius * t;
        return {centre.x + radius * std::cos(a), centre.y, centre.z + radius * std::sin(a)};
    }
};

// A wall of width x height pixels, 3.2 m x 2.4 m, tracked on 127.0.0.1 (a free port). The room
// transform is the identity in metres (DTrack millimetres): what is sent is wall coordinates.
// On display nodes: two columns of screens, the left on node "left", the right on node "right"
// (a mono wall is then two screens side by side).
std::string wallText(int width, int height, bool stereo, double predictionMs, bool reproject, double refreshHz, bool nodes) {
    char buf[1024];
    std::snprintf(buf, sizeof buf,
                  "[wall]\nname = \"latency\"\nvsync = false\nreproject = \"%s\"\nrefresh_hz = %.3f\n[grid]\ncolumns = %d\nrows = %d\nscreen_width = %d\nscreen_height = %d\n"
                  "[stereo]\nmode = \"%s\"\neye_separation = 0.065\nviewer = [0.0, 0.2, 2.5]\n"
                  "lower_left = [-1.6, -1.2, 0.0]\nlower_right = [1.6, -1.2, 0.0]\nupper_left = [-1.6, 1.2, 0.0]\n"
                  "[tracking]\nsource = \"dtrack://127.0.0.1:0\"\nroom_scale = 0.001\ntimeout_ms = 1000\nprediction_ms = %.3f\n"
                  "filter = \"none\"\n[headless]\nwrite_every = 0\n",
                  reproject ? "on" : "off", refreshHz, stereo || nodes ? 2 : 1, stereo ? 2 : 1,
                  stereo || nodes ? width / 2 : width, stereo ? height / 2 : height, stereo ? "passive" : "none", predictionMs);
    return std::string(buf) + (nodes ? "[[node]]\nname = \"left\"\ncolumns = [0, 0]\n[[node]]\nname = \"right\"\ncolumns = [1, 1]\n" : "");
}

struct Case {
    bool stereo = false, async = false, reproject = false;
    double predictionMs = 0;
    int width = 0, height = 0;
    bool nodes = false;  // on two display nodes (threads of this process, headless, warping on the CPU)
};

struct Measured {
    std::vector<double> latency;  // seconds, per datagram shown: arrival to the first presentation made with it
    std::vector<double> newest;   // seconds, per presentation: arrival of the newest datagram its pose was made with to it
    std::vector<double> error;    // metres, per presentation
    std::vector<double> frame;    // seconds between rendered frames (steps)
    std::vector<double> refresh;  // seconds between presentations
    std::vector<double> specToPresent;  // seconds from a presentation's head pose being read to it
    std::vector<double> poseToNode;     // on nodes: seconds from the master's pose to a node's answer (shown, one hop back)
    uint64_t sent = 0, shownPackets = 0;
};

double seconds(Clock::time_point t) { return std::chrono::duration<double>(t.time_since_epoch()).count(); }

// Sends the circle's datagrams at `rate` Hz until stopped; the send time of datagram k (1-based,
// the receiver's packet count after it) is times[k - 1].
class HeadSender {
public:
    HeadSender(int port, Circle circle, double rate, Clock::time_point start)
        : sender_(port), circle_(circle), rate_(rate), start_(start), thread_([this] { run(); }) {}
    ~HeadSender() {
        stop_ = true;
        thread_.join();
    }
    std::vector<Clock::time_point> times() const {
        std::lock_guard lock(m_);
        return times_;
    }

private:
    void run() {
        for (uint64_t k = 1; !stop_; ++k) {
            const Clock::time_point due = start_ + std::chrono::nanoseconds(int64_t(double(k - 1) / rate_ * 1e9));
            std::this_thread::sleep_until(due);
            const double t = std::chrono::duration<double>(Clock::now() - start_).count();
            const std::array<double, 3> p = circle_.at(t);
            DTrackFrame f;
            f.frame = k;
            DTrackBody b;
            b.quality = 1;
            b.position = {p[0] * 1e3, p[1] * 1e3, p[2] * 1e3};
            f.bodies.push_back(b);
            {
                std::lock_guard lock(m_);
                times_.push_back(Clock::now());
            }
            sender_.send(f);
        }
    }
    DTrackSender sender_;
    Circle circle_;
    double rate_;
    Clock::time_point start_;
    std::atomic<bool> stop_{false};
    mutable std::mutex m_;
    std::vector<Clock::time_point> times_;
    std::thread thread_;
};

Measured measure(const LatencyOptions& o, const Case& c, const std::filesystem::path& dir) {
    const std::filesystem::path wall = dir / "wall.toml";
    std::ofstream(wall) << wallText(c.width, c.height, c.stereo, c.predictionMs, c.reproject, o.refreshHz, c.nodes);
    RunConfig rc = steppedRunConfig(dir, o.clients);
    rc.scene = o.scene;
    rc.wall = wall;
    rc.cluster.threadsPerClient = 1;
    rc.cluster.async = c.async;
    WallSession session(rc);
    for (int i = 0; i < 3; ++i) session.step();  // warm-up: scene built, affinity settled

    const Circle circle;
    const Clock::time_point start = Clock::now();
    Measured m;
    HeadSender sender(session.trackerPort(), circle, o.rate, start);
    uint64_t lastShown = 0;
    Clock::time_point lastStep = Clock::now(), lastPresented = lastStep;
    std::vector<Presentation> sentPoses;  // on nodes: the poses the master sent, in order
    for (int f = 0; f < o.warmupFrames + o.frames; ++f) {
        session.step();
        const Clock::time_point stepped = Clock::now();
        const std::vector<Presentation> shown = session.takePresentations();
        const std::vector<Clock::time_point> times = sender.times();
        if (f < o.warmupFrames) {  // the head comes up to speed, the async pipeline fills
            for (const Presentation& p : shown) lastShown = std::max(lastShown, p.trackerPackets);
            lastStep = stepped;
            if (!shown.empty()) lastPresented = shown.back().at;
            session.takeNodeRefreshes();
            continue;
        }
        m.frame.push_back(std::chrono::duration<double>(stepped - lastStep).count());
        lastStep = stepped;
        if (c.nodes) {
            // The photons are on the nodes: each node's answer to a refresh is its presentation
            // (an upper bound: it also holds the answer's way back), of the master's pose read
            // just before that refresh was sent (the newest presentation posed before it).
            for (const Presentation& p : shown) {
                m.refresh.push_back(std::chrono::duration<double>(p.at - lastPresented).count());
                lastPresented = p.at;
                sentPoses.push_back(p);
            }
            std::vector<NodeRefreshDelay> answers = session.takeNodeRefreshes();
            for (const NodeRefreshDelay& d : answers) {
                auto it = std::upper_bound(sentPoses.begin(), sentPoses.end(), d.askedAt,
                                           [](double t, const Presentation& p) { return t < seconds(p.posed); });
                if (it == sentPoses.begin()) continue;
                const Presentation& p = *std::prev(it);
                const double photon = d.askedAt + d.milliseconds * 1e-3;
                m.poseToNode.push_back(d.milliseconds * 1e-3);
                m.specToPresent.push_back(photon - seconds(p.posed));
                if (d.node == "left") {  // every datagram: counted on one node
                    for (uint64_t k = lastShown + 1; k <= p.trackerPackets && k <= times.size(); ++k)
                        m.latency.push_back(photon - seconds(times[k - 1]));
                    if (p.trackerPackets > lastShown) m.shownPackets += p.trackerPackets - lastShown;
                    lastShown = std::max(lastShown, p.trackerPackets);
                }
                if (p.trackerPackets >= 1 && p.trackerPackets <= times.size())
                    m.newest.push_back(photon - seconds(times[p.trackerPackets - 1]));
                const std::array<double, 3> truth = circle.at(photon - seconds(start));
                const Float3& h = p.head.position;
                m.error.push_back(std::hypot(h.x - truth[0], h.y - truth[1], h.z - truth[2]));
            }
            continue;
        }
        // Each presentation: with re-projection several a step, each with the pose read just before it.
        for (const Presentation& p : shown) {
            m.refresh.push_back(std::chrono::duration<double>(p.at - lastPresented).count());
            lastPresented = p.at;
            m.specToPresent.push_back(std::chrono::duration<double>(p.at - p.posed).count());
            for (uint64_t k = lastShown + 1; k <= p.trackerPackets && k <= times.size(); ++k)
                m.latency.push_back(std::chrono::duration<double>(p.at - times[k - 1]).count());
            if (p.trackerPackets > lastShown) m.shownPackets += p.trackerPackets - lastShown;
            if (p.trackerPackets >= 1 && p.trackerPackets <= times.size())
                m.newest.push_back(std::chrono::duration<double>(p.at - times[p.trackerPackets - 1]).count());
            lastShown = std::max(lastShown, p.trackerPackets);
            const std::array<double, 3> truth = circle.at(std::chrono::duration<double>(p.at - start).count());
            const Float3& h = p.head.position;
            m.error.push_back(std::hypot(h.x - truth[0], h.y - truth[1], h.z - truth[2]));
        }
    }
    m.sent = sender.times().size();
    return m;
}

toml::table medianP95(const std::vector<double>& v, double scale) {
    return toml::table{{"median", scale * median(v)}, {"p95", scale * quantile(v, 0.95)}};
}

// The target of the newest datagram's way to the display: one refresh plus 5 ms re-projecting
// (issue 27), one frame plus the slack otherwise (issue 18).
double newestTarget(const LatencyOptions& o, const Case& c, const Measured& m) {
    return c.reproject ? 1.0 / o.refreshHz + o.reprojectSlackMs * 1e-3 : median(m.frame) + o.targetSlackMs * 1e-3;
}

toml::table row(const LatencyOptions& o, const Case& c, const Measured& m) {
    const double frameS = median(m.frame);
    const double bound = newestTarget(o, c, m);
    size_t late = 0, lateFrames = 0, off = 0;
    for (double l : m.latency) late += l > bound;
    for (double l : m.newest) lateFrames += l > bound;
    for (double e : m.error) off += e > o.targetErrorMm * 1e-3;
    const double refreshS = median(m.refresh);
    toml::table out{{"reproject", c.reproject},
                       {"stereo", c.stereo},
                       {"nodes", c.nodes},
                       {"async", c.async},
                       {"prediction_ms", c.predictionMs},
                       {"width", c.width},
                       {"height", c.height},
                       {"render_fps", frameS > 0 ? 1.0 / frameS : 0.0},
                       {"display_hz", o.refreshHz},
                       {"presented_hz", refreshS > 0 ? 1.0 / refreshS : 0.0},
                       {"newest_to_photon_ms", medianP95(m.newest, 1e3)},
                       {"head_error_mm", medianP95(m.error, 1e3)},
                       {"newest_to_photon_target_ms", 1e3 * bound},
                       {"frames", int64_t(m.frame.size())},
                       {"presentations", int64_t(m.newest.size())},
                       {"fps", frameS > 0 ? 1.0 / frameS : 0.0},
                       {"frame_ms_median", 1e3 * frameS},
                       {"frame_ms_p95", 1e3 * quantile(m.frame, 0.95)},
                       {"datagrams_sent", int64_t(m.sent)},
                       {"datagrams_shown", int64_t(m.latency.size())},
                       {"latency_ms_median", 1e3 * median(m.latency)},
                       {"latency_ms_p95", 1e3 * quantile(m.latency, 0.95)},
                       {"latency_target_ms", 1e3 * bound},
                       {"latency_over_target", m.latency.empty() ? 0.0 : double(late) / double(m.latency.size())},
                       {"frame_latency_ms_median", 1e3 * median(m.newest)},
                       {"frame_latency_ms_p95", 1e3 * quantile(m.newest, 0.95)},
                       {"frame_latency_over_target", m.newest.empty() ? 0.0 : double(lateFrames) / double(m.newest.size())},
                       {"pose_to_present_ms_median", 1e3 * median(m.specToPresent)},
                       {"error_mm_median", 1e3 * median(m.error)},
                       {"error_mm_p95", 1e3 * quantile(m.error, 0.95)},
                       {"error_over_target", m.error.empty() ? 0.0 : double(off) / double(m.error.size())}};
    if (c.nodes) out.insert("pose_to_node_ms", medianP95(m.poseToNode, 1e3));
    return out;
}

// A configuration measured without prediction, then with it as far ahead as its presentations
// take from their head pose (measured without it); both rows.
void measurePair(const LatencyOptions& o, const Case& c, const std::filesystem::path& dir, toml::array& rows) {
    const Measured plain = measure(o, c, dir);
    Case p = c;
    // (At most the 500 ms a wall config takes: a configuration that slow misses every target anyway.)
    p.predictionMs = std::clamp(std::round(1e3 * median(plain.specToPresent) * 10) / 10, 0.1, 500.0);
    const Measured predicted = measure(o, p, dir);
    for (const auto& [cc, mm] : {std::pair<const Case&, const Measured&>{c, plain}, {p, predicted}}) {
        toml::table r = row(o, cc, mm);
        if (o.text)
            std::fprintf(o.text, "%-6s %-5s %-9s%s %4dx%-4d pred %5.1f ms: %5.1f fps, %5.1f Hz shown, every datagram %5.1f ms (p95 %5.1f), "
                                 "newest to photon %5.1f ms (p95 %5.1f, %4.1f%% over %5.1f ms), head error %5.1f mm "
                                 "(p95 %5.1f, %4.1f%% over %.0f mm)\n",
                         cc.stereo ? "stereo" : "mono", cc.async ? "async" : "sync", cc.reproject ? "reproject" : "as-is",
                         cc.nodes ? " on nodes" : "", cc.width,
                         cc.height, cc.predictionMs, r["render_fps"].value_or(0.0), r["presented_hz"].value_or(0.0),
                         r["latency_ms_median"].value_or(0.0), r["latency_ms_p95"].value_or(0.0),
                         r["frame_latency_ms_median"].value_or(0.0), r["frame_latency_ms_p95"].value_or(0.0),
                         100 * r["frame_latency_over_target"].value_or(0.0), r["latency_target_ms"].value_or(0.0),
                         r["error_mm_median"].value_or(0.0), r["error_mm_p95"].value_or(0.0), 100 * r["error_over_target"].value_or(0.0),
                         o.targetErrorMm);
        rows.push_back(std::move(r));
    }
}

}  // namespace

toml::table latency(const LatencyOptions& o) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("rtwall-bench-latency-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    toml::array rows;
    if (o.text)
        std::fprintf(o.text, "head on a circle at 0.5 m/s, DTrack at %.0f Hz on loopback, %d client threads, scene %s; targets: "
                             "newest datagram to photon <= frame time + %.0f ms (async off), <= %.1f ms re-projecting (a %.0f Hz "
                             "refresh + %.0f ms), error <= %.0f mm (prediction on)\n",
                     o.rate, o.clients, o.scene.c_str(), o.targetSlackMs, 1e3 / o.refreshHz + o.reprojectSlackMs, o.refreshHz,
                     o.reprojectSlackMs, o.targetErrorMm);
    for (int width : o.widths)
        for (bool stereo : {false, true}) {
            // With --reproject: each size with re-projection off and on (async off: the display
            // loop never waits for the cluster anyway). Without: async off and on, as issue 18 measured.
            if (o.reproject) {
                for (bool reproject : {false, true}) measurePair(o, Case{stereo, false, reproject, 0.0, width, width * 3 / 4}, dir, rows);
                // The same wall on two display nodes, each warping its own screens to the pose
                // the master sends every refresh.
                if (o.nodes) measurePair(o, Case{stereo, false, true, 0.0, width, width * 3 / 4, true}, dir, rows);
            } else
                for (bool async : {false, true}) measurePair(o, Case{stereo, async, false, 0.0, width, width * 3 / 4}, dir, rows);
        }
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    return toml::table{{"benchmark", "latency"},
                       {"scene", o.scene},
                       {"clients", o.clients},
                       {"tracker_hz", o.rate},
                       {"head_speed_m_s", 0.5},
                       {"frames", o.frames},
                       {"target_slack_ms", o.targetSlackMs},
                       {"reproject", o.reproject},
                       {"nodes", o.nodes},
                       {"display_hz", o.refreshHz},
                       {"reproject_slack_ms", o.reprojectSlackMs},
                       {"target_error_mm", o.targetErrorMm},
                       {"rows", std::move(rows)}};
}

}  // namespace rtwall::bench
