// The building blocks of `rtwall bench reproject`: the wall rig, the head's walk, the render
// clock, the scores, and the display loop that shows each track's newest frame warped and stale.
#include "reproject_quality.h"

#include <generators.h>
#include <rtwall/input_error.h>
#include <rtwall/tune.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

namespace rtwall::bench::reproject {

CameraDesc WallRig::camera(Float3 head, int width, int height, int guardX, int guardY) const {
    const Float3 pitchX = right * (1.0f / float(width)), pitchY = up * (1.0f / float(height));
    EyeWindow wall;
    wall.eye = head;
    wall.lowerLeft = lowerLeft - pitchX * float(guardX) - pitchY * float(guardY);
    wall.right = pitchX * float(width + 2 * guardX);
    wall.up = pitchY * float(height + 2 * guardY);
    const EyeWindow world = eyeWindowInWorld(wall, viewer, navigation);
    CameraDesc c;
    c.name = "wall";
    c.position = world.eye;
    c.window = ProjectionWindow{world.lowerLeft, world.right, world.up};
    return c;
}

BenchScene benchScene(const std::string& name, const std::string& demoFile, const std::filesystem::path& dir,
                      int64_t plantTriangles) {
    BenchScene s;
    if (name == "demo") {
        s.desc = loadSceneFile(demoFile);
        s.rig.navigation = {{0.0f, 1.6f, 6.0f}, {0.0f, 0.9f, 0.0f}, {0.0f, 1.0f, 0.0f}, 45.0f};
        return s;
    }
    if (name != "plant") throw InputError("bench reproject: unknown scene '" + name + "' (demo, plant)");
    gen::GenOptions g;
    g.out = dir / "plant";
    g.triangles = plantTriangles;
    gen::genPowerplant(g);
    s.desc = loadSceneFile(g.out / "scene.toml");
    const CameraDesc* close = s.desc.findCamera("close");
    if (!close) throw InputError("bench reproject: the generated plant has no camera 'close'");
    s.rig.navigation = {close->position, close->lookAt, close->up, close->fovY};
    return s;
}

Float3 HeadPath::at(double t) const { return through + direction * float(speed * (t - middle)); }

HeadPath steppingHead(const WallRig& rig, double speed, double middle) {
    return {rig.viewer, normalize(Float3{1.0f, 0.0f, -0.25f}), speed, middle};
}

int64_t RenderClock::newestAt(double t) const { return int64_t(std::floor((t - phase) / period)) - 1; }

namespace {

double psnrOf(double squaredError, size_t values) {
    if (values == 0) return std::numeric_limits<double>::quiet_NaN();
    if (squaredError == 0) return kIdenticalPsnr;
    return std::min(kIdenticalPsnr, 10.0 * std::log10(255.0 * 255.0 * double(values) / squaredError));
}

// Squared error and FLIP summed over the pixels of one region.
struct Sums {
    double se = 0, flip = 0;
    size_t pixels = 0;
    void add(double pixelSe, double pixelFlip) {
        se += pixelSe;
        flip += pixelFlip;
        ++pixels;
    }
    double psnr() const { return psnrOf(se, pixels * 3); }
    double meanFlip() const { return pixels ? flip / double(pixels) : std::numeric_limits<double>::quiet_NaN(); }
};

}  // namespace

Score scoreImage(const Image& shown, const Image& truth, double edgeFraction, const std::vector<uint8_t>* only) {
    const std::vector<float> flip = flipErrorMap(shown, truth);
    const int w = truth.width, h = truth.height;
    const int ex = std::max(1, int(std::lround(edgeFraction * w))), ey = std::max(1, int(std::lround(edgeFraction * h)));
    Sums all, edge, masked;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            double se = 0;
            for (size_t c = 0; c < 3; ++c) {
                const double d = double(shown.rgb[i * 3 + c]) - double(truth.rgb[i * 3 + c]);
                se += d * d;
            }
            all.add(se, flip[i]);
            if (x < ex || x >= w - ex || y < ey || y >= h - ey) edge.add(se, flip[i]);
            if (only && (*only)[i]) masked.add(se, flip[i]);
        }
    return {all.psnr(), all.meanFlip(), edge.psnr(), edge.meanFlip(), masked.psnr(), masked.meanFlip()};
}

Image cropCentre(const Image& image, int width, int height) {
    const int x0 = (image.width - width) / 2, y0 = (image.height - height) / 2;
    Image out;
    out.width = width;
    out.height = height;
    out.rgb.resize(size_t(width) * size_t(height) * 3);
    for (int y = 0; y < height; ++y)
        std::copy_n(image.pixel(x0, y0 + y), size_t(width) * 3, out.pixel(0, y));
    return out;
}

