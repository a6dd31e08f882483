// Decodes accepted tiles into the master's frame on a few threads.
#pragma once

#include "codec.h"
#include "protocol.h"

#include <rtwall/frame.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace rtwall::cluster {

// Tiles accepted by the network thread wait in a queue; each decode thread takes one, decodes
// it straight into the assembler's frame and commits it there.
class DecodePool {
public:
    struct Job {
        std::vector<uint8_t> pixels;  // encoded
        TileCodec codec;
        uint32_t tile;
        TileRect rect;
        TileView view;
        TilePixels format = TilePixels::Srgb8;
        float* linear = nullptr;  // LinearHalf: the tile's first pixel in the frame's linear buffer
        size_t linearStride = 0;  // floats from one row of that buffer to the next
        std::vector<uint8_t> depthBytes;  // encoded depth (encodeDepthTile), when the frame has depth
        float* depth = nullptr;  // then the tile's first pixel in the view's depth buffer
        size_t depthStride = 0;  // floats from one row of it to the next
        std::vector<uint8_t> featureBytes;  // encoded features (encodeFeatureTile), when the frame has them
        uint8_t features = 0;               // which
        FeatureView featureView{};          // then the tile's first pixel in the view's feature buffers
    };

    // `onComplete`: the frame is complete (called on a decode thread); `onFailure`: a tile did
    // not decode and is claimable again.
    DecodePool(FrameAssembler& assembler, int threads, std::function<void()> onComplete,
               std::function<void(uint32_t)> onFailure);
    ~DecodePool() {
        {
            std::lock_guard lock(m_);
            stop_ = true;
        }
        cv_.notify_all();
        for (auto& t : workers_) t.join();
    }
    void push(Job job) {
        {
            std::lock_guard lock(m_);
            jobs_.push_back(std::move(job));
        }
        cv_.notify_one();
    }
    uint64_t failures() const { return failures_.load(); }

private:
    void run();

    FrameAssembler& assembler_;
    std::function<void()> onComplete_;
    std::function<void(uint32_t)> onFailure_;
    std::mutex m_;
    std::condition_variable cv_;
    std::deque<Job> jobs_;
    bool stop_ = false;
    std::atomic<uint64_t> failures_{0};
    std::vector<std::thread> workers_;
};

}  // namespace rtwall::cluster
