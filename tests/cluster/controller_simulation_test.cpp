// The operating-point controller (rtwall::tune) driven by the cluster simulation (the real
// TileScheduler against simulated clients and links): every frame is simulated at the point the
// controller chose, under the cluster of that moment; clients leave and join and the master's
// link is throttled mid-run. The controller must bring the achieved frame rate back to the
// target within a bounded number of frames after each event, and must not oscillate.
#include <rtwall/cluster.h>
#include <rtwall/tune.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace rtwall {
namespace {

// A front of five settings of a 512x512 frame (64 tiles of 64x64): each step more accurate costs
// twice the render time per tile; the two fastest send JPEG-sized tiles, the rest LZ4-sized ones.
struct Setting {
    double renderPerTile;  // seconds on one thread
    uint32_t bytesPerTile;
    double error;
};
const std::vector<Setting> kSettings = {
    {0.5e-3, 1500, 8.0}, {1e-3, 1500, 4.0}, {2e-3, 6000, 2.0}, {4e-3, 6000, 1.0}, {8e-3, 6000, 0.5}};

TileProfile profileOf(const Setting& s) {
    TileProfile p;
    p.width = p.height = 512;
    p.tileSize = 64;
    // Tiles differ in cost (a heavier middle), as in a real scene, so stealing and affinity matter.
    std::vector<double> render;
    for (int ty = 0; ty < 8; ++ty)
        for (int tx = 0; tx < 8; ++tx) render.push_back(s.renderPerTile * ((tx >= 2 && tx < 6) ? 1.5 : 0.5));
    p.renderSeconds = {render};
    TileProfile::CodecCost c;
    c.codec.codec = TileCodec::Lz4;
    c.bytes.assign(64, s.bytesPerTile);
    c.encodeSeconds.assign(64, 20e-6);
    c.decodeSeconds.assign(64, 10e-6);
    p.codecs = {c};
    return p;
}

struct Cluster {
    int clients;
    double masterBits;  // the master's link
};

SimConfig configOf(const Cluster& c) {
    SimConfig cfg;
    cfg.clients = c.clients;
    cfg.threadsPerClient = 2;
    cfg.prefetch = 4;
    cfg.clientLink = {1e9, 100e-6, 0, 0};
    cfg.masterBitsPerSecond = c.masterBits;
    cfg.masterSecondsPerMessage = 10e-6;
    cfg.messageOverheadBytes = 40;
    cfg.frames = 1;
    cfg.warmupFrames = 1;
    return cfg;
}

double simulatedFrame(const TileProfile& p, const Cluster& c) { return simulateCluster(p, configOf(c)).frameSeconds.front(); }

struct Phase {
    const char* what;
    Cluster cluster;
    int frames;
};

struct Trace {
    std::vector<double> seconds;  // achieved frame time
    std::vector<size_t> point;    // front index the frame was rendered at
};

Trace drive(OperatingPointController& ctl, const std::vector<TileProfile>& profiles, const std::vector<Phase>& phases) {
    // The front's point names carry the index into kSettings.
    Trace t;
    for (const Phase& ph : phases)
        for (int f = 0; f < ph.frames; ++f) {
            const size_t s = size_t(std::stoi(ctl.current().name));
            const double sec = simulatedFrame(profiles[s], ph.cluster);
            t.seconds.push_back(sec);
            t.point.push_back(ctl.currentIndex());
            ctl.observe(sec);
        }
    return t;
}

TEST(ControllerInSimulation, HoldsTheTargetWhenClientsComeAndGoAndTheLinkIsThrottled) {
    std::vector<TileProfile> profiles;
    for (const Setting& s : kSettings) profiles.push_back(profileOf(s));
    // The front as tools/speed_accuracy.py measures it: simulated on the nominal cluster.
    const Cluster nominal{4, 1e9};
    std::vector<OperatingPoint> front;
    for (size_t i = 0; i < kSettings.size(); ++i)
        front.push_back({std::to_string(i), {}, simulatedFrame(profiles[i], nominal), kSettings[i].error});
    const double target = 40;
    // The nominal cluster holds the target at setting 2 (setting 3 takes about 33 ms).
    ASSERT_LT(front[2].frameSeconds, 1 / target);
    ASSERT_GT(front[3].frameSeconds, 1 / target);

    ControllerOptions opt;
    opt.targetFps = target;
    OperatingPointController ctl(front, opt);
    const std::vector<Phase> phases = {
        {"nominal: 4 clients, 1 Gbit/s", nominal, 60},
        {"two clients leave", {2, 1e9}, 60},
        {"they come back, and four more", {8, 1e9}, 60},
        {"the master's link is throttled to 40 Mbit/s", {8, 40e6}, 80},
        {"the link recovers", {8, 1e9}, 80},
    };
    const Trace t = drive(ctl, profiles, phases);

    // After every event the frame rate is back at the target within K frames and stays there
    // until the next event; within a phase the point moves in one direction only (no
    // oscillation) and settles: the last half of every phase has no change at all.
    const int K = 12;  // downFrames + holdFrames and a margin: two steps down
    size_t start = 0;
    for (const Phase& ph : phases) {
        const size_t end = start + size_t(ph.frames);
        for (size_t f = start + K; f < end; ++f)
            EXPECT_LE(t.seconds[f], 1 / target) << ph.what << ": frame " << f - start << " at point " << t.point[f] << " took "
                                                << t.seconds[f] * 1e3 << " ms";
        int direction = 0;
        for (size_t f = start + 1; f < end; ++f) {
            const int d = t.point[f] > t.point[f - 1] ? 1 : t.point[f] < t.point[f - 1] ? -1 : 0;
            if (d == 0) continue;
            EXPECT_TRUE(direction == 0 || d == direction) << ph.what << ": the point went both ways (oscillation) at frame "
                                                          << f - start;
            direction = d;
        }
        for (size_t f = start + size_t(ph.frames) / 2 + 1; f < end; ++f)
            EXPECT_EQ(t.point[f], t.point[f - 1]) << ph.what << ": still changing at frame " << f - start;
        start = end;
    }
    // And the controller used the headroom it had: fewer clients, a lower point than nominal;
    // more clients, a higher one; the throttled link forced a lower one again.
    auto settled = [&](int phase) {
        size_t end = 0;
        for (int i = 0; i <= phase; ++i) end += size_t(phases[size_t(i)].frames);
        return t.point[end - 1];
    };
    EXPECT_LT(settled(1), settled(0));
    EXPECT_GT(settled(2), settled(0));
    EXPECT_LT(settled(3), settled(2));
    EXPECT_EQ(settled(4), settled(2));
}

}  // namespace
}  // namespace rtwall
