// The denoiser's threads (rtwall/denoise.h's DenoiseWorkerPool holds them): private to
// engine/frame's denoise*.cpp.
#pragma once

#include <rtwall/denoise.h>

#include <atomic>
#include <barrier>
#include <cstdint>
#include <thread>
#include <vector>

namespace rtwall {

// Threads that live as long as their Denoiser: each frame sets the job and bumps the generation,
// every worker runs its part and counts down, and the caller runs part 0 and waits for the count.
// The phases inside a job meet at the one barrier. No lock, no allocation per frame.
class DenoiseWorkers {
public:
    explicit DenoiseWorkers(int threads) : threads_(threads), sync_(threads) {
        pool_.reserve(size_t(threads - 1));
        for (int part = 1; part < threads; ++part) pool_.emplace_back([this, part] { loop(part); });
    }
    ~DenoiseWorkers() {
        stop_.store(true, std::memory_order_relaxed);
        generation_.fetch_add(1, std::memory_order_release);
        generation_.notify_all();
        pool_.clear();  // joins
    }
    DenoiseWorkers(const DenoiseWorkers&) = delete;
    DenoiseWorkers& operator=(const DenoiseWorkers&) = delete;
    int threads() const { return threads_; }
    std::barrier<>& sync() { return sync_; }
    // job(context, part) for every part; returns when all are done.
    void run(void (*job)(void*, int), void* context) {
        job_ = job;
        context_ = context;
        remaining_.store(threads_ - 1, std::memory_order_relaxed);
        generation_.fetch_add(1, std::memory_order_release);
        generation_.notify_all();
        job(context, 0);
        for (int left = remaining_.load(std::memory_order_acquire); left != 0; left = remaining_.load(std::memory_order_acquire))
            remaining_.wait(left, std::memory_order_acquire);
    }

private:
    void loop(int part) {
        uint64_t seen = 0;
        for (;;) {
            generation_.wait(seen, std::memory_order_acquire);
            seen = generation_.load(std::memory_order_acquire);
            if (stop_.load(std::memory_order_relaxed)) return;
            job_(context_, part);
            if (remaining_.fetch_sub(1, std::memory_order_acq_rel) == 1) remaining_.notify_one();
        }
    }

    int threads_;
    std::barrier<> sync_;
    std::atomic<uint64_t> generation_{0};
    std::atomic<int> remaining_{0};
    std::atomic<bool> stop_{false};
    void (*job_)(void*, int) = nullptr;
    void* context_ = nullptr;
    std::vector<std::jthread> pool_;  // last: its threads start once the rest is built
};

}  // namespace rtwall
