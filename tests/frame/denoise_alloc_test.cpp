// The denoiser's hot path (issue 28: "no allocation per frame"): after the first frame of a size
// and thread count, a frame allocates nothing on any thread, moving or still, svgf or temporal;
// its threads stay between frames, restart when their number changes, and a copy of a
// Denoiser runs on threads of its own with the same history. Its own program: it counts every
// operator new of the process.
#include <rtwall/denoise.h>

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>
#include <random>
#include <vector>

namespace {
std::atomic<long> allocations{0};
}  // namespace

void* operator new(std::size_t n) {
    allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void* operator new(std::size_t n, std::align_val_t a) {
    allocations.fetch_add(1, std::memory_order_relaxed);
    const std::size_t al = std::size_t(a);
    if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace rtwall {
namespace {

// A plane facing the camera with a step in depth (two surfaces), noisy colour.
struct Frame {
    int w = 64, h = 48;
    std::vector<float> rgb, depth, albedo, normal;
    std::vector<uint32_t> id;
    CameraDesc camera;
    Frame() {
        const size_t n = size_t(w) * size_t(h);
        rgb.assign(n * 3, 0.5f);
        depth.assign(n, 5.0f);
        albedo.assign(n * 3, 0.8f);
        normal.assign(n * 3, 0.0f);
        id.assign(n, 1u);
        for (size_t i = 0; i < n; ++i) {
            normal[3 * i + 2] = 1.0f;
            if (i % size_t(w) > 40) depth[i] = 6.0f, id[i] = 2u;
        }
        camera.position = {0, 0, 5};
        camera.lookAt = {0, 0, 0};
    }
    void noise(uint32_t seed) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(0.2f, 0.8f);
        for (float& v : rgb) v = u(rng);
    }
    DenoiseInput input() const {
        DenoiseInput in;
        in.width = w, in.height = h;
        in.linear = rgb, in.depth = depth, in.albedo = albedo, in.normal = normal, in.id = id;
        in.camera = camera;
        return in;
    }
};

DenoiseSettings settings(DenoiseSettings::Mode m) {
    DenoiseSettings s;
    s.mode = m;
    return s;
}

TEST(DenoiserHotPath, AFrameAllocatesNothingAfterTheFirst) {
    for (auto m : {DenoiseSettings::Mode::Svgf, DenoiseSettings::Mode::Temporal})
        for (int threads : {1, 2, 3}) {
            Frame f;
            Denoiser d;
            f.noise(1);
            const long start = allocations.load();
            d.denoise(f.input(), settings(m), threads);  // sizes the buffers, starts the threads
            EXPECT_GT(allocations.load() - start, 0) << "the count sees the first frame's buffers";
            for (int k = 2; k <= 5; ++k) {
                f.noise(uint32_t(k));
                if (k < 4) f.camera.position.x += 0.01f;  // moving, then still
                const long before = allocations.load();
                d.denoise(f.input(), settings(m), threads);
                EXPECT_EQ(allocations.load() - before, 0) << denoiseModeName(m) << ", " << threads << " threads, frame " << k;
            }
        }
}

TEST(DenoiserHotPath, ThreadsRestartWhenTheirNumberChangesAndACopyHasItsOwn) {
    std::vector<float> want, got;
    {
        Frame f;
        Denoiser d;
        for (int k = 1; k <= 4; ++k) {
            f.noise(uint32_t(k));
            f.camera.position.x += 0.01f;
            const auto o = d.denoise(f.input(), settings(DenoiseSettings::Mode::Svgf), 2);
            want.assign(o.begin(), o.end());
        }
    }
    Frame f;
    Denoiser d;
    const int threads[] = {3, 1, 2};
    for (int k = 1; k <= 3; ++k) {
        f.noise(uint32_t(k));
        f.camera.position.x += 0.01f;
        d.denoise(f.input(), settings(DenoiseSettings::Mode::Svgf), threads[k - 1]);
    }
    Denoiser copy = d;  // the history, and threads of its own
    f.noise(4);
    f.camera.position.x += 0.01f;
    const auto a = copy.denoise(f.input(), settings(DenoiseSettings::Mode::Svgf), 2);
    got.assign(a.begin(), a.end());
    EXPECT_EQ(0, std::memcmp(want.data(), got.data(), want.size() * sizeof(float)));
    const auto b = d.denoise(f.input(), settings(DenoiseSettings::Mode::Svgf), 3);
    EXPECT_EQ(0, std::memcmp(want.data(), b.data(), want.size() * sizeof(float)));
}

}  // namespace
}  // namespace rtwall
