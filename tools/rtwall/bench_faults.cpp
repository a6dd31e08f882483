// rtwall bench faults: options of the fault-cost benchmark (tools/bench/faults.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchFaults(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::FaultsOptions>(bench, "faults", "Cost of a killed or frozen client, and of CURVE encryption");
    cmd->add_option("--clients", o.clients, "Local client processes")->check(CLI::Range(2, 64));
    cmd->add_option("--frames", o.frames, "Frames per measurement (medians)")->check(CLI::Range(1, 1000));
    cmd->add_option("--timeout", o.timeoutMs, "Heartbeat timeout in ms")->check(CLI::Range(50, 60000));
    addNetemOptions(cmd, o.bind, o.netns, o.link, "Master endpoint for the CURVE runs (tools/netem.sh)",
                    "Start client i of the CURVE runs in namespace <prefix><i>");
    callBenchmark(cmd, run, a, bench::faults);
}

}  // namespace rtwall::cli
