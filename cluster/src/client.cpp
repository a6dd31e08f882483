// A render client (rtwall/cluster.h: runClient). What it does is in the files client_runtime.h
// lists, one per job.
#include "client_runtime.h"

namespace rtwall {

namespace cluster {

ClientRuntime::ClientRuntime(const ClientSettings& s) : settings_(s), faults_(s.faults ? *s.faults : ClientFaults{}) {
    threads_ = s.threads > 0 ? s.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    checkZmqVersion();
    if (!s.keyFile.empty()) {
        if (s.serverKeyFile.empty()) throw InputError("--key needs --server-key (the master's public key)");
        keys_ = readKeyPair(s.keyFile);
        serverKey_ = readPublicKey(s.serverKeyFile);
    }
}

int ClientRuntime::run() {
    results_.bind(kResultsAddress);
    slots_ = std::make_unique<Slot[]>(size_t(threads_));
    for (int i = 0; i < threads_; ++i) workers_.emplace_back([this, i] { workerLoop(slots_[size_t(i)]); });
    const int status = networkLoop();
    {
        std::lock_guard lock(workMutex_);
        stopping_ = true;
    }
    stopRequested_ = true;
    workCv_.notify_all();
    for (auto& t : workers_) t.join();
    return status;
}

}  // namespace cluster

using namespace cluster;

void writeNewKeyPair(const std::filesystem::path& stem) { writeKeyFiles(makeKeyPair(), stem); }

int runClient(const ClientSettings& settings) {
    if (settings.packetWidth != 0 && settings.packetWidth != 4 && settings.packetWidth != 8 && settings.packetWidth != 16)
        throw InputError("packet width " + std::to_string(settings.packetWidth) + ": expected 0 (this CPU's widest), 4, 8 or 16");
    ClientRuntime client(settings);
    return client.run();
}

}  // namespace rtwall
