// rtwall bench warp (issue 30): direct per-pixel rays against the rasteriser's post-warp on a
// curved screen. The screen is a cylindrical section whose chord is the flat screen (3.2 m x
// 2.4 m, its centre 2.5 m before the eye); one projector's pixels span its arc evenly, so its
// warp bends more as the arc grows (0 degrees: the chord itself, where both must agree). The
// room is placed in the scene by the scene camera's pose (the eye at the camera, the chord
// ahead of it), 1 m = 1 scene unit times the scene's size over the chord's.
#include "bench.h"
#include "bench_util.h"

#include <rtwall/engine.h>
#include <rtwall/frame.h>
#include <rtwall/tune.h>

#include <toml++/toml.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <vector>

namespace rtwall::bench {

namespace {

constexpr double kChordW = 3.2, kChordH = 2.4, kEyeDistance = 2.5;

// The projector's surface points (room metres: the chord in z = 0, the eye at (0, 0, 2.5)),
// one per pixel centre: the arc bulges away from the eye.
std::shared_ptr<const PixelWarp> cylinder(double spanDeg, int w, int h) {
    auto g = std::make_shared<PixelWarp>();
    g->kind = PixelWarp::Kind::SurfacePoints;
    g->width = w;
    g->height = h;
    const double span = spanDeg * std::numbers::pi / 180.0;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const double u = (i + 0.5) / w - 0.5, y = kChordH * (0.5 - (j + 0.5) / h);
            if (span <= 0) {
                g->samples.push_back({float(u * kChordW), float(y), 0.0f});
                continue;
            }
            const double r = 0.5 * kChordW / std::sin(span / 2), t = u * span;
            g->samples.push_back({float(r * std::sin(t)), float(y), float(-(r * std::cos(t) - r * std::cos(span / 2)))});
        }
    return g;
}

struct Timed {
    Image image;
    double seconds = 0;  // median of runs
};

}  // namespace

toml::table warp(const WarpOptions& o) {
    SceneDesc desc = loadScene(o.scene);
    const Scene scene(desc);
    const CameraDesc base = desc.cameras.front();
    // The room in the scene: the camera's frame, the eye at the camera.
    const Float3 f = normalize(base.lookAt - base.position);
    Float3 right = normalize(cross(f, base.up));
    const Float3 up = cross(right, f);
    const float unit = float(length(base.lookAt - base.position) / kEyeDistance);  // the chord lands at the look-at distance
    RoomToWorld room{base.position, {0.0f, 0.0f, float(kEyeDistance)}, right, up, f * -1.0f, unit};
    CameraDesc camera = base;
    camera.window = ProjectionWindow{room.point({float(-kChordW / 2), float(-kChordH / 2), 0.0f}),
                                     room.direction({float(kChordW), 0.0f, 0.0f}) * unit,
                                     room.direction({0.0f, float(kChordH), 0.0f}) * unit};
    RenderSettings s = desc.settings;
    s.width = o.width;
    s.height = o.height;
    s.threads = o.threads;
    s.supersample = 1;
    const auto timed = [&](const auto& make) {
        Timed t;
        std::vector<double> times;
        for (int r = 0; r < o.runs; ++r) times.push_back(secondsOf([&] { t.image = make(); }));
        t.seconds = median(times);
        return t;
    };
    toml::array rows;
    for (double span : o.spans) {
        const ScreenWarp sw{{0, 0, o.width, o.height}, cylinder(span, o.width, o.height), room};
        const Camera direct(camera, o.width, o.height, {sw});
        RenderSettings refSettings = s;
        refSettings.supersample = o.referenceSupersample;
        const Image reference = renderFrame(scene, direct, refSettings, 1);
        const Timed d = timed([&] { return renderFrame(scene, direct, s, 1); });
        toml::table row{{"span_deg", span}};
        const auto add = [&](const char* name, const Timed& t) {
            const ImageError e = compareImages(t.image, reference);
            row.insert(name, toml::table{{"psnr_db", e.psnrDb}, {"flip", e.flip}, {"ssim", e.ssim}, {"frame_s", t.seconds}});
            if (o.text)
                std::fprintf(o.text, "arc %5.0f deg  %-8s PSNR %6.2f dB  FLIP %.4f  %.3f s\n", span, name, e.psnrDb, e.flip, t.seconds);
        };
        add("direct", d);
        // The same rays a pixel as post_2x renders: 2 x 2 samples through the warp.
        RenderSettings s2 = s;
        s2.supersample = 2;
        add("direct_ss2", timed([&] { return renderFrame(scene, direct, s2, 1); }));
        for (const int scale : {1, 2}) {
            RenderSettings fs = s;
            fs.width = o.width * scale;
            fs.height = o.height * scale;
            const Camera flat(camera, fs.width, fs.height);
            const Timed p = timed([&] {
                const Image flatImage = renderFrame(scene, flat, fs, 1);
                Image out;
                postWarp(flatImage, camera, sw, o.width, o.height, out);
                return out;
            });
            add(scale == 1 ? "post" : "post_2x", p);
        }
        rows.push_back(std::move(row));
    }
    return toml::table{{"benchmark", "warp"},
                       {"scene", o.scene},
                       {"width", o.width},
                       {"height", o.height},
                       {"reference_supersample", o.referenceSupersample},
                       {"runs", o.runs},
                       {"chord_m", toml::array{kChordW, kChordH}},
                       {"eye_distance_m", kEyeDistance},
                       {"rows", rows}};
}

}  // namespace rtwall::bench
