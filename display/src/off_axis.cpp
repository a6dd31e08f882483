// Off-axis stereo frusta from the wall's physical corners and the viewer's head.
#include <rtwall/display.h>

#include <cmath>

namespace rtwall {

namespace {
Float3 add(Float3 a, Float3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Float3 sub(Float3 a, Float3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Float3 mul(Float3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
Float3 cross(Float3 a, Float3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
float len(Float3 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }
// Divided, not multiplied by the reciprocal: an axis-aligned edge gives exactly the axis, so a
// static head along a wall's x axis and a tracked head looking straight at it agree to the bit.
Float3 unit(Float3 a, Float3 fallback) {
    const float l = len(a);
    return l > 0 && std::isfinite(l) ? Float3{a.x / l, a.y / l, a.z / l} : fallback;
}
bool near(Float3 a, Float3 b, float tolerance) { return len(sub(a, b)) <= tolerance; }
}  // namespace

HeadPose staticHead(const StereoConfig& s) {
    HeadPose h;
    h.position = s.viewer;
    h.right = unit(sub(s.lowerRight, s.lowerLeft), {1, 0, 0});
    h.up = unit(sub(s.upperLeft, s.lowerLeft), {0, 1, 0});
    return h;
}

Float3 eyePosition(const HeadPose& head, double eyeSeparation, int eye) {
    const float half = float(eyeSeparation * 0.5);
    const float side = eye == 0 ? -half : eye == 1 ? half : 0.0f;
    return add(head.position, mul(head.right, side));
}

EyeWindow wallEyeWindow(const StereoConfig& s, const HeadPose& head, int eye) {
    EyeWindow w;
    w.lowerLeft = s.lowerLeft;
    w.right = sub(s.lowerRight, s.lowerLeft);
    w.up = sub(s.upperLeft, s.lowerLeft);
    w.eye = eyePosition(head, s.eyeSeparation, eye);
    return w;
}

EyeWindow wallEyeWindow(const StereoConfig& s, int eye) { return wallEyeWindow(s, staticHead(s), eye); }

bool wallHasViews(const WallConfig& wall) {
    if (wall.stereo.mode != StereoMode::None || wall.tracking.enabled) return true;
    for (const ScreenConfig& s : wall.screens)
        if (s.hasCorners) return true;
    return false;
}

std::vector<WallView> wallViews(const WallConfig& wall, const HeadPose& head, int eye) {
    const Float3 e = eyePosition(head, wall.stereo.eyeSeparation, eye);
    auto shows = [eye](const ScreenConfig& s) {
        return s.eye == Eye::Mono || s.eye == Eye::Both || (eye == 0 && s.eye == Eye::Left) || (eye == 1 && s.eye == Eye::Right);
    };
    std::vector<WallView> views;
    if (wall.screens.empty() || !wall.screens.front().hasCorners) {
        WallView v;
        v.window = wallEyeWindow(wall.stereo, head, eye);
        for (size_t i = 0; i < wall.screens.size(); ++i)
            if (shows(wall.screens[i])) v.screens.push_back(i);
        views.push_back(std::move(v));
        return views;
    }
    const double W = wall.width, H = wall.height;
    for (size_t i = 0; i < wall.screens.size(); ++i) {
        const ScreenConfig& s = wall.screens[i];
        if (!shows(s)) continue;
        // Per wall pixel along the screen's edges, then out to the whole image's edges (image y
        // grows downwards: below the screen lie H - (y + height) rows).
        const PixelRect& vp = s.viewport;
        auto d = [](Float3 a) { return std::array<double, 3>{a.x, a.y, a.z}; };
        const auto ll = d(s.lowerLeft), lr = d(s.lowerRight), ul = d(s.upperLeft);
        EyeWindow w;
        w.eye = e;
        std::array<double, 3> lower{}, right{}, up{};
        for (int k = 0; k < 3; ++k) {
            const double du = (lr[size_t(k)] - ll[size_t(k)]) / vp.width, dv = (ul[size_t(k)] - ll[size_t(k)]) / vp.height;
            lower[size_t(k)] = ll[size_t(k)] - du * vp.x - dv * (H - (vp.y + vp.height));
            right[size_t(k)] = du * W;
            up[size_t(k)] = dv * H;
        }
        w.lowerLeft = {float(lower[0]), float(lower[1]), float(lower[2])};
        w.right = {float(right[0]), float(right[1]), float(right[2])};
        w.up = {float(up[0]), float(up[1]), float(up[2])};
        // Screens that line up (one plane, one pixel pitch) share a render.
        const float tolerance = 1e-5f * (len(w.right) + len(w.up));
        bool joined = false;
        for (WallView& v : views)
            if (near(v.window.lowerLeft, w.lowerLeft, tolerance) && near(v.window.right, w.right, tolerance) &&
                near(v.window.up, w.up, tolerance)) {
                v.screens.push_back(i);
                joined = true;
                break;
            }
        if (!joined) views.push_back({w, {i}});
    }
    return views;
}

EyeWindow eyeWindowInWorld(const EyeWindow& wall, const Float3& viewer, const ViewPose& pose) {
    // The camera's orthonormal frame, as the engine's Camera builds it.
    const Float3 forward = unit(sub(pose.lookAt, pose.position), {0, 0, -1});
    Float3 right = unit(cross(forward, pose.up), {0, 0, 0});
    if (len(right) == 0)
        right = unit(cross(forward, std::fabs(forward.y) < 0.9f ? Float3{0, 1, 0} : Float3{1, 0, 0}), {1, 0, 0});
    const Float3 up = cross(right, forward);
    const Float3 back = mul(forward, -1.0f);
    auto dir = [&](Float3 v) { return add(add(mul(right, v.x), mul(up, v.y)), mul(back, v.z)); };
    auto point = [&](Float3 p) { return add(pose.position, dir(sub(p, viewer))); };
    return {point(wall.eye), point(wall.lowerLeft), dir(wall.right), dir(wall.up)};
}

}  // namespace rtwall
