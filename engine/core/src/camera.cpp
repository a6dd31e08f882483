#include <rtwall/camera.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace rtwall {

Camera::Camera(const CameraDesc& desc, int width, int height, std::vector<ScreenWarp> warps) {
    origin_ = desc.position;
    for (ScreenWarp& w : warps)
        if (w.warp && w.warp->width > 0 && w.warp->height > 0 && w.rect.width() > 0 && w.rect.height() > 0 &&
            w.warp->samples.size() == size_t(w.warp->width) * size_t(w.warp->height))
            warps_.push_back(std::move(w));
    if (desc.window) {
        // Off-axis: rays from the eye through the window; image y grows downwards.
        const ProjectionWindow& w = *desc.window;
        corner_ = w.lowerLeft + w.up - desc.position;
        du_ = w.right * (1.0f / float(width > 0 ? width : 1));
        dv_ = w.up * (-1.0f / float(height > 0 ? height : 1));
        return;
    }
    const Float3 w = normalize(desc.lookAt - desc.position);  // forward
    Float3 u = normalize(cross(w, desc.up));                   // right
    if (!(dot(u, u) > 0.0f)) u = normalize(cross(w, std::fabs(w.y) < 0.9f ? Float3{0, 1, 0} : Float3{1, 0, 0}));
    const Float3 v = cross(u, w);  // up, orthogonal to both
    const float halfH = std::tan(float(desc.fovY * std::numbers::pi / 360.0));
    const float aspect = height > 0 ? float(width) / float(height) : 1.0f;
    const float halfW = halfH * aspect;
    // Image y grows downwards.
    du_ = u * (2.0f * halfW / float(width));
    dv_ = v * (-2.0f * halfH / float(height));
    corner_ = w - u * halfW + v * halfH;
}

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

bool hasNaN(Float3 v) { return std::isnan(v.x) || std::isnan(v.y) || std::isnan(v.z); }

// a + t (b - a), and exactly a where t is 0 (b may be NaN there: a neighbour off the screen
// does not darken a sample that does not reach it), exactly a where b equals a.
Float3 lerp(Float3 a, Float3 b, float t) {
    if (t == 0.0f) return a;
    return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)};
}

}  // namespace

Float3 sampleWarp(const PixelWarp& w, const TileRect& rect, float px, float py) {
    // Grid coordinates of the position; a grid of the rectangle's size needs no scaling (and
    // so is exact at pixel centres).
    float gx = px - float(rect.x0), gy = py - float(rect.y0);
    if (w.width != rect.width()) gx *= float(w.width) / float(rect.width());
    if (w.height != rect.height()) gy *= float(w.height) / float(rect.height());
    gx = std::clamp(gx - 0.5f, 0.0f, float(w.width - 1));
    gy = std::clamp(gy - 0.5f, 0.0f, float(w.height - 1));
    const int i0 = int(gx), j0 = int(gy);
    const int i1 = std::min(i0 + 1, w.width - 1), j1 = std::min(j0 + 1, w.height - 1);
    const float fx = gx - float(i0), fy = gy - float(j0);
    const auto at = [&](int i, int j) { return w.samples[size_t(j) * size_t(w.width) + size_t(i)]; };
    const Float3 top = lerp(at(i0, j0), at(i1, j0), fx);
    if (fy == 0.0f) return top;
    return lerp(top, lerp(at(i0, j1), at(i1, j1), fx), fy);
}

Float3 Camera::warpedDirection(float px, float py) const {
    const int x = int(std::floor(px)), y = int(std::floor(py));
    for (const ScreenWarp& v : warps_) {
        if (x < v.rect.x0 || x >= v.rect.x1 || y < v.rect.y0 || y >= v.rect.y1) continue;
        const PixelWarp& w = *v.warp;
        const Float3 s = sampleWarp(w, v.rect, px, py);
        if (hasNaN(s)) return {kNaN, kNaN, kNaN};
        if (w.kind == PixelWarp::Kind::ScreenOffsets) {
            if (v.offsetScaleX == 1.0f && v.offsetScaleY == 1.0f) return flatDirection(px + s.x, py + s.y);
            return flatDirection(px + s.x * v.offsetScaleX, py + s.y * v.offsetScaleY);
        }
        return v.room.point(s) - origin_;
    }
    return flatDirection(px, py);
}

bool samePose(const CameraDesc& a, const CameraDesc& b) {
    return a.position == b.position && a.lookAt == b.lookAt && a.up == b.up && a.fovY == b.fovY && a.window == b.window;
}

}  // namespace rtwall
