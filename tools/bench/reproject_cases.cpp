// rtwall bench reproject's failure cases: where a depth warp cannot be right, each shown as one
// image (true render | warped | debug colours of warpDebugColours) and scored over the whole
// image and over the pixels the case is about. Each is one displayed moment of the benchmark's
// model: the newest frame rendered for the head at t = 0 and the one before it at -1/render_fps,
// shown at t = 1.5/render_fps (the middle of its one-to-two periods of age) for the head there.
//  - thin: a fence of 2 cm poles and 6 mm wires in the demo scene, 0.7 m behind the screen.
//  - mirror_glass: the demo scene's mirror and glass spheres seen from close by, whose reflections and refractions
//    move with what they show, not with the depth of their surfaces.
//  - disocclusion: a column 1.4 m in front of the eye (in front of the screen) and a fast step
//    sideways: a wide strip behind it that neither frame saw.
#include "bench.h"
#include "reproject_quality.h"

#include <rtwall/input_error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

namespace rtwall::bench {

toml::table reprojectionFailureCases(const ReprojectOptions& o);

namespace {

namespace rq = reproject;

// The pixels a case is about: the instances it added, the mirror and glass surfaces, or the holes.
enum class Marked { Added, Mirrors, Holes };

struct FailureCase {
    std::string name, about;
    SceneDesc desc;
    double speed = 1, renderFps = 5;
    Marked marked = Marked::Added;
    uint32_t firstAdded = 0;              // Added: the instances from here on
    std::optional<ViewPose> navigation;   // where the wall stands, when not the benchmark's
};

uint32_t meshNamed(const SceneDesc& d, const std::string& name) {
    for (size_t i = 0; i < d.meshes.size(); ++i)
        if (d.meshes[i].name == name) return uint32_t(i);
    throw InputError("bench reproject: the demo scene has no mesh '" + name + "'");
}

uint32_t addMaterial(SceneDesc& d, const std::string& name, Color colour) {
    Material m;
    m.name = name;
    m.color = colour;
    d.materials.push_back(m);
    return uint32_t(d.materials.size() - 1);
}

// Boxes (the demo's [-1, 1]^3 box mesh) of half sizes `half` at `centre`.
void addBox(SceneDesc& d, uint32_t material, Float3 centre, Float3 half) {
    d.instances.push_back({meshNamed(d, "box"), material,
                           Transform::translate(centre.x, centre.y, centre.z) * Transform::scale(half.x, half.y, half.z)});
}

FailureCase named(const std::string& name, const std::string& about, const SceneDesc& desc, double speed) {
    FailureCase c;
    c.name = name;
    c.about = about;
    c.desc = desc;
    c.speed = speed;
    return c;
}

std::vector<FailureCase> failureCases(const SceneDesc& demo) {
    std::vector<FailureCase> cases;
    FailureCase thin = named("thin", "the poles' and wires' pixels", demo, 0.5);
    thin.firstAdded = uint32_t(demo.instances.size());
    const uint32_t steel = addMaterial(thin.desc, "pole", {0.15f, 0.15f, 0.17f});
    for (int i = 0; i < 9; ++i) addBox(thin.desc, steel, {-1.4f + 0.35f * float(i), 1.2f, 2.8f}, {0.01f, 1.2f, 0.01f});
    for (float y : {1.5f, 1.8f, 2.1f}) addBox(thin.desc, steel, {0.0f, y, 2.75f}, {1.6f, 0.003f, 0.003f});
    cases.push_back(thin);
    FailureCase mirrors = named("mirror_glass", "the mirror and glass spheres' pixels", demo, 0.5);
    mirrors.marked = Marked::Mirrors;
    // Close to the glass sphere, the knot behind it seen through it upside down (the mirror
    // sphere, which reflects mostly sky and floor from every side, is hidden behind the knot).
    mirrors.navigation = ViewPose{{3.6f, 1.3f, 4.6f}, {1.0f, 0.8f, 0.6f}, {0.0f, 1.0f, 0.0f}, 45.0f};
    cases.push_back(mirrors);
    FailureCase column = named("disocclusion", "the holes: pixels neither frame saw from the new pose (Older and Filled)", demo, 1.0);
    column.marked = Marked::Holes;
    addBox(column.desc, addMaterial(column.desc, "column", {0.8f, 0.75f, 0.3f}), {0.15f, 1.1f, 4.6f}, {0.12f, 0.6f, 0.12f});
    cases.push_back(column);
    return cases;
}

// Per pixel of `camera`'s image: 1 where the case's objects (Added, Mirrors) are seen first.
std::vector<uint8_t> seen(const FailureCase& c, const Scene& scene, const Camera& camera, int width, int height) {
    std::vector<uint8_t> mask(size_t(width) * size_t(height), 0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const auto hit = pick(scene, camera, float(x) + 0.5f, float(y) + 0.5f);
            if (!hit) continue;
            const MaterialType type = c.desc.materials[c.desc.instances[hit->instance].material].type;
            const bool mirror = type == MaterialType::Mirror || type == MaterialType::Glass;
            mask[size_t(y) * size_t(width) + size_t(x)] = c.marked == Marked::Mirrors ? mirror : hit->instance >= c.firstAdded;
        }
    return mask;
}

// true | warped | debug, 4 white pixels apart.
Image strip(const std::vector<const Image*>& images) {
    constexpr int kGap = 4;
    Image out;
    out.height = images.front()->height;
    out.width = int(images.size()) * (images.front()->width + kGap) - kGap;
    out.rgb.assign(size_t(out.width) * size_t(out.height) * 3, 255);
    int x0 = 0;
    for (const Image* image : images) {
        for (int y = 0; y < image->height; ++y) std::copy_n(image->pixel(0, y), size_t(image->width) * 3, out.pixel(x0, y));
        x0 += image->width + kGap;
    }
    return out;
}

toml::table scores(const rq::Score& s) {
    auto finite = [](double v) { return std::isfinite(v) ? v : -1.0; };
    return toml::table{{"psnr_db", s.psnrDb}, {"flip", s.flip}, {"marked_psnr_db", finite(s.maskedPsnrDb)}, {"marked_flip", finite(s.maskedFlip)}};
}

toml::table runCase(const FailureCase& c, rq::WallRig rig, const ReprojectOptions& o) {
    if (c.navigation) rig.navigation = *c.navigation;
    const int w = o.width, h = o.height;
    SceneDesc desc = c.desc;
    desc.settings.width = w;
    desc.settings.height = h;
    desc.settings.threads = 0;
    const Scene scene(desc);
    const double period = 1.0 / c.renderFps, shownAt = 1.5 * period;
    const rq::HeadPath head = rq::steppingHead(rig, c.speed, shownAt / 2);
    auto render = [&](double t) {
        const CameraDesc camera = rig.camera(head.at(t), w, h);
        return std::pair{renderFrameWithDepth(scene, Camera(camera, w, h), desc.settings), camera};
    };
    const auto [newest, newestCamera] = render(0);
    const auto [older, olderCamera] = render(-period);
    const auto [truth, truthCamera] = render(shownAt);
    Reprojector warper;
    const WarpSource olderSource{older.image, older.depth, olderCamera};
    const WarpedView& view = warper.warp({newest.image, newest.depth, newestCamera}, truthCamera, &olderSource);
    std::vector<uint8_t> mask(view.mask.size());
    if (c.marked != Marked::Holes) mask = seen(c, scene, Camera(truthCamera, w, h), w, h);
    else
        for (size_t i = 0; i < mask.size(); ++i) mask[i] = view.mask[i] == WarpPixel::Older || view.mask[i] == WarpPixel::Filled;
    Image debug;
    warpDebugColours(view, debug);
    const std::filesystem::path file = std::filesystem::path(o.images.empty() ? o.dir : o.images) / ("reprojection_" + c.name + ".png");
    std::filesystem::create_directories(file.parent_path());
    writePng(strip({&truth.image, &view.image, &debug}), file);
    const rq::Score warped = rq::scoreImage(view.image, truth.image, 0.05, &mask);
    const rq::Score stale = rq::scoreImage(newest.image, truth.image, 0.05, &mask);
    if (o.text)
        std::fprintf(o.text, "failure case %s: warped PSNR %.1f dB FLIP %.3f (%s: %.1f dB, %.3f), stale %.1f dB %.3f, holes %.1f%%: %s\n",
                     c.name.c_str(), warped.psnrDb, warped.flip, c.about.c_str(), warped.maskedPsnrDb, warped.maskedFlip,
                     stale.psnrDb, stale.flip, 100 * rq::holeFraction(view, w, h), file.string().c_str());
    return toml::table{{"case", c.name},
                       {"marked", c.about},
                       {"speed_m_s", c.speed},
                       {"render_fps", c.renderFps},
                       {"age_ms", 1e3 * shownAt},
                       {"image", file.string()},
                       {"holes", rq::holeFraction(view, w, h)},
                       {"warped", scores(warped)},
                       {"stale", scores(stale)}};
}

}  // namespace

toml::table reprojectionFailureCases(const ReprojectOptions& o) {
    const rq::BenchScene demo = rq::benchScene("demo", o.demo, o.dir, o.plantTriangles);
    toml::table out;
    for (const FailureCase& c : failureCases(demo.desc)) out.insert(c.name, runCase(c, demo.rig, o));
    return out;
}

}  // namespace rtwall::bench
