// Render-client processes on this PC, started as `rtwall client` children of this executable
// and stopped (SIGTERM, then SIGKILL) when the object goes away.
#pragma once

#include <string>
#include <vector>

#include <sys/types.h>

namespace rtwall::cli {

class LocalClients {
public:
    // With a netns prefix, client i runs in network namespace <prefix><i> (tools/netem.sh).
    LocalClients(int count, const std::string& endpoint, int threadsEach, bool replay = false,
                 const std::string& netnsPrefix = {}, const std::vector<std::string>& extraArgs = {});
    ~LocalClients();
    LocalClients(const LocalClients&) = delete;
    LocalClients& operator=(const LocalClients&) = delete;

    const std::vector<pid_t>& pids() const { return pids_; }

private:
    std::vector<pid_t> pids_;
};

}  // namespace rtwall::cli
