#include "decode_pool.h"

#include <pthread.h>

namespace rtwall::cluster {

DecodePool::DecodePool(FrameAssembler& assembler, int threads, std::function<void()> onComplete,
                       std::function<void(uint32_t)> onFailure)
    : assembler_(assembler), onComplete_(std::move(onComplete)), onFailure_(std::move(onFailure)) {
    for (int i = 0; i < threads; ++i) workers_.emplace_back([this] {
        pthread_setname_np(pthread_self(), "rtw-decode");  // for rtwall bench cluster's CPU split
        run();
    });
}

void DecodePool::run() {
    std::vector<uint8_t> scratch;  // a linear tile's half floats or its depth codes, reused
    for (;;) {
        Job job;
        {
            std::unique_lock lock(m_);
            cv_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
            if (jobs_.empty()) return;
            job = std::move(jobs_.front());
            jobs_.pop_front();
        }
        try {
            if (job.format == TilePixels::LinearHalf) {
                // Into the linear frame, and quantised into the 8-bit one for display.
                const size_t stride = job.linearStride;
                float* dst = job.linear;
                decodeWideTile(job.codec, job.pixels.data(), job.pixels.size(), job.rect.width(),
                               job.rect.height(), dst, stride, scratch);
                for (int y = 0; y < job.rect.height(); ++y)
                    linearToSrgb8(dst + size_t(y) * stride, size_t(job.rect.width()) * 3,
                                  job.view.data + size_t(y) * job.view.stride);
            } else {
                decodeTile(job.codec, job.pixels.data(), job.pixels.size(), job.rect.width(), job.rect.height(),
                           job.view.data, job.view.stride);
            }
            // A depth that does not decode drops the whole tile: it is rendered again, both
            // halves (what its pixels wrote is overwritten then).
            if (job.depth)
                decodeDepthTile(kDepthCodec, job.depthBytes.data(), job.depthBytes.size(), job.rect.width(),
                                job.rect.height(), job.depth, job.depthStride, scratch);
            if (job.features)
                decodeFeatureTile(job.features, job.featureBytes.data(), job.featureBytes.size(), job.rect.width(),
                                  job.rect.height(), job.featureView, scratch);
            assembler_.commit(job.tile);
            if (assembler_.complete()) onComplete_();
        } catch (const std::exception&) {
            // A result that does not decode is dropped: the tile becomes claimable again
            // and the network thread reopens it in the scheduler, so someone renders it.
            assembler_.release(job.tile);
            ++failures_;
            onFailure_(job.tile);
        }
    }
}

}  // namespace rtwall::cluster
