// Small helpers every benchmark subcommand shares: medians (rtwall/tune.h) and timing.
#pragma once

#include <rtwall/tune.h>

#include <chrono>

namespace rtwall::cli {

// Wall-clock seconds that f takes.
template <class F> double secondsOf(F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Wall-clock seconds since construction or the last restart().
class Stopwatch {
public:
    double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
    void restart() { start_ = std::chrono::steady_clock::now(); }

private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace rtwall::cli
