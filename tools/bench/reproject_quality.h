// The building blocks of `rtwall bench reproject` (tools/bench/reproject.cpp): a tracked wall
// placed in a scene, a head stepping in front of it, a cluster that renders at a fixed rate and
// a 60 Hz display that shows the newest finished frame, warped or as it is, scored against a
// true render of the pose at the moment it is shown. Public for the benchmark's own tests
// (tests/tools/reproject_bench_test.cpp).
#pragma once

#include <rtwall/display.h>
#include <rtwall/engine.h>
#include <rtwall/image.h>
#include <rtwall/reproject.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace rtwall::bench::reproject {

// A tracked wall as the wall session makes its eye cameras (off_axis.cpp): a 3.2 m x 2.4 m
// screen in the plane z = 0 of wall coordinates, centred on the origin, the viewer's default
// position 2.5 m in front of it, and the navigation pose that places the room in the scene
// (eyeWindowInWorld: the viewer's position lands on navigation.position, 1 m = 1 unit).
struct WallRig {
    ViewPose navigation;
    Float3 viewer{0.0f, 0.2f, 2.5f};
    Float3 lowerLeft{-1.6f, -1.2f, 0.0f}, right{3.2f, 0.0f, 0.0f}, up{0.0f, 2.4f, 0.0f};

    // The off-axis camera of an eye at `head` (wall coordinates) for a width x height screen,
    // its window grown by guardX pixels beyond the left and right edges and guardY beyond the
    // top and bottom at the screen's own pixel pitch: a (width + 2 guardX) x (height + 2 guardY)
    // image whose centre width x height pixels are the screen's.
    CameraDesc camera(Float3 head, int width, int height, int guardX = 0, int guardY = 0) const;
};

// A scene of the benchmark and where the wall stands in it. "demo": the scene file `demoFile`,
// the viewer 6 m in front of the knot, 1.6 m up, the screen 2.5 m ahead (the copper knot, the
// mirror and glass spheres and the box behind it); "plant": `rtwall gen powerplant` at about
// `plantTriangles` triangles, generated into dir/plant, the viewer at its "close" camera among
// the pipe racks (metres: 1 m = 1 unit in both).
struct BenchScene {
    SceneDesc desc;
    WallRig rig;
};
BenchScene benchScene(const std::string& name, const std::string& demoFile, const std::filesystem::path& dir,
                      int64_t plantTriangles);

// The head: a person stepping in front of the wall, sideways and a little towards it (direction
// (1, 0, -0.25) in wall coordinates), in a straight line at `speed` m/s, passing the viewer's
// position at time `middle`. Mono: one eye at the head's centre; the off-axis camera depends only
// on where the eye is, so where the head looks (a fixed point) changes nothing.
struct HeadPath {
    Float3 through, direction;
    double speed = 0, middle = 0;
    Float3 at(double t) const;
};
HeadPath steppingHead(const WallRig& rig, double speed, double middle);

// The cluster's frames: frame k starts at phase + k * period, is rendered for the head's pose
// at its start, and is complete one period later (render, transfer and assembly take the whole
// period, as a cluster that renders back to back does). At a display moment t the wall has
// frame newestAt(t): the newest complete one, between one and two periods old.
struct RenderClock {
    double period = 0.1, phase = 0;
    double start(int64_t k) const { return phase + double(k) * period; }
    int64_t newestAt(double t) const;
};

// How a shown image compares with the true render: PSNR (dB; kIdenticalPsnr when identical)
// and mean FLIP (67 pixels per degree) over the whole image and over its edges (the pixels
// within `edgeFraction` of the width of the left or right edge or of the height of the top or
// bottom), and over the pixels `only` marks (when given; NaN when it marks none).
struct Score {
    double psnrDb = 0, flip = 0, edgePsnrDb = 0, edgeFlip = 0, maskedPsnrDb = 0, maskedFlip = 0;
};
Score scoreImage(const Image& shown, const Image& truth, double edgeFraction, const std::vector<uint8_t>* only = nullptr);

// The centre width x height pixels of a guard-banded image.
Image cropCentre(const Image& image, int width, int height);
// The share of the centre width x height pixels of a warp that are holes (Older or Filled).
double holeFraction(const WarpedView& view, int width, int height);

// One way of showing: a render rate, and a guard band (the share of the width and of the height
// rendered beyond the screen, half on each side; 0: none).
struct Track {
    double renderFps = 14, guardBand = 0;
};

// Per displayed frame: the shown image's scores with the warp, and without it (the stale frame
// shown as it is; only for tracks without a guard band), the hole fraction and the newest
// frame's age.
struct Series {
    std::vector<Score> warped, stale;
    std::vector<double> holes, ageSeconds;
    double renderedPixels = 1;  // pixels rendered per frame, relative to the screen's
};

struct MeasureOptions {
    int width = 320, height = 240;
    double displayHz = 60, seconds = 1, edgeFraction = 0.05;
    uint64_t seed = 1;  // the render clocks' phases against the display's
};

// Shows the head walking at `speed` for o.seconds at o.displayHz on every track at once (the
// true renders are shared), rendering `desc`'s settings at o.width x o.height. One Series per
// track, in order.
std::vector<Series> measure(const Scene& scene, const RenderSettings& settings, const WallRig& rig, double speed,
                            const std::vector<Track>& tracks, const MeasureOptions& o);

// The value 95 % of the values are at least as good as: the 5th percentile for PSNR
// (`higherIsBetter`), the 95th for FLIP and holes.
double worst5(std::vector<double> values, bool higherIsBetter);

}  // namespace rtwall::bench::reproject
