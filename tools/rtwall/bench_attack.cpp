// rtwall bench attack and rtwall bench chaos: options of the robustness benchmarks
// (tools/bench/attack.cpp).
#include "bench_cli.h"

#include <bench.h>

namespace rtwall::cli {

void addBenchAttack(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::AttackOptions>(bench, "attack", "The master under attack (garbage, multi-frame, truncated, oversized, "
                                                   "replayed messages, ZMTP junk), with and without CURVE");
    cmd->add_option("--seconds", o.seconds, "Seconds of attack (and as many undisturbed before it), per mode")->check(CLI::Range(0.5, 3600.0));
    cmd->add_option("--rate", o.rate, "Attack messages per second")->check(CLI::Range(1, 1'000'000));
    cmd->add_option("--clients", o.clients, "Local client processes")->check(CLI::Range(1, 64));
    cmd->add_option("--seed", o.seed, "Seed of the attack");
    callBenchmark(cmd, run, a, bench::attack);
}

void addBenchChaos(CLI::App& bench, Run& run) {
    auto [a, o, cmd] = benchCommand<bench::ChaosOptions>(bench, "chaos", "Render while client processes are frozen, killed, restarted and cut off at random");
    cmd->add_option("--seconds", o.seconds, "Seconds of faults")->check(CLI::Range(1.0, 86400.0));
    cmd->add_option("--clients", o.clients, "Client processes")->check(CLI::Range(1, 64));
    cmd->add_option("--seed", o.seed, "Seed of the faults");
    cmd->add_option("--interval", o.intervalMs, "Mean ms between faults")->check(CLI::Range(10, 600000));
    cmd->add_option("--max-fault", o.maxMs, "Longest ms a client stays frozen, dead or cut off")->check(CLI::Range(101, 600000));
    cmd->add_option("--timeout", o.timeoutMs, "The master's heartbeat timeout in ms")->check(CLI::Range(50, 60000));
    cmd->add_option("--frames-after", o.framesAfter, "Frames after the last fault")->check(CLI::Range(1, 100000));
    cmd->add_flag("--link-cuts", o.linkCuts, "Clients in network namespaces of their own, links cut too (root)");
    callBenchmark(cmd, run, a, bench::chaos, [](const toml::table& r) { return bench::chaosPassed(r) ? 0 : 1; });
}

}  // namespace rtwall::cli
