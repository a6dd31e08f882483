// rtwall bench shading: frame time and error against a converged reference for the shading
// demos, as the speed/accuracy controls vary: the ray-tree pruning threshold (every scene,
// against the unpruned image), GI samples per pixel (office and the alpha-masked sunflower field,
// against a many-sample mean) and the volume step (office, against a fine step). PSNR over the whole image, and mean
// LDR-FLIP (rtwall::tune, 67 pixels per degree).
#include "bench.h"
#include "bench_util.h"
#include "generators.h"

#include <rtwall/engine.h>
#include <rtwall/tune.h>

#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace rtwall::bench {

namespace {

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
        std::vector<float> linear;
        Image img;
        t.push_back(secondsOf([&] {
            linear = renderFrameLinear(scene, cam, s, uint32_t(r + 1), &st);
            img = srgbImage(linear, s.width, s.height);
        }));
        if (r == 0) out.first = img;
        if (stochastic) acc.addLinear(linear.data(), s.width, s.height);
        else acc.add(img);  // the same image every frame
    }
    seconds = median(t);
    out.mean = acc.resolve();
    return out;
}

toml::table point(const char* control, double value, double seconds, double db, const TileStats& st, double flip = 0) {
    return toml::table{{control, value}, {"frame_s", seconds}, {"psnr_db", std::isinf(db) ? 999.0 : db}, {"flip", flip},
                       {"mrays", double(st.rays + st.shadowRays) * 1e-6}};
}

// Pruning threshold, against the unpruned image. The headlight's glass splits every path in two
// at each of its many interfaces: unpruned, its ray tree grows as 2^depth, so its reference is
// threshold 1e-4 instead.
void pruneRows(const std::string& name, const SceneDesc& desc, const Scene& scene, const Camera& cam, const ShadingOptions& o,
               toml::table& sceneOut) {
    double sec;
    TileStats st;
    const bool deep = name == "headlight";
    const float referenceThreshold = deep ? 1e-4f : 0.0f;
    RenderSettings s = desc.settings;
    s.pruneThreshold = referenceThreshold;
    const Timed unpruned = timed(scene, cam, s, o.rounds, sec, st);
    toml::array prune;
    prune.push_back(point("threshold", referenceThreshold, sec, INFINITY, st));
    sceneOut.insert("prune_reference_threshold", referenceThreshold);
    for (float th : o.thresholds) {
        s.pruneThreshold = th;
        const Timed img = timed(scene, cam, s, o.rounds, sec, st);
        toml::table pt = point("threshold", th, sec, psnrDb(img.first, unpruned.first), st, flipMean(img.first, unpruned.first));
        const double meanDb = psnrDb(img.mean, unpruned.mean);
        pt.insert("psnr_mean_db", std::isinf(meanDb) ? 999.0 : meanDb);
        prune.push_back(std::move(pt));
    }
    sceneOut.insert("prune", prune);
}

// GI samples per pixel (one frame), against the mean of many frames (in linear light).
void giRows(const SceneDesc& desc, const Scene& scene, const Camera& cam, const ShadingOptions& o, toml::table& sceneOut) {
    double sec;
    TileStats st;
    RenderSettings g = desc.settings;
    g.gi = true;
    g.samples = 4;
    Accumulator acc;
    for (int f = 0; f < o.referenceFrames; ++f)
        acc.addLinear(renderFrameLinear(scene, cam, g, uint32_t(100000 + f)).data(), g.width, g.height);
    const Image reference = acc.resolve();
    toml::array gi;
    for (int spp : o.giSamples) {
        g.samples = spp;
        const Image img = timed(scene, cam, g, o.rounds, sec, st).first;
        gi.push_back(point("spp", spp, sec, psnrDb(img, reference), st, flipMean(img, reference)));
    }
    sceneOut.insert("gi_spp", gi);
    sceneOut.insert("gi_reference_spp", 4 * o.referenceFrames);
}

// Volume step (voxels), against step 0.05.
void volumeRows(const SceneDesc& desc, const Camera& cam, const ShadingOptions& o, toml::table& sceneOut) {
    double sec;
    TileStats st;
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
    for (float step : o.volumeSteps) {
        const SceneDesc d = withStep(step);
        const Scene sc(d);
        const Image img = timed(sc, cam, d.settings, o.rounds, sec, st).first;
        vol.push_back(point("step_voxels", step, sec, psnrDb(img, volumeRef), st, flipMean(img, volumeRef)));
    }
    sceneOut.insert("volume_step", vol);
}

// The demo scene `name`, written into o.dir (the sunflower field at o.sunflowerPlants plants).
SceneDesc demoScene(const std::string& name, const ShadingOptions& o, toml::table& out) {
    if (name != "sunflowers") return loadSceneFile(gen::writeShadingDemo(name, std::filesystem::path(o.dir) / name));
    gen::GenOptions g;
    g.out = std::filesystem::path(o.dir) / name;
    g.instances = o.sunflowerPlants;
    g.trees = o.sunflowerTrees;
    gen::genSunflowers(g);
    out.insert("sunflower_plants", o.sunflowerPlants);
    out.insert("sunflower_trees", o.sunflowerTrees);
    return loadSceneFile(g.out / "scene.toml");
}

}  // namespace

toml::table shading(const ShadingOptions& o) {
    toml::table out{{"width", o.width}, {"height", o.height}, {"rounds", o.rounds}, {"flip", "mean LDR-FLIP, 67 pixels per degree"}};
    for (const std::string& name : o.scenes) {
        SceneDesc desc = demoScene(name, o, out);
        desc.settings.width = o.width;
        desc.settings.height = o.height;
        desc.settings.threads = o.threads;
        const Scene scene(desc);
        const Camera cam(desc.cameras.front(), o.width, o.height);
        toml::table sceneOut;
        pruneRows(name, desc, scene, cam, o, sceneOut);
        if (name == "office" || name == "sunflowers") giRows(desc, scene, cam, o, sceneOut);
        if (name == "office") volumeRows(desc, cam, o, sceneOut);
        out.insert(name, sceneOut);
        std::fprintf(stderr, "bench shading: %s done\n", name.c_str());
    }
    if (o.text) printToml(o.text, out);
    return out;
}

}  // namespace rtwall::bench
