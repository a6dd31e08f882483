// rtwall bench denoise (issue 28): what the denoiser buys. A camera orbits its scene's first
// camera's look-at point, arriving at that camera on the last frame; each frame is rendered with
// GI (gi_spp samples a pixel), its features and depth (renderFrameFeatures), denoised
// (rtwall/denoise.h: off, temporal, svgf) and scored against a converged reference of that very
// view (reference_spp samples, rendered once per scored frame and shared by every setting): PSNR
// and mean FLIP of the 8-bit images, median and the worst 5 %. Then the camera stops there and
// the view stays still for flicker_frames frames: the flicker is the mean absolute change of the
// shown luminance from frame to frame, from the last moving frame on, against the reference's own
// (two independent converged renders of the view): what a viewer sees when the walk stops (`off`
// accumulates from the stop, as the wall does; the filters go on with their history). Then the
// same view from a cold start (a cut): how long until the shown image reaches 40 dB, and the
// flicker of its first frames (flicker_cold). fps: one over the median of render + denoise per
// frame on this machine's threads (no cluster); denoise_ms the filter alone.
#include "bench.h"
#include "bench_util.h"
#include "generators.h"

#include <rtwall/denoise.h>
#include <rtwall/engine.h>
#include <rtwall/tune.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

namespace rtwall::bench {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The worst 5 %: the value 95 % of the frames are at least as good as.
double worst5(std::vector<double> v, bool higherIsBetter) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const size_t k = size_t(std::floor(0.05 * double(v.size() - 1) + 0.5));
    return higherIsBetter ? v[k] : v[v.size() - 1 - k];
}

double finiteDb(double db) { return std::isfinite(db) ? db : kIdenticalPsnr; }

// Mean absolute change of the luminance (0..1 of the 8-bit codes) between two images.
double luminanceChange(const Image& a, const Image& b) {
    double sum = 0;
    const size_t n = a.rgb.size() / 3;
    for (size_t i = 0; i < n; ++i) {
        auto lum = [](const uint8_t* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; };
        sum += std::fabs(lum(&a.rgb[3 * i]) - lum(&b.rgb[3 * i]));
    }
    return n ? sum / (255.0 * double(n)) : 0.0;
}

struct BenchSceneDesc {
    SceneDesc desc;
    CameraDesc camera;
};

BenchSceneDesc loadBenchScene(const std::string& name, const DenoiseOptions& o) {
    BenchSceneDesc s;
    const std::filesystem::path dir = std::filesystem::path(o.dir) / name;
    if (name == "office") {
        s.desc = loadSceneFile(gen::writeShadingDemo("office", dir));
    } else if (name == "demo") {
        s.desc = loadSceneFile(o.demo);
    } else if (name == "sunflowers") {
        gen::GenOptions g;
        g.out = dir;
        g.instances = 400;
        g.trees = 2;
        g.cache = false;
        gen::genSunflowers(g);
        s.desc = loadSceneFile(dir / "scene.toml");
    } else {
        throw InputError("bench denoise: unknown scene '" + name + "' (office, demo, sunflowers)");
    }
    if (s.desc.cameras.empty()) throw InputError("bench denoise: scene '" + name + "' has no camera");
    s.camera = s.desc.cameras.front();
    if (!o.camera.empty()) {
        const CameraDesc* c = s.desc.findCamera(o.camera);
        if (!c) throw InputError("bench denoise: scene '" + name + "' has no camera '" + o.camera + "'");
        s.camera = *c;
    }
    return s;
}

struct Setting {
    DenoiseSettings::Mode mode;
    int spp;
};

}  // namespace

