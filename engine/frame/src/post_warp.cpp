// postWarp (rtwall/frame.h, issue 30): a calibrated projector's pixels resampled from a flat
// render, the rasteriser's way, for the comparison with tracing each pixel's own ray.
#include <rtwall/frame.h>
#include <rtwall/image_sample.h>
#include <rtwall/warp.h>

#include <algorithm>
#include <cmath>

namespace rtwall {

void postWarp(const Image& flat, const CameraDesc& camera, const ScreenWarp& warp, int width, int height, Image& out) {
    if (out.width != width || out.height != height || out.rgb.size() != size_t(std::max(0, width)) * size_t(std::max(0, height)) * 3) {
        out.width = width;
        out.height = height;
        out.rgb.assign(size_t(std::max(0, width)) * size_t(std::max(0, height)) * 3, 0);
    }
    const int w = flat.width, h = flat.height;  // the flat render may be finer than the view's image
    if (!warp.warp || w <= 0 || h <= 0 || width <= 0 || height <= 0) return;
    // The warp at each pixel centre through a camera of that warp alone: its target direction.
    const Camera warped(camera, width, height, {warp});
    const ImageProjection flatImage(camera, w, h);
    const TileRect r{std::max(0, warp.rect.x0), std::max(0, warp.rect.y0), std::min(width, warp.rect.x1), std::min(height, warp.rect.y1)};
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            uint8_t* o = out.pixel(x, y);
            o[0] = o[1] = o[2] = 0;
            // Where the pixel's ray meets the flat image: the flat pixel a 2D offset names, or
            // the surface point's projection (the ray's direction from the eye solves like the
            // point: the two cameras share the eye).
            const Float3 d = warped.direction(float(x) + 0.5f, float(y) + 0.5f);
            if (std::isnan(d.x) || std::isnan(d.y) || std::isnan(d.z)) continue;
            const double v[3] = {d.x, d.y, d.z};
            double abc[3];
            flatImage.solve(v, abc);
            if (!(abc[2] > 0.0)) continue;
            const double fx = abc[0] / abc[2], fy = abc[1] / abc[2];
            sampleBilinear(flat, fx, fy, o);  // a target off the flat image stays black
        }
}


}  // namespace rtwall
