// rtwall core: what the re-projection of a rendered view (issue 27) is asked and says, shared by
// its CPU form (rtwall/reproject.h, engine/frame) and its GL form (the display's GlReprojector),
// which must agree: the options, the per-pixel origin of a warped image and the debug view's
// tints. Cameras and the depth convention: rtwall/camera.h.
#pragma once

#include <rtwall/camera.h>
#include <rtwall/image.h>

#include <cstdint>
#include <optional>
#include <span>

namespace rtwall {

// A rendered view as the warp reads it: its image, one depth per pixel as renderTile writes it
// (kBackgroundDepth: background; NaN, infinities, zero and negative: no depth, never moved) and
// the camera it was rendered with (its own size: an older view may be of another resolution).
struct WarpSource {
    const Image& image;
    std::span<const float> depth;
    const CameraDesc& camera;
};
// Throws std::invalid_argument, naming `which` view and its sizes, unless it has one depth and
// three colour bytes per pixel.
void checkWarpSource(const WarpSource& source, const char* which);

// Where world points land in a camera's image: direction(px, py) = corner + du px + dv py, so
// a point p seen from the origin solves p - origin = s (du px + dv py + corner): px = a / c,
// py = b / c for (a, b, c) = M^-1 (p - origin), M = [du dv corner], in front where c > 0. In
// double: both warps take their per-camera constants from it.
struct ImageProjection {
    double origin[3];
    double inv[3][3];  // M^-1 (zero for a degenerate camera, which sees nothing)
    int width, height;

    ImageProjection(const CameraDesc& desc, int w, int h);
    // M^-1 v: a point's (a, b, c) from its offset v from the origin; linear, so a ray's is its
    // direction's times the distance along it.
    void solve(const double v[3], double out[3]) const {
        for (int i = 0; i < 3; ++i) out[i] = inv[i][0] * v[0] + inv[i][1] * v[1] + inv[i][2] * v[2];
    }
};

// Where each pixel of a re-projected image came from (the debug view's colours).
enum class WarpPixel : uint8_t {
    Fresh,   // rendered for this very pose: the newest view's pixel, unmoved
    Warped,  // the newest view's pixel, moved to where the new pose sees it
    Older,   // a hole of the newest view, filled from the older view
    Filled,  // a hole of both: the fallback (the row's nearest neighbour on the farther side)
};

struct WarpOptions {
    // A pixel that no source covers but whose two neighbours (left and right, or above and below)
    // do, at depths within this ratio of each other, is a crack of a magnified surface, not a
    // disocclusion: it takes its nearer neighbour and counts as warped (a second pass closes
    // where a crack row crosses a crack column). Gaps of two pixels and more (a surface seen
    // over twice as large) stay holes.
    float crackRatio = 1.05f;
    uint8_t background[3] = {0, 0, 0};  // a row with no pixel to fill from (never when one has any)
    // A target camera equal to the newest view's (position, look-at, up, field of view, window)
    // copies the view: a static head shows the rendered bytes, all Fresh, for the price of a copy.
    // Off: the warp runs anyway (the tests show that it, too, gives the bytes back).
    bool copySamePose = true;
    // Threads the warp runs on (0: one per hardware thread). The bytes are the same for any
    // number: a pixel's winner is the nearest point, the first in row order of equals, whichever
    // thread splatted it.
    int threads = 0;
    // Only this rectangle of the target is warped, and of a source of the target's size only
    // its pixels are read: a display node holds and shows only its screens' tiles and the ring
    // around them, and warping the rest of the view was half of its refresh's work on a
    // two-node wall. Its edges act as the image's edges (cracks, the row fill); pixels outside
    // keep what they held; an empty one warps nothing. None (the default): the whole view. The
    // CPU warp's; a GL warp draws only its window's screens anyway.
    std::optional<TileRect> region;
};

// The debug view: each pixel half its own colour, half its origin's tint (fresh green, warped
// blue, older yellow, filled red), (colour + tint + 1) / 2 per channel.
inline constexpr uint8_t kWarpTints[4][3] = {{0, 200, 0}, {40, 90, 255}, {255, 220, 0}, {255, 0, 0}};

}  // namespace rtwall