toml::table denoise(const DenoiseOptions& o) {
    toml::table out{{"benchmark", "denoise"},
                    {"frames", o.frames},
                    {"score_every", o.scoreEvery},
                    {"degrees_per_frame", o.degreesPerFrame},
                    {"reference_spp", o.referenceSpp},
                    {"still_reference_spp", o.stillReferenceSpp},
                    {"still_seconds", o.stillSeconds},
                    {"threads", o.threads},
                    {"flip", "mean LDR-FLIP, 67 pixels per degree"},
                    {"p95", "the value 95 % of scored frames are at least as good as (PSNR: 5th percentile)"},
                    {"flicker", "mean absolute change of the shown luminance (0..1) from frame to frame on a camera that "
                                "stopped after the orbit, over flicker_frames frames from the last moving one; flicker_cold: "
                                "the same over the first frames after a cut (a cold start); reference_flicker: between two "
                                "converged references"},
                    {"flicker_frames", o.flickerFrames},
                    {"fps", "one over the median of render + denoise per frame, this machine, no cluster"}};
    std::vector<DenoiseSettings::Mode> modes;
    for (const std::string& m : o.modes) modes.push_back(denoiseModeFromName(m));
    toml::array rows, filterCost;
    for (const std::string& name : o.scenes) {
        BenchSceneDesc bs = loadBenchScene(name, o);
        for (const std::string& size : o.sizes) {
            int w = 0, h = 0;
            if (std::sscanf(size.c_str(), "%dx%d", &w, &h) != 2 || w < 8 || h < 8 || w > 4096 || h > 4096)
                throw InputError("bench denoise: size '" + size + "' is not WIDTHxHEIGHT (8..4096)");
            SceneDesc d = bs.desc;
            d.settings.width = w;
            d.settings.height = h;
            d.settings.gi = true;
            d.settings.threads = o.threads;
            const Scene scene(d);
            RenderSettings ref = d.settings;
            ref.samples = o.referenceSpp;
            ref.pruneThreshold = std::min(ref.pruneThreshold, 0.0005f);
            // The references of the scored frames of the path, and of the still view (twice).
            std::vector<Image> refs(size_t(o.frames));
            auto scored = [&](int k) { return k % o.scoreEvery == o.scoreEvery - 1; };
            // Frame k's camera: the orbit arrives at the scene's camera (the still view) on the last
            // frame (turning against orbitCamera's sense: the path of the figures in docs/shading.md).
            auto pathCamera = [&](int k) {
                return k == o.frames - 1 ? bs.camera : orbitCamera(bs.camera, -o.degreesPerFrame * (o.frames - 1 - k));
            };
            const auto tRef = Clock::now();
            for (int k = 0; k < o.frames; ++k)
                if (scored(k)) {
                    const Camera cam(pathCamera(k), w, h);
                    refs[size_t(k)] = srgbImage(renderFrameLinear(scene, cam, ref, uint32_t(1'000'000 + k)), w, h);
                }
            const Camera still(bs.camera, w, h);
            RenderSettings stillRefSettings = ref;
            stillRefSettings.samples = o.stillReferenceSpp;
            const Image stillRef = srgbImage(renderFrameLinear(scene, still, stillRefSettings, 2'000'000), w, h);
            const Image stillRef2 = srgbImage(renderFrameLinear(scene, still, stillRefSettings, 2'000'001), w, h);
            const double referenceFlicker = luminanceChange(stillRef, stillRef2);
            const double referenceDb = finiteDb(psnrDb(stillRef, stillRef2));
            if (o.text)
                std::fprintf(o.text, "%s %dx%d: references in %.1f s (%d samples; the still view's two of %d differ by %.1f dB, "
                                     "flicker %.5f)\n",
                             name.c_str(), w, h, secondsSince(tRef), o.referenceSpp, o.stillReferenceSpp, referenceDb,
                             referenceFlicker);
            // The filter alone (svgf, the scene's settings): one frame's inputs denoised again and
            // again by a camera that moves a hair each time (re-projection and all), on one
            // thread and on all.
            {
                DenoiseSettings ds = d.denoise;
                ds.mode = DenoiseSettings::Mode::Svgf;
                if (o.levels) ds.levels = o.levels;
                RenderSettings one = d.settings;
                one.samples = 1;
                const FeatureFrame f = renderFrameFeatures(scene, still, one, 1);
                toml::table cost{{"scene", name}, {"width", w}, {"height", h}, {"levels", ds.levels}};
                for (int threads : {1, 0}) {
                    Denoiser dn;
                    std::vector<double> ms;
                    // One thread: where the time goes, the phases' medians (DenoiseStats::seconds).
                    std::vector<double> phase[5];
                    for (int k = 0; k < 12; ++k) {
                        CameraDesc c = bs.camera;
                        c.position.x += 1e-4f * float(k);
                        const auto t0 = Clock::now();
                        dn.denoise({w, h, f.linear, f.depth, f.albedo, f.normal, f.id, c, 0}, ds, threads);
                        if (k < 2) continue;
                        ms.push_back(1e3 * secondsSince(t0));
                        const DenoiseStats::Seconds& s = dn.stats().seconds;
                        const double parts[5] = {s.temporal, s.prepare, s.variance, s.atrous, s.finish};
                        for (int p = 0; p < 5; ++p) phase[p].push_back(1e3 * parts[p]);
                    }
                    if (threads == 1) {
                        cost.insert("isa", denoiseIsaName(dn.stats().isa));
                        toml::table phases;
                        const char* names[5] = {"temporal_ms", "prepare_ms", "variance_ms", "atrous_ms", "finish_ms"};
                        for (int p = 0; p < 5; ++p) phases.insert(names[p], median(phase[p]));
                        cost.insert("phases_one_thread", phases);
                    }
                    const double mp = double(w) * double(h) * 1e-6;
                    cost.insert(threads == 1 ? "ms_one_thread" : "ms_all_threads", median(ms));
                    cost.insert(threads == 1 ? "ms_per_megapixel_thread" : "ms_per_megapixel_all_threads", median(ms) / mp);
                }
                // Each instruction set this CPU has, on one thread, in the same run (the same bytes:
                // tested; here only the time): the a-trous tap loop and temporal reuse's row pass.
                {
                    const DenoiseIsa before = denoiseIsa();
                    toml::table byIsa, temporalByIsa;
                    for (DenoiseIsa isa : {DenoiseIsa::Sse2, DenoiseIsa::Avx2, DenoiseIsa::Avx512}) {
                        if (!denoiseIsaSupported(isa)) continue;
                        setDenoiseIsa(isa);
                        Denoiser dn;
                        std::vector<double> ms, temporalMs;
                        for (int k = 0; k < 12; ++k) {
                            CameraDesc c = bs.camera;
                            c.position.x += 1e-4f * float(k);
                            dn.denoise({w, h, f.linear, f.depth, f.albedo, f.normal, f.id, c, 0}, ds, 1);
                            if (k < 2) continue;
                            ms.push_back(1e3 * dn.stats().seconds.atrous);
                            temporalMs.push_back(1e3 * dn.stats().seconds.temporal);
                        }
                        byIsa.insert(denoiseIsaName(isa), median(ms));
                        temporalByIsa.insert(denoiseIsaName(isa), median(temporalMs));
                    }
                    setDenoiseIsa(before);
                    cost.insert("atrous_ms_one_thread_by_isa", byIsa);
                    cost.insert("temporal_ms_one_thread_by_isa", temporalByIsa);
                    if (o.text)
                        for (const auto& [what, table] : {std::pair{"the a-trous levels", &byIsa}, std::pair{"temporal reuse", &temporalByIsa}}) {
                            std::fprintf(o.text, "%s %dx%d: %s on one thread:", name.c_str(), w, h, what);
                            for (const auto& [isa, v] : *table)
                                std::fprintf(o.text, " %s %.1f ms", std::string(isa.str()).c_str(), v.value_or(0.0));
                            std::fprintf(o.text, "\n");
                        }
                }
                if (o.text)
                    std::fprintf(o.text, "%s %dx%d: the svgf filter alone takes %.1f ms on one thread (%.0f ms per megapixel), "
                                         "%.1f ms on all\n",
                                 name.c_str(), w, h, cost["ms_one_thread"].value_or(0.0),
                                 cost["ms_per_megapixel_thread"].value_or(0.0), cost["ms_all_threads"].value_or(0.0));
                if (o.text) {
                    const toml::table& ph = *cost["phases_one_thread"].as_table();
                    std::fprintf(o.text, "%s %dx%d: one thread's phases: temporal %.1f ms, prepare %.1f, variance %.1f, "
                                         "a-trous %.1f, finish %.1f\n",
                                 name.c_str(), w, h, ph["temporal_ms"].value_or(0.0), ph["prepare_ms"].value_or(0.0),
                                 ph["variance_ms"].value_or(0.0), ph["atrous_ms"].value_or(0.0), ph["finish_ms"].value_or(0.0));
                }
                filterCost.push_back(std::move(cost));
            }
            for (int spp : o.giSpp)
                for (DenoiseSettings::Mode mode : modes) {
                    DenoiseSettings ds = d.denoise;
                    ds.mode = mode;
                    if (o.levels) ds.levels = o.levels;
                    if (o.history) ds.history = o.history;
                    if (o.sigmaLuminance > 0) ds.sigmaLuminance = float(o.sigmaLuminance);
                    if (o.sigmaDepth > 0) ds.sigmaDepth = float(o.sigmaDepth);
                    if (o.sigmaNormal > 0) ds.sigmaNormal = float(o.sigmaNormal);
                    RenderSettings rs = d.settings;
                    rs.samples = spp;
                    // Moving.
                    Denoiser dn;
                    std::vector<double> frameS, denoiseS, db, flip;
                    Image lastMoving;
                    std::vector<float> lastLinear;  // the last moving frame's own samples (at the still view)
                    for (int k = 0; k < o.frames; ++k) {
                        const CameraDesc cd = pathCamera(k);
                        const Camera cam(cd, w, h);
                        const auto t0 = Clock::now();
                        const FeatureFrame f = renderFrameFeatures(scene, cam, rs, uint32_t(k + 1));
                        const double tr = secondsSince(t0);
                        std::span<const float> shown = f.linear;
                        const auto t1 = Clock::now();
                        if (mode != DenoiseSettings::Mode::Off)
                            shown = dn.denoise({w, h, f.linear, f.depth, f.albedo, f.normal, f.id, cd, 0}, ds, o.threads);
                        const double td = secondsSince(t1);
                        frameS.push_back(tr + td);
                        denoiseS.push_back(td);
                        if (k == o.frames - 1) {
                            lastMoving = srgbImage(shown, w, h);
                            lastLinear = f.linear;
                        }
                        if (!scored(k)) continue;
                        const Image img = srgbImage(shown, w, h);
                        db.push_back(finiteDb(psnrDb(img, refs[size_t(k)])));
                        flip.push_back(flipMean(img, refs[size_t(k)]));
                        if (!o.images.empty() && k == o.frames - 1 - (o.frames % o.scoreEvery)) {
                            std::filesystem::create_directories(o.images);
                            const std::string stem = "denoise_" + (o.tag.empty() ? "" : o.tag + "_") + name + "_" + std::to_string(w);
                            writePng(img, std::filesystem::path(o.images) /
                                              (stem + "_" + denoiseModeName(mode) + "_" + std::to_string(spp) + "spp.png"));
                            writePng(refs[size_t(k)], std::filesystem::path(o.images) / (stem + "_reference.png"));
                        }
                    }
                    // Stopped: the walk ends at the still view and the view stays; off accumulates
                    // from the last moving frame (the wall's accumulator restarts at a camera move
                    // and goes on while it stays), the filters go on with their history.
                    // A still frame as the wall shows it: off the running mean, else the filter's.
                    auto showStill = [&](Accumulator& mean, Denoiser& filter, const FeatureFrame& f) {
                        if (mode != DenoiseSettings::Mode::Off)
                            return srgbImage(filter.denoise({w, h, f.linear, f.depth, f.albedo, f.normal, f.id, bs.camera, 0}, ds,
                                                          o.threads),
                                           w, h);
                        mean.addLinear(f.linear.data(), w, h);
                        return mean.resolve();
                    };
                    double flicker = 0;
                    {
                        Accumulator stopped;
                        if (mode == DenoiseSettings::Mode::Off) stopped.addLinear(lastLinear.data(), w, h);
                        Image previous = lastMoving;
                        for (int k = 1; k <= o.flickerFrames; ++k) {
                            Image img = showStill(stopped, dn, renderFrameFeatures(scene, still, rs, uint32_t(o.frames + k)));
                            flicker += luminanceChange(img, previous) / o.flickerFrames;
                            previous = std::move(img);
                        }
                    }
                    // Still: accumulate (off) or denoise from a cold start until 40 dB or the time is up.
                    Denoiser sd;
                    Accumulator acc;
                    double elapsed = 0, to40 = -1, stillDb = 0, flickerCold = 0;
                    Image previous;
                    int stillFrames = 0;
                    for (int k = 0; elapsed < o.stillSeconds || k <= o.flickerFrames; ++k) {
                        const auto t0 = Clock::now();
                        Image img = showStill(acc, sd, renderFrameFeatures(scene, still, rs, uint32_t(5000 + k)));
                        elapsed += secondsSince(t0);
                        ++stillFrames;
                        stillDb = finiteDb(psnrDb(img, stillRef));
                        if (to40 < 0 && stillDb >= 40.0) to40 = elapsed;
                        if (k > 0 && k <= o.flickerFrames) flickerCold += luminanceChange(img, previous) / o.flickerFrames;
                        previous = std::move(img);
                        if (to40 >= 0 && k >= o.flickerFrames) break;
                    }
                    const double fps = 1.0 / median(frameS);
                    toml::table common{{"scene", name},
                                       {"levels", ds.levels},
                                       {"history", ds.history},
                                       {"sigma_luminance", ds.sigmaLuminance},
                                       {"width", w},
                                       {"height", h},
                                       {"denoise", denoiseModeName(mode)},
                                       {"gi_spp", spp},
                                       {"fps", fps},
                                       {"render_ms", 1e3 * (median(frameS) - median(denoiseS))},
                                       {"denoise_ms", 1e3 * median(denoiseS)},
                                       {"flicker", flicker},
                                       {"reference_flicker", referenceFlicker},
                                       {"flicker_ratio", referenceFlicker > 0 ? flicker / referenceFlicker : 0.0},
                                       {"flicker_cold", flickerCold},
                                       {"flicker_cold_ratio", referenceFlicker > 0 ? flickerCold / referenceFlicker : 0.0}};
                    toml::table moving = common;
                    moving.insert("still", false);
                    moving.insert("psnr_db", median(db));
                    moving.insert("psnr_db_p95", worst5(db, true));
                    moving.insert("flip", median(flip));
                    moving.insert("flip_p95", worst5(flip, false));
                    moving.insert("scored_frames", int64_t(db.size()));
                    toml::table st = common;
                    st.insert("still", true);
                    st.insert("seconds_to_40db", to40);
                    st.insert("psnr_db", stillDb);
                    st.insert("flip", flipMean(previous, stillRef));
                    st.insert("still_frames", stillFrames);
                    st.insert("still_seconds", elapsed);
                    if (o.text) {
                        std::fprintf(o.text,
                                     "%-10s %4dx%-4d %-8s %2d spp: %6.1f fps (denoise %5.1f ms) moving %5.1f dB (worst 5%% %5.1f) "
                                     "FLIP %.3f; still: 40 dB after %s, %5.1f dB after %.1f s, flicker after the stop %.5f (%.1fx "
                                     "the reference's; after a cut %.1fx)\n",
                                     name.c_str(), w, h, denoiseModeName(mode), spp, fps, 1e3 * median(denoiseS), median(db),
                                     worst5(db, true), median(flip),
                                     to40 < 0 ? "never" : (std::to_string(to40).substr(0, 5) + " s").c_str(), stillDb, elapsed,
                                     flicker, referenceFlicker > 0 ? flicker / referenceFlicker : 0.0,
                                     referenceFlicker > 0 ? flickerCold / referenceFlicker : 0.0);
                        std::fflush(o.text);
                    }
                    rows.push_back(std::move(moving));
                    rows.push_back(std::move(st));
                }
        }
    }
    out.insert("rows", rows);
    out.insert("filter_cost", filterCost);
    return out;
}

}  // namespace rtwall::bench
