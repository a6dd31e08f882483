// Micro-benchmarks of single tiles with Google Benchmark (Embree's tutorials do the same with a
// Rays/s counter). `rtwall bench ...` gives whole-frame figures; this isolates one tile so that
// perf and callgrind see only the kernel; the denoiser's, one frame's filter alone (the camera
// moves a hair each time, so the history is re-projected as on a walking wall).
//   build/tools/rtwall_bench_micro --benchmark_format=json
#include <rtwall/denoise.h>
#include <rtwall/engine.h>

#include <benchmark/benchmark.h>

#include <memory>

namespace {

struct Fixture {
    rtwall::SceneDesc desc = rtwall::builtinScene("knots", 1'000'000);
    rtwall::Scene scene{desc};
};

Fixture& fixture() {
    static Fixture f;
    return f;
}

void renderOneTile(benchmark::State& state, rtwall::KernelType kernel, rtwall::ShadingMode shading) {
    Fixture& f = fixture();
    rtwall::RenderSettings s = f.desc.settings;
    s.kernel = kernel;
    s.shading = shading;
    const int tile = int(state.range(0));
    const rtwall::Camera camera(f.desc.cameras.front(), s.width, s.height);
    // A tile in the middle of the image, where the knots are.
    const rtwall::TileRect rect{s.width / 2 - tile / 2, s.height / 2 - tile / 2, s.width / 2 + tile / 2,
                                s.height / 2 + tile / 2};
    std::vector<uint8_t> out(size_t(tile) * tile * 3);
    uint64_t rays = 0;
    for (auto _ : state) {
        const rtwall::TileStats st = rtwall::renderTile(f.scene, camera, rect, 0, s, {out.data(), size_t(tile) * 3});
        rays += st.rays + st.shadowRays;
        benchmark::DoNotOptimize(out.data());
    }
    state.counters["Rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
}

void packetEyeLight(benchmark::State& s) { renderOneTile(s, rtwall::KernelType::Packet, rtwall::ShadingMode::EyeLight); }
void singleEyeLight(benchmark::State& s) { renderOneTile(s, rtwall::KernelType::Single, rtwall::ShadingMode::EyeLight); }
void packetFull(benchmark::State& s) { renderOneTile(s, rtwall::KernelType::Packet, rtwall::ShadingMode::Full); }
void singleFull(benchmark::State& s) { renderOneTile(s, rtwall::KernelType::Single, rtwall::ShadingMode::Full); }

BENCHMARK(packetEyeLight)->Arg(16)->Arg(32)->Arg(64);
BENCHMARK(singleEyeLight)->Arg(32);
BENCHMARK(packetFull)->Arg(32);
BENCHMARK(singleFull)->Arg(32);

// One 320x240 frame of the knots with GI (one sample a pixel) denoised again and again, one
// thread: the mode's phases (temporal: re-projection and the moving average alone).
void denoiseFrame(benchmark::State& state, rtwall::DenoiseSettings::Mode mode) {
    static const struct Frame {
        rtwall::SceneDesc desc = [] {
            rtwall::SceneDesc d = rtwall::builtinScene("knots", 200'000);
            d.settings.width = 320;
            d.settings.height = 240;
            d.settings.gi = true;
            d.settings.samples = 1;
            return d;
        }();
        rtwall::Scene scene{desc};
        rtwall::FeatureFrame f = rtwall::renderFrameFeatures(
            scene, rtwall::Camera(desc.cameras.front(), desc.settings.width, desc.settings.height), desc.settings, 1);
    } frame;
    const int w = frame.desc.settings.width, h = frame.desc.settings.height;
    rtwall::DenoiseSettings settings;
    settings.mode = mode;
    rtwall::Denoiser denoiser;
    rtwall::CameraDesc camera = frame.desc.cameras.front();
    for (auto _ : state) {
        camera.position.x += 1e-4f;
        const auto out = denoiser.denoise({w, h, frame.f.linear, frame.f.depth, frame.f.albedo, frame.f.normal,
                                           frame.f.id, camera, 0},
                                          settings, 1);
        benchmark::DoNotOptimize(out.data());
    }
    state.counters["Mpixels/s"] = benchmark::Counter(double(state.iterations()) * w * h * 1e-6, benchmark::Counter::kIsRate);
}
void denoiseTemporal(benchmark::State& s) { denoiseFrame(s, rtwall::DenoiseSettings::Mode::Temporal); }
void denoiseSvgf(benchmark::State& s) { denoiseFrame(s, rtwall::DenoiseSettings::Mode::Svgf); }

BENCHMARK(denoiseTemporal);
BENCHMARK(denoiseSvgf);

}  // namespace

BENCHMARK_MAIN();
