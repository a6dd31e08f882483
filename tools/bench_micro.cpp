// Micro-benchmarks of single tiles with Google Benchmark (Embree's tutorials do the same with a
// Rays/s counter). `rtwall bench ...` gives whole-frame figures; this isolates one tile so that
// perf and callgrind see only the kernel.
//   build/tools/rtwall_bench_micro --benchmark_format=json
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

}  // namespace

BENCHMARK_MAIN();
