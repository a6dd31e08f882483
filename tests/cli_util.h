// Running the rtwall executable from a test, as a user would: one helper for every CLI test.
// Header-only and free of the libraries, so the display tests (which must not link the engine)
// use it too.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace rtwall::test {

struct CliResult {
    int status = -1;
    std::string output;  // stdout and stderr together
};

// Runs `rtwall ARGS` under `timeout` (a hung command fails its test instead of the suite), with
// `envPrefix` (e.g. "env -u DISPLAY") in front.
inline CliResult runCli(const std::string& exe, const std::string& args, int timeoutSeconds = 120,
                        const std::string& envPrefix = "") {
    const std::string cmd = envPrefix + (envPrefix.empty() ? "" : " ") + "timeout " + std::to_string(timeoutSeconds) + " " +
                            exe + " " + args + " 2>&1";
    CliResult r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    const int st = pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    return r;
}

}  // namespace rtwall::test