double holeFraction(const WarpedView& view, int width, int height) {
    const int w = view.image.width, x0 = (w - width) / 2, y0 = (view.image.height - height) / 2;
    size_t holes = 0;
    for (int y = y0; y < y0 + height; ++y)
        for (int x = x0; x < x0 + width; ++x) {
            const WarpPixel p = view.mask[size_t(y) * size_t(w) + size_t(x)];
            holes += p == WarpPixel::Older || p == WarpPixel::Filled;
        }
    return double(holes) / (double(width) * double(height));
}

double worst5(std::vector<double> values, bool higherIsBetter) {
    std::erase_if(values, [](double v) { return std::isnan(v); });
    if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
    std::sort(values.begin(), values.end());
    const size_t k = size_t(0.05 * double(values.size() - 1) + 0.5);
    return higherIsBetter ? values[k] : values[values.size() - 1 - k];
}

namespace {

struct Rendered {
    RenderedFrame frame;
    CameraDesc camera;
};

// One track's frames as the display loop reaches them: the newest complete frame and the one
// before it, rendered when first needed.
struct TrackState {
    RenderClock clock;
    int guardX = 0, guardY = 0;
    std::map<int64_t, Rendered> frames;
    Reprojector warper;
};

RenderSettings sized(RenderSettings s, int width, int height) {
    s.width = width;
    s.height = height;
    return s;
}

const Rendered& frameOf(TrackState& track, int64_t k, const Scene& scene, const RenderSettings& settings, const WallRig& rig,
                        const HeadPath& head, const MeasureOptions& o) {
    auto it = track.frames.find(k);
    if (it != track.frames.end()) return it->second;
    const RenderSettings s = sized(settings, o.width + 2 * track.guardX, o.height + 2 * track.guardY);
    const CameraDesc camera = rig.camera(head.at(track.clock.start(k)), o.width, o.height, track.guardX, track.guardY);
    Rendered r{renderFrameWithDepth(scene, Camera(camera, s.width, s.height), s), camera};
    return track.frames.emplace(k, std::move(r)).first->second;
}

}  // namespace

std::vector<Series> measure(const Scene& scene, const RenderSettings& settings, const WallRig& rig, double speed,
                            const std::vector<Track>& tracks, const MeasureOptions& o) {
    const HeadPath head = steppingHead(rig, speed, o.seconds / 2);
    // One phase per render rate: the tracks of one rate (guard bands) show the same frames at
    // the same ages, so they differ by their guard band alone.
    std::mt19937_64 rng(o.seed);
    std::map<double, double> phases;
    std::vector<TrackState> states(tracks.size());
    std::vector<Series> out(tracks.size());
    for (size_t j = 0; j < tracks.size(); ++j) {
        const double period = 1.0 / tracks[j].renderFps;
        if (!phases.contains(period)) phases[period] = std::uniform_real_distribution<double>(0, period)(rng);
        states[j].clock = {period, phases[period]};
        states[j].guardX = int(std::lround(tracks[j].guardBand * o.width / 2));
        states[j].guardY = int(std::lround(tracks[j].guardBand * o.height / 2));
        out[j].renderedPixels = double(o.width + 2 * states[j].guardX) * double(o.height + 2 * states[j].guardY) /
                                (double(o.width) * double(o.height));
    }
    const RenderSettings screen = sized(settings, o.width, o.height);
    const int shown = std::max(1, int(std::lround(o.seconds * o.displayHz)));
    for (int i = 0; i < shown; ++i) {
        const double t = double(i) / o.displayHz;
        const Float3 eye = head.at(t);
        const Image truth = renderFrame(scene, Camera(rig.camera(eye, o.width, o.height), o.width, o.height), screen);
        for (size_t j = 0; j < tracks.size(); ++j) {
            TrackState& st = states[j];
            const int64_t k = st.clock.newestAt(t);
            std::erase_if(st.frames, [k](const auto& f) { return f.first < k - 1; });
            const Rendered& older = frameOf(st, k - 1, scene, settings, rig, head, o);
            const Rendered& newest = frameOf(st, k, scene, settings, rig, head, o);
            const WarpSource olderSource{older.frame.image, older.frame.depth, older.camera};
            const WarpedView& view = st.warper.warp({newest.frame.image, newest.frame.depth, newest.camera},
                                                    rig.camera(eye, o.width, o.height, st.guardX, st.guardY), &olderSource);
            const bool guarded = st.guardX > 0 || st.guardY > 0;
            out[j].warped.push_back(scoreImage(guarded ? cropCentre(view.image, o.width, o.height) : view.image, truth, o.edgeFraction));
            out[j].holes.push_back(holeFraction(view, o.width, o.height));
            out[j].ageSeconds.push_back(t - st.clock.start(k));
            if (!guarded) out[j].stale.push_back(scoreImage(newest.frame.image, truth, o.edgeFraction));
        }
    }
    return out;
}

}  // namespace rtwall::bench::reproject
