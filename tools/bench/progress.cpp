#include "progress.h"

#include <csignal>
#include <cstdio>
#include <unistd.h>

namespace rtwall::bench {

namespace {

std::atomic<int> gInterrupts{0};

extern "C" void onInterrupt(int) {
    if (gInterrupts.fetch_add(1) >= 1) _exit(130);  // a second Ctrl-C: stop now
}

}  // namespace

void installInterruptHandler() {
    static const bool installed = [] {
        struct sigaction sa {};
        sa.sa_handler = onInterrupt;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGINT, &sa, nullptr);
        return true;
    }();
    (void)installed;
}

bool interrupted() { return gInterrupts.load() > 0; }

ProgressBar::ProgressBar(std::string label, double total, std::string unit)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total), start_(std::chrono::steady_clock::now()),
      lastDraw_(start_), tty_(isatty(STDERR_FILENO) != 0) {}

ProgressBar::~ProgressBar() {
    if (drawn_) {
        update(1.0);
        std::fputc('\n', stderr);
    }
}

ProgressFn ProgressBar::fn() {
    return [this](double f) { return update(f); };
}

bool ProgressBar::update(double fraction) {
    if (interrupted()) return false;
    if (!tty_) return true;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    // Nothing for steps under a second, then at most ten redraws a second.
    if (elapsed < 1.0 || (fraction < 1.0 && std::chrono::duration<double>(now - lastDraw_).count() < 0.1)) return true;
    lastDraw_ = now;
    drawn_ = true;
    fraction = std::min(1.0, std::max(0.0, fraction));
    const int width = 30, filled = int(fraction * width);
    const double rate = fraction * total_ / elapsed;
    const double left = fraction > 0 ? elapsed * (1 - fraction) / fraction : 0;
    char rateText[64] = "";
    if (!unit_.empty()) std::snprintf(rateText, sizeof rateText, "  %.1f %s/s", rate, unit_.c_str());
    std::fprintf(stderr, "\r%-14s [%.*s%*s] %3d%%%s  %4.0f s left ", label_.c_str(), filled,
                 "##############################", width - filled, "", int(fraction * 100), rateText, left);
    std::fflush(stderr);
    return true;
}

}  // namespace rtwall::bench
