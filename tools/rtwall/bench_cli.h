// What the benchmark commands share: --json and the call into tools/bench/ (bench.h, speed.h).
#pragma once

#include "commands.h"

#include <toml++/toml.h>

#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <string>

namespace rtwall::cli {

// A benchmark's options as the command line fills them, and --json.
template <class Options> struct BenchArgs {
    Options options;
    bool json = false;
};

// A benchmark's subcommand of `parent` and the options its command line fills.
template <class Options> struct BenchCommand {
    std::shared_ptr<BenchArgs<Options>> args;
    Options& options;  // args->options
    CLI::App* cmd;
};

template <class Options>
BenchCommand<Options> benchCommand(CLI::App& parent, const std::string& name, const std::string& description) {
    auto args = std::make_shared<BenchArgs<Options>>();
    return {args, args->options, parent.add_subcommand(name, description)};
}

// The options many benchmarks share, with their help text "<what> width<note>" and so on.
inline void addSizeOptions(CLI::App* cmd, int& width, int& height, int min, int max, const std::string& what = "Image",
                           const std::string& note = "") {
    cmd->add_option("--width", width, what + " width" + note)->check(CLI::Range(min, max));
    cmd->add_option("--height", height, what + " height" + note)->check(CLI::Range(min, max));
}

inline void addTrianglesOption(CLI::App* cmd, int64_t& triangles, const std::string& help, int64_t max = 100'000'000) {
    cmd->add_option("--triangles", triangles, help)->check(CLI::Range(int64_t(1000), max));
}

inline void addThreadsOption(CLI::App* cmd, int& threads, const std::string& help) {
    cmd->add_option("--threads", threads, help)->check(CLI::Range(0, 1024));
}

// Where the master listens and the clients start, for runs inside tools/netem.sh's namespaces.
inline void addNetemOptions(CLI::App* cmd, std::string& bind, std::string& netns, std::string& link,
                            const std::string& bindHelp, const std::string& netnsHelp) {
    cmd->add_option("--bind", bind, bindHelp);
    cmd->add_option("--client-netns", netns, netnsHelp);
    cmd->add_option("--link", link, "Description of the link, copied into the output");
}

// Adds --json and makes `run` call `benchmark`: its lines on stdout as it goes, or, with --json,
// only its result as JSON. The exit status is `status(result)` (0 when not given).
template <class Options, class Benchmark>
void callBenchmark(CLI::App* cmd, Run& run, std::shared_ptr<BenchArgs<Options>> a, Benchmark benchmark,
                   std::function<int(const toml::table&)> status = {}, bool addJsonFlag = true) {
    if (addJsonFlag) cmd->add_flag("--json", a->json, "Print JSON");
    cmd->callback([&run, a, benchmark, status] {
        run = [a, benchmark, status] {
            a->options.text = a->json ? nullptr : stdout;
            const toml::table result = benchmark(a->options);
            if (a->json) std::cout << toml::json_formatter{result} << "\n";
            return status ? status(result) : 0;
        };
    });
}

}  // namespace rtwall::cli
