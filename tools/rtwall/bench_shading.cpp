// rtwall bench shading: frame time and error against a converged reference for the shading
// demos, as the speed/accuracy controls vary: the ray-tree pruning threshold (every scene,
// against the unpruned image), GI samples per pixel (office and the alpha-masked sunflower field,
// against a many-sample mean) and the volume step (office, against a fine step). PSNR over the whole image, and mean
// LDR-FLIP (rtwall::tune, 67 pixels per degree).
#include "commands.h"
#include "gen_shading.h"
#include "generators.h"

#include <rtwall/engine.h>
#include <rtwall/tune.h>

#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

namespace rtwall::cli {

namespace {

struct Options {
    bool json = false;
    int width = 1600, height = 1200, rounds = 3, referenceFrames = 64, threads = 0;
    std::string dir = "out/bench-shading";
    std::vector<std::string> scenes{"office", "headlight", "sunflowers"};
    int64_t sunflowerPlants = 2000;  // the field is generated at this size (rtwall gen sunflowers --instances)
    int sunflowerTrees = 1;
    std::vector<float> thresholds{0.0005f, 0.002f, 0.01f, 0.05f};
    std::vector<int> giSamples{1, 2, 4, 8, 16};
    std::vector<float> volumeSteps{0.25f, 0.5f, 1.0f, 2.0f, 4.0f};
};

double psnr(const Image& a, const Image& b) {
    double se = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        const double d = double(a.rgb[i]) - double(b.rgb[i]);
        se += d * d;
    }
    if (se == 0) return INFINITY;
    return 10.0 * std::log10(255.0 * 255.0 / (se / double(a.rgb.size())));
}

// Median frame time over `rounds` frames (frames 1..rounds: seeds change each frame). `first`
// is frame 1, the error one frame shows as the viewer sees it; `mean` the average of all of
// them (what progressive refinement converges to: its error against the reference's mean over
// the same frames is the bias, with the noise averaged down). Frames are rendered in linear
// light and quantised here (renderFrame's bytes), so that a stochastic scene's mean is taken in
// linear light, as `rtwall render --frames` and `rtwall run` take it, not from frames each
// clipped at 1.0.
struct Timed {
    Image first, mean;
};
Timed timed(const Scene& scene, const Camera& cam, const RenderSettings& s, int rounds, double& seconds, TileStats& st) {
    SceneDesc d = scene.desc();
    d.settings = s;
    const bool stochastic = rendersStochastically(d);
    std::vector<double> t;
    Accumulator acc;
    Timed out;
    for (int r = 0; r < rounds; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        const std::vector<float> linear = renderFrameLinear(scene, cam, s, uint32_t(r + 1), &st);
        Image img;
        img.width = s.width;
        img.height = s.height;
        img.rgb.resize(linear.size());
        linearToSrgb8(linear.data(), linear.size(), img.rgb.data());
        t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        if (r == 0) out.first = img;
        if (stochastic) acc.addLinear(linear.data(), s.width, s.height);
        else acc.add(img);  // the same image every frame
    }
    std::sort(t.begin(), t.end());
    seconds = t[t.size() / 2];
    out.mean = acc.resolve();
    return out;
}

toml::table point(const char* control, double value, double seconds, double db, const TileStats& st, double flip = 0) {
    return toml::table{{control, value}, {"frame_s", seconds}, {"psnr_db", std::isinf(db) ? 999.0 : db}, {"flip", flip},
                       {"mrays", double(st.rays + st.shadowRays) * 1e-6}};
}

}  // namespace

