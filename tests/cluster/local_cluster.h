// A master and client threads in one test process, on loopback, for the tests that compare a
// cluster's frames with one machine's: the master goes first (its goodbye ends the clients),
// then the client threads are joined, also when a test fails half-way.
#pragma once

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <atomic>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

namespace rtwall::test {

struct LocalCluster {
    // Client i traces packets of packetWidths[i % size] rays (empty: each its CPU's widest).
    LocalCluster(const SceneDesc& desc, const ClusterSettings& cs, int clientCount,
                 const std::filesystem::path& cacheDir = {}, const std::vector<int>& packetWidths = {})
        : master(std::make_unique<Master>(desc, cs)) {
        for (int i = 0; i < clientCount; ++i) {
            ClientSettings c;
            c.connect = master->endpoint();
            c.threads = 1;
            if (!packetWidths.empty()) c.packetWidth = packetWidths[size_t(i) % packetWidths.size()];
            c.exitAfterIdleMs = 4000;
            c.cacheDir = cacheDir;
            c.counters = std::make_shared<ClientCounters>();
            counters.push_back(c.counters);
            threads.emplace_back([c] { runClient(c); });
        }
    }
    ~LocalCluster() {
        master.reset();
        for (auto& t : threads) t.join();
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

inline Image singleMachine(const Scene& scene, const SceneDesc& d, uint32_t frame) {
    return renderFrame(scene, Camera(d.cameras.front(), d.settings.width, d.settings.height), d.settings, frame);
}
inline Image singleMachine(const SceneDesc& d, uint32_t frame) { return singleMachine(Scene(d), d, frame); }

}  // namespace rtwall::test
