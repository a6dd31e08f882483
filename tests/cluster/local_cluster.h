// A master and client threads in one test process, on loopback, for the tests that compare a
// cluster's frames with one machine's: the master goes first (its goodbye ends the clients),
// then the client threads are joined, also when a test fails half-way.
#pragma once

#include "image_compare.h"
#include "test_util.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace rtwall::test {

// configs/demo.toml at width x height without supersampling, in tiles of `tileSize` (0 keeps the
// file's): the small, quick frame most cluster tests render.
inline SceneDesc quickDemo(int width, int height, int tileSize = 0) {
    SceneDesc desc = demoScene(width, height, 1);
    if (tileSize > 0) desc.settings.tileSize = tileSize;
    return desc;
}

// One machine's frame `frame` of d's first camera: what the cluster must give bit for bit.
inline Image singleMachine(const Scene& scene, const SceneDesc& d, uint32_t frame) {
    return renderFrame(scene, Camera(d.cameras.front(), d.settings.width, d.settings.height), d.settings, frame);
}
inline Image singleMachine(const SceneDesc& d, uint32_t frame = 0) { return singleMachine(Scene(d), d, frame); }

struct LocalCluster {
    // Client i traces packets of packetWidths[i % size] rays (empty: each its CPU's widest).
    LocalCluster(const SceneDesc& desc, const ClusterSettings& cs, int clientCount,
                 const std::filesystem::path& cacheDir = {}, const std::vector<int>& packetWidths = {})
        : master(std::make_unique<Master>(desc, cs)) {
        for (int i = 0; i < clientCount; ++i) {
            ClientSettings c;
            if (!packetWidths.empty()) c.packetWidth = packetWidths[size_t(i) % packetWidths.size()];
            c.cacheDir = cacheDir;
            add(c);
        }
    }
    ~LocalCluster() {
        master.reset();
        for (auto& t : threads) t.join();
    }
    // One more client of the master: `c` (a cache, a packet width, a fault) with one render
    // thread, giving up after 4 s without its master; its counters join the others'.
    void add(ClientSettings c = {}) {
        c.connect = master->endpoint();
        c.threads = 1;
        c.exitAfterIdleMs = 4000;
        if (!c.counters) c.counters = std::make_shared<ClientCounters>();
        counters.push_back(c.counters);
        threads.emplace_back([c] { runClient(c); });
    }
    // Every client joined (30 s at most).
    bool ready() { return master->waitForClients(int(threads.size()), 30000); }
    // Renders the next frame, expects it to be bit-identical to one machine's frame of `state`
    // with the same number (`what` names the step in a failure) and returns it.
    Image expectFrameOf(const SceneDesc& state, const std::string& what = {}, FrameReport* report = nullptr) {
        FrameReport r;
        Image img = master->renderFrame(&r);
        EXPECT_EQ(differingBytes(img, singleMachine(state, r.frame)), 0u) << what << " (frame " << r.frame << ")";
        if (report) *report = std::move(r);
        return img;
    }
    // A counter summed over the clients.
    uint64_t sum(std::atomic<uint64_t> ClientCounters::*field) const {
        uint64_t n = 0;
        for (const auto& c : counters) n += (*c).*field;
        return n;
    }
    std::unique_ptr<Master> master;
    std::vector<std::thread> threads;
    std::vector<std::shared_ptr<ClientCounters>> counters;
};

// Frames one at a time (async off): every tile of a frame is of the state the frame began with,
// so a frame can be compared with one machine's.
inline ClusterSettings inStep() {
    ClusterSettings cs;
    cs.async = false;
    return cs;
}

// In step, `prefetch` tiles asked ahead, 8-bit tiles: for comparing a cluster's frames with one
// machine's 8-bit frames (linear tiles for accumulation have tests of their own in
// assets_accumulation_test.cpp).
inline ClusterSettings eightBitFrames(int prefetch = 2) {
    ClusterSettings cs = inStep();
    cs.prefetch = prefetch;
    cs.wideAccumulation = false;
    return cs;
}

// A master with a stop flag, and render clients on threads of the test whose exit statuses come
// back as futures: for the tests of a master that must not freeze. The clients are declared
// before the master, so the master goes first and its goodbye ends them.
struct StoppableCluster {
    StoppableCluster(const SceneDesc& desc, const ClusterSettings& cs) : master(std::make_unique<Master>(desc, cs)) {
        master->setStopFlag(&stop);
    }
    // A client of this master: `c` (keys, counters, a fault) with `threads` render threads that
    // gives up after 4 s without its master.
    void start(ClientSettings c = {}, int threads = 1) {
        c.connect = master->endpoint();
        c.threads = threads;
        c.exitAfterIdleMs = 4000;
        clients.push_back(std::async(std::launch::async, [c] { return runClient(c); }));
    }
    // Every client started joined (30 s at most).
    bool ready() { return master->waitForClients(int(clients.size()), 30000); }
    // renderFrame on another thread, given up (stop flag) if it takes longer than `seconds`: a
    // frozen master fails the test instead of hanging it.
    std::optional<Image> frameWithin(double seconds, FrameReport* report = nullptr) {
        auto f = std::async(std::launch::async, [&] { return master->renderFrame(report); });
        if (f.wait_for(std::chrono::duration<double>(seconds)) == std::future_status::ready) return f.get();
        stop = true;
        try {
            f.get();
        } catch (const Cancelled&) {
        }
        return std::nullopt;
    }
    std::vector<std::future<int>> clients;
    std::atomic<bool> stop{false};
    std::unique_ptr<Master> master;
};

}  // namespace rtwall::test