void addBenchShading(CLI::App& bench, Run& run) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = bench.add_subcommand("shading", "Shading demos: frame time and PSNR vs pruning, GI samples, volume step");
    cmd->add_flag("--json", o->json, "Print JSON");
    cmd->add_option("--width", o->width, "Image width")->check(CLI::Range(16, 8192));
    cmd->add_option("--height", o->height, "Image height")->check(CLI::Range(16, 8192));
    cmd->add_option("--rounds", o->rounds, "Frames timed per point (median)")->check(CLI::Range(1, 100));
    cmd->add_option("--reference-frames", o->referenceFrames, "Frames averaged for the GI reference")->check(CLI::Range(1, 100000));
    cmd->add_option("--threads", o->threads, "Render threads (0 = all)")->check(CLI::Range(0, 1024));
    cmd->add_option("--dir", o->dir, "Where the demo scenes are written");
    cmd->add_option("--scenes", o->scenes, "Scenes to run (office, headlight, sunflowers)")
        ->check(CLI::IsMember({"office", "headlight", "sunflowers"}))
        ->delimiter(',');
    cmd->add_option("--sunflower-plants", o->sunflowerPlants, "Plants in the generated sunflower field")
        ->check(CLI::Range(int64_t(1), int64_t(10'000'000)));
    cmd->add_option("--sunflower-trees", o->sunflowerTrees, "Large trees in the generated sunflower field")
        ->check(CLI::Range(0, 64));
    cmd->add_option("--thresholds", o->thresholds, "Pruning thresholds to measure")
        ->check(CLI::Range(0.0f, 1.0f))
        ->delimiter(',');
    cmd->add_option("--gi-samples", o->giSamples, "GI samples per pixel to measure (office, sunflowers)")
        ->check(CLI::Range(1, 4096))
        ->delimiter(',');
    cmd->add_option("--volume-steps", o->volumeSteps, "Volume steps in voxels to measure (office)")
        ->check(CLI::Range(0.01f, 64.0f))
        ->delimiter(',');
    cmd->callback([&run, o] {
        run = [o] {
            toml::table out{{"width", o->width}, {"height", o->height}, {"rounds", o->rounds}, {"flip", "mean LDR-FLIP, 67 pixels per degree"}};
            for (const std::string& name : o->scenes) {
                SceneDesc desc;
                if (name == "sunflowers") {
                    gen::GenOptions g;
                    g.out = std::filesystem::path(o->dir) / name;
                    g.instances = o->sunflowerPlants;
                    g.trees = o->sunflowerTrees;
                    gen::genSunflowers(g);
                    desc = loadSceneFile(g.out / "scene.toml");
                    out.insert("sunflower_plants", o->sunflowerPlants);
                    out.insert("sunflower_trees", o->sunflowerTrees);
                } else {
                    desc = loadSceneFile(writeShadingDemo(name, std::filesystem::path(o->dir) / name));
                }
                desc.settings.width = o->width;
                desc.settings.height = o->height;
                desc.settings.threads = o->threads;
                const Scene scene(desc);
                const Camera cam(desc.cameras.front(), o->width, o->height);
                toml::table sceneOut;
                double sec;
                TileStats st;

                // Pruning threshold, against the unpruned image. The headlight's glass splits
                // every path in two at each of its many interfaces: unpruned, its ray tree grows
                // as 2^depth, so its reference is threshold 1e-4 instead.
                const bool deep = name == "headlight";
                const float referenceThreshold = deep ? 1e-4f : 0.0f;
                RenderSettings s = desc.settings;
                s.pruneThreshold = referenceThreshold;
                const Timed unpruned = timed(scene, cam, s, o->rounds, sec, st);
                toml::array prune;
                prune.push_back(point("threshold", referenceThreshold, sec, INFINITY, st));
                sceneOut.insert("prune_reference_threshold", referenceThreshold);
                for (float th : o->thresholds) {
                    s.pruneThreshold = th;
                    const Timed img = timed(scene, cam, s, o->rounds, sec, st);
                    toml::table pt = point("threshold", th, sec, psnr(img.first, unpruned.first), st, flipMean(img.first, unpruned.first));
                    const double meanDb = psnr(img.mean, unpruned.mean);
                    pt.insert("psnr_mean_db", std::isinf(meanDb) ? 999.0 : meanDb);
                    prune.push_back(std::move(pt));
                }
                sceneOut.insert("prune", prune);

                if (name == "office" || name == "sunflowers") {
                    // GI samples per pixel (one frame), against the mean of many frames (in
                    // linear light).
                    RenderSettings g = desc.settings;
                    g.gi = true;
                    g.samples = 4;
                    Accumulator acc;
                    for (int f = 0; f < o->referenceFrames; ++f)
                        acc.addLinear(renderFrameLinear(scene, cam, g, uint32_t(100000 + f)).data(), g.width, g.height);
                    const Image reference = acc.resolve();
                    toml::array gi;
                    for (int spp : o->giSamples) {
                        g.samples = spp;
                        const Image img = timed(scene, cam, g, o->rounds, sec, st).first;
                        gi.push_back(point("spp", spp, sec, psnr(img, reference), st, flipMean(img, reference)));
                    }
                    sceneOut.insert("gi_spp", gi);
                    sceneOut.insert("gi_reference_spp", 4 * o->referenceFrames);
                }
                if (name == "office") {

                    // Volume step (voxels), against step 0.05.
                    auto withStep = [&](float step) {
                        SceneDesc d = desc;
                        for (Material& m : d.materials)
                            if (m.type == MaterialType::Volume) m.volumeStep = step;
                        return d;
                    };
                    const SceneDesc fine = withStep(0.05f);
                    const Scene fineScene(fine);
                    const Image volumeRef = timed(fineScene, cam, fine.settings, 1, sec, st).first;
                    toml::array vol;
                    for (float step : o->volumeSteps) {
                        const SceneDesc d = withStep(step);
                        const Scene sc(d);
                        const Image img = timed(sc, cam, d.settings, o->rounds, sec, st).first;
                        vol.push_back(point("step_voxels", step, sec, psnr(img, volumeRef), st, flipMean(img, volumeRef)));
                    }
                    sceneOut.insert("volume_step", vol);
                }
                out.insert(name, sceneOut);
                std::fprintf(stderr, "bench shading: %s done\n", name.c_str());
            }
            if (o->json) std::cout << toml::json_formatter{out} << "\n";
            else std::cout << out << "\n";
            return 0;
        };
    });
}

}  // namespace rtwall::cli
