// What the benchmark commands share: --json and the call into tools/bench/ (bench.h, speed.h).
#pragma once

#include "commands.h"

#include <toml++/toml.h>

#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>

namespace rtwall::cli {

// A benchmark's options as the command line fills them, and --json.
template <class Options> struct BenchArgs {
    Options options;
    bool json = false;
};

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
