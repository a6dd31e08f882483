// Sub-command registration for the rtwall executable. Each command adds its options to the
// CLI11 app and returns the function that runs it.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <string>

namespace rtwall::cli {

using Run = std::function<int()>;

// A command of `parent` whose one required argument is a string (a path): running it is `work(argument)`.
inline void addCommandOfOneArgument(CLI::App& parent, Run& run, const std::string& name, const std::string& description,
                                    const std::string& argument, const std::string& help,
                                    std::function<int(const std::string&)> work) {
    auto value = std::make_shared<std::string>();
    CLI::App* cmd = parent.add_subcommand(name, description);
    cmd->add_option(argument, *value, help)->required();
    cmd->callback([&run, value, work] { run = [value, work] { return work(*value); }; });
}

// --denoise-isa: the denoiser's instruction set in this process (rtwall/denoise.h, DenoiseIsa),
// applied by applyDenoiseIsa before the command runs (one line for a CPU that lacks it).
inline void addDenoiseIsaOption(CLI::App* cmd, std::string& isa) {
    cmd->add_option("--denoise-isa", isa,
                    "The denoiser's instruction set: auto (the widest this CPU has), sse2, avx2 or avx512; the same bytes, "
                    "only the speed differs")
        ->check(CLI::IsMember({"auto", "sse2", "avx2", "avx512"}));
}
void applyDenoiseIsa(const std::string& isa);  // cmd_render.cpp; empty: auto

void addRender(CLI::App& app, Run& run);
void addInfo(CLI::App& app, Run& run);
void addClient(CLI::App& app, Run& run);
void addDisplay(CLI::App& app, Run& run);  // cmd_display.cpp (issue 19)
void addRun(CLI::App& app, Run& run);
void addControls(CLI::App& app, Run& run);  // cmd_run.cpp
void addKeys(CLI::App& app, Run& run);
void addBenchKernel(CLI::App& bench, Run& run);
void addBenchCluster(CLI::App& bench, Run& run);
void addBenchFaults(CLI::App& bench, Run& run);
void addBenchAttack(CLI::App& bench, Run& run);  // bench_attack.cpp (issue 16)
void addBenchChaos(CLI::App& bench, Run& run);
void addBenchUpdates(CLI::App& bench, Run& run);  // bench_updates.cpp (issue 17)
void addBenchWeb(CLI::App& bench, Run& run);      // bench_web.cpp (issue 31)
void addBenchLatency(CLI::App& bench, Run& run);  // bench_latency.cpp (issue 18)
void addCheck(CLI::App& app, Run& run);
void addBenchDisplay(CLI::App& bench, Run& run);
void addGen(CLI::App& app, Run& run);
void addBenchScene(CLI::App& bench, Run& run);
// Speed against accuracy (cmd_speed.cpp).
void addCompare(CLI::App& app, Run& run);
void addReference(CLI::App& app, Run& run);
void addSimulate(CLI::App& app, Run& run);
void addBenchTiles(CLI::App& bench, Run& run);
void addBenchCodecs(CLI::App& bench, Run& run);
void addBenchShading(CLI::App& bench, Run& run);
void addBenchTessellation(CLI::App& bench, Run& run);  // bench_tessellation.cpp (issue 20)
void addBenchWarp(CLI::App& bench, Run& run);          // bench_warp.cpp (issue 30)
void addBenchReproject(CLI::App& bench, Run& run);  // bench_reproject.cpp (issue 27)
void addBenchDenoise(CLI::App& bench, Run& run);    // bench_denoise.cpp (issue 28)
void addTrackerSim(CLI::App& app, Run& run);  // cmd_tracker_sim.cpp (issue 18)

}  // namespace rtwall::cli
