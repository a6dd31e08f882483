// rtwall tune: speed against accuracy, the one public header.
//
// - Error metrics of an image against a reference (RMSE, PSNR, SSIM, FLIP, largest error) and a
//   false-colour difference image: `rtwall compare`, the sweep driver and the tests.
// - Bilinear resampling, so that a frame rendered at a lower resolution is compared with the
//   reference at the wall's resolution, as the wall would show it.
// - The operating-point controller: given a measured front of settings (frame time, error)
//   and a target frame rate, it picks the most accurate point that holds the rate, and moves
//   along the front as measured frame times change, with hysteresis.
// Plain code: no engine, no sockets, no clock. Depends only on rtwall::mesh (Image, PNG).
#pragma once

#include <rtwall/image.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rtwall {

// ---- Error metrics --------------------------------------------------------------------------

struct ImageError {
    double rmse = 0;        // root mean square over every channel of every pixel, in 8-bit levels
    double psnrDb = 0;      // 20 log10(255 / rmse); kIdenticalPsnr when the images are identical
    double ssim = 1;        // mean SSIM of the luminance (see ssimLuminance)
    int maxError = 0;       // largest absolute difference of any channel, in levels
    int maxX = 0, maxY = 0; // where it is (the first such pixel in row order)
    double meanAbs = 0;     // mean absolute difference per channel, in levels
    double flip = 0;        // mean LDR-FLIP at kFlipPixelsPerDegree (see flipMean): 0 identical, 1 worst
    bool identical() const { return maxError == 0; }
};

// PSNR reported for identical images (JSON has no infinity).
inline constexpr double kIdenticalPsnr = 999.0;

// Compares two images of the same size; throws InputError naming both sizes otherwise, and for
// images smaller than the SSIM window (11 x 11).
ImageError compareImages(const Image& test, const Image& reference);

// Mean SSIM (Wang, Bovik, Sheikh, Simoncelli 2004) on luminance Y = 0.299 R + 0.587 G + 0.114 B
// of the 8-bit values, with the paper's 11 x 11 Gaussian window (sigma 1.5), K1 = 0.01,
// K2 = 0.03, L = 255, over every position where the window lies inside the image ("valid").
// This is the reference implementation's ssim_index.m on rgb2gray input, without its
// optional downsampling.
double ssimLuminance(const Image& a, const Image& b);

// LDR-FLIP (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images"), per
// pixel in [0, 1] (0: no perceived difference), for sRGB images seen at `pixelsPerDegree` (the
// paper's default 67: a 0.7 m wide 3840-pixel monitor at 0.7 m). Colour: YCxCz, contrast
// sensitivity filters, Hunt-adjusted L*a*b*, HyAB distance; features: edges and points of the
// achromatic channel; combined as colour ^ (1 - feature). Borders extend their edge pixels.
// Throws InputError for images of different sizes or a ppd outside (0, 10000].
inline constexpr double kFlipPixelsPerDegree = 67.0;
std::vector<float> flipErrorMap(const Image& test, const Image& reference,
                                double pixelsPerDegree = kFlipPixelsPerDegree);
// The mean of flipErrorMap: the number FLIP reports for an image pair.
double flipMean(const Image& test, const Image& reference, double pixelsPerDegree = kFlipPixelsPerDegree);

// Per-pixel largest channel difference mapped to a false-colour scale (black 0, then blue,
// green, yellow, red at `scaleLevels` and above). scaleLevels <= 0: the largest error.
Image differenceImage(const Image& test, const Image& reference, int scaleLevels = 0);

// Bilinear resampling to width x height (pixel centres aligned, edges clamped), on the 8-bit
// values, rounded to nearest: what a display would do to upscale a lower-resolution frame.
Image resizeBilinear(const Image& src, int width, int height);

// The median of some measurements (the mean of the middle two for an even count; 0 for none):
// benchmarks and frame rates quote medians, which the noise of a shared machine moves least.
double median(std::vector<double> values);

