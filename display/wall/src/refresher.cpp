// Refresher (refresher.h): one worker thread for the whole session, handed one render at a time.
#include "refresher.h"

#include <algorithm>

namespace rtwall::wall {

Refresher::Refresher(double refreshHz, bool paced)
    : period_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / std::max(1.0, refreshHz)))),
      paced_(paced),
      worker_([this] { work(); }) {}

Refresher::~Refresher() {
    {
        std::lock_guard lock(m_);
        quit_ = true;
    }
    cv_.notify_all();
    worker_.join();
}

void Refresher::work() {
    std::unique_lock lock(m_);
    for (;;) {
        cv_.wait(lock, [this] { return quit_ || job_; });
        if (quit_) return;
        const std::function<void()>* job = job_;
        lock.unlock();
        std::exception_ptr error;
        try {
            (*job)();
        } catch (...) {
            error = std::current_exception();
        }
        lock.lock();
        job_ = nullptr;
        error_ = error;
        done_ = true;
        cv_.notify_all();
    }
}

void Refresher::run(const std::function<void()>& render, const std::function<void()>& present, bool canPresent) {
    // A refresh long past (the first frame, or a step that took long between renders) is now.
    if (const Clock::time_point now = Clock::now(); next_ + period_ < now) next_ = now;
    std::unique_lock lock(m_);
    done_ = false;
    error_ = nullptr;
    job_ = &render;
    cv_.notify_all();
    for (;;) {
        if (paced_ || !canPresent) {
            // Wait for the next refresh, or for the render to end first. Without anything to show
            // yet, only for the render.
            if (canPresent) cv_.wait_until(lock, next_, [this] { return done_; });
            else cv_.wait(lock, [this] { return done_; });
        }
        if (done_) break;
        lock.unlock();
        present();
        const Clock::time_point now = Clock::now();
        // The next refresh is a period after this one's; one that is already over is skipped.
        next_ += period_;
        if (next_ <= now) {
            const auto behind = (now - next_) / period_ + 1;
            missed_ += uint64_t(behind);
            next_ += behind * period_;
        }
        lock.lock();
    }
    std::exception_ptr error = error_;
    error_ = nullptr;
    lock.unlock();
    if (error) std::rethrow_exception(error);
}

}  // namespace rtwall::wall
