// rtwall re-projection on the CPU (issue 27): a rendered view, moved to a new pose.
//
// The newest complete view (colour, depth, the camera it was rendered with) is forward-warped
// to the camera of the pose read just before the swap: every pixel goes back into the world at
// its depth and lands where the new camera sees it; the nearest point wins each pixel. What the
// newest view does not cover (disocclusions, the edges it never saw) is filled from an older
// view warped the same way, then from the row's neighbour on the farther side (a row with none:
// from the nearest row that has some). The compositor's
// per-screen stage "reproject" runs this on the CPU (headless, display nodes without GL, tests);
// the GL presenter runs the same algorithm in shaders (display/src/gl_reproject.cpp). What both
// take and say (WarpSource, WarpOptions, WarpPixel) is core's rtwall/warp.h.
#pragma once

#include <rtwall/engine.h>
#include <rtwall/warp.h>

#include <cstdint>
#include <span>
#include <vector>

namespace rtwall {




struct WarpedView {
    Image image;
    std::vector<float> depth;      // distance from the new camera (kBackgroundDepth: background)
    std::vector<WarpPixel> mask;
    size_t holes = 0;              // pixels the newest view left uncovered (Older + Filled)
};

// Warps views frame after frame into buffers it keeps: after the first frame of a size nothing
// is allocated but the threads. Deterministic: the same inputs give the same bytes, on any
// number of threads (the first source pixel in row order wins a tie).
class Reprojector {
public:
    // The newest view warped to `target` at the newest view's size, holes filled from `older`
    // (when given) and then by the fallback. Throws std::invalid_argument when a depth span does
    // not have one value per pixel.
    const WarpedView& warp(const WarpSource& newest, const CameraDesc& target, const WarpSource* older = nullptr,
                           const WarpOptions& options = {});
    const WarpedView& result() const { return out_; }

    // A view's pixels splatted into `target` (w x h): what warp() does to each source before
    // filling. Public for tests and the benchmark.
    struct Splat {
        Image image;
        std::vector<float> depth;
        std::vector<uint8_t> covered;  // 0 none, 1 a source pixel, 2 or 3 a crack filled
    };

private:
    WarpedView out_;
    Splat newest_, older_;
    std::vector<uint64_t> newestKeys_, olderKeys_;  // per target pixel: its splat's winner so far
    std::vector<size_t> rowHoles_;                  // per thread: the holes of its rows
    std::vector<uint8_t> rowKnown_;                 // per target row: some pixel came from a view
};

// The debug view: each pixel half its own colour, half its origin's (fresh green, warped blue,
// older yellow, filled red), into `out` (resized to the view).
void warpDebugColours(const WarpedView& view, Image& out);

// The CPU warp's cost for one width x height screen: a synthetic view (a slanted plane with
// steps, some background) warped to a moved camera `runs` times on `threads` threads.
struct WarpTiming {
    double medianMs = 0, p95Ms = 0;
    int runs = 0;
};
WarpTiming timeReprojection(int width, int height, int runs, int threads = 1);

}  // namespace rtwall