// ---- Operating point ------------------------------------------------------------------------

// One measured setting: the values of its controls, its frame time and its error.
struct OperatingPoint {
    std::string name;                                      // for messages, e.g. "jpeg q75, tile 64"
    std::vector<std::pair<std::string, double>> controls;  // e.g. {"tile", 64}, {"jpeg_quality", 75}
    double frameSeconds = 0;                               // measured or simulated, > 0
    double error = 0;                                      // lower is better (e.g. 1 - SSIM); >= 0

    std::optional<double> control(const std::string& key) const;
};

// The points not dominated by another (one at most as slow and at most as inaccurate, and
// strictly better in one), sorted from fastest (least accurate) to slowest (most accurate).
// Exact duplicates keep the first.
std::vector<OperatingPoint> paretoFront(const std::vector<OperatingPoint>& points);

struct ControllerOptions {
    double targetFps = 30;     // frames per second to hold
    double headroom = 0.10;    // a more accurate point is taken only if predicted within (1 - headroom) of the budget...
    int upFrames = 10;         // ...for this many frames in a row
    double tolerance = 0.05;   // the current point is left for a faster one when measured above (1 + tolerance) x budget...
    int downFrames = 2;        // ...for this many frames in a row
    int holdFrames = 5;        // no change at all for this many frames after a change
    double smoothing = 0.3;    // weight of the newest frame in the running cost ratio (0..1]
};

// Picks the most accurate point of a front that holds the target frame rate and follows the
// measured frame times. Frame time of point i is predicted as front[i].frameSeconds x ratio,
// where ratio (a running average of measured / front time of the point in use) carries what
// the front did not know: a heavier view, a slower link, fewer clients.
//
// Hysteresis: going to a more accurate point needs `upFrames` consecutive predictions within
// budget x (1 - headroom); going to a faster one needs `downFrames` consecutive measurements
// above budget x (1 + tolerance); after any change `holdFrames` pass without another. A point
// taken on the way up is therefore left only when the cost ratio rises by at least
// (1 + tolerance) / (1 - headroom): noise smaller than that cannot make it flip back and forth.
class OperatingPointController {
public:
    // Throws InputError for an empty front, a point with frameSeconds <= 0 or error < 0, or a
    // target <= 0. The front is reduced to its Pareto points (paretoFront).
    OperatingPointController(std::vector<OperatingPoint> points, ControllerOptions options);

    // The point to use now; at start, the most accurate one that fits the budget by the front's
    // own times (the fastest if none does).
    const OperatingPoint& current() const { return front_[current_]; }
    size_t currentIndex() const { return current_; }
    const std::vector<OperatingPoint>& front() const { return front_; }
    double ratio() const { return ratio_; }
    double budgetSeconds() const { return 1.0 / options_.targetFps; }

    // Feeds the measured time of one frame rendered at current(). Returns true when current()
    // changed (the caller applies the new settings before the next frame).
    // `moving`: the view moved for this frame (navigation, a scripted camera, a tracked head).
    // A moving viewer sees each frame once and notices lag more than error, so motion favours
    // speed: while moving the controller never steps up to a more accurate point, and one frame
    // over budget x (1 + tolerance) steps down at once (not downFrames in a row), also during
    // the hold after a change. A still view goes back to the hysteresis above.
    bool observe(double measuredFrameSeconds, bool moving = false);

    void setTargetFps(double fps);  // keeps the point; the next observations decide
    uint64_t changes() const { return changes_; }

private:
    std::vector<OperatingPoint> front_;  // fastest first
    ControllerOptions options_;
    size_t current_ = 0;
    double ratio_ = 1.0;
    int overBudget_ = 0;   // consecutive frames above budget x (1 + tolerance)
    int underBudget_ = 0;  // consecutive frames in which a better point fitted with headroom
    int hold_ = 0;
    uint64_t changes_ = 0;

    size_t bestFitting(double budget) const;  // most accurate point predicted within budget (0 if none)
};

}  // namespace rtwall
