// The refresh loop of a re-projecting wall (issue 27): the cluster renders the next frame on a
// worker thread while the calling thread presents at the display's refresh, so the wall never
// waits for the cluster.
#pragma once

#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

namespace rtwall::wall {

class Refresher {
public:
    using Clock = std::chrono::steady_clock;

    // `refreshHz`: the presentations a second. `paced`: this loop keeps the rate by waiting for
    // each refresh (headless, windows without vsync); else the presenter's swap waits for the
    // retrace and the loop presents back to back.
    Refresher(double refreshHz, bool paced);
    ~Refresher();
    Refresher(const Refresher&) = delete;
    Refresher& operator=(const Refresher&) = delete;

    // Runs `render` on the worker thread and, until it returns, `present` on this thread at every
    // refresh. Returns as soon as `render` has, without waiting for the next refresh (the caller
    // shows the new frame at once); rethrows what `render` threw. `present` is not called when
    // `canPresent` is false (nothing to show yet). The functions must outlive the call.
    void run(const std::function<void()>& render, const std::function<void()>& present, bool canPresent);
    // A presentation happened outside run() (the new frame's): the next refresh is a period after it.
    void presented() { next_ = Clock::now() + period_; }
    Clock::duration period() const { return period_; }
    uint64_t missedRefreshes() const { return missed_; }  // refreshes skipped: a presentation took longer than its period

private:
    Clock::duration period_;
    bool paced_;
    Clock::time_point next_{};
    uint64_t missed_ = 0;

    std::mutex m_;
    std::condition_variable cv_;
    const std::function<void()>* job_ = nullptr;  // set: the worker runs it
    bool done_ = false, quit_ = false;
    std::exception_ptr error_;
    std::thread worker_;

    void work();
};

}  // namespace rtwall::wall
