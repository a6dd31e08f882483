// A terminal progress bar with rate and time left, and Ctrl-C handling, for the long steps
// (import, cache writing, BVH build). Quiet when stderr is not a terminal, and for steps that end
// within a second.
#pragma once

#include <rtwall/mesh.h>

#include <atomic>
#include <chrono>
#include <string>

namespace rtwall::bench {

// Installs a SIGINT handler that sets a flag (once per process). The first Ctrl-C asks the
// running step to stop at its next progress report; a second one ends the process at once.
void installInterruptHandler();
bool interrupted();

class ProgressBar {
public:
    // `total` units of `unit` (e.g. "MB", "Mtri") for the rate.
    ProgressBar(std::string label, double total, std::string unit);
    ~ProgressBar();
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;
    // A ProgressFn for the libraries: draws and returns false after Ctrl-C.
    ProgressFn fn();
    bool update(double fraction);

private:
    std::string label_, unit_;
    double total_;
    std::chrono::steady_clock::time_point start_, lastDraw_;
    bool tty_, drawn_ = false;
};

}  // namespace rtwall::bench
