// Off-axis stereo frusta from the wall's physical corners and the viewer's head.
#include <rtwall/display.h>
#include <rtwall/vec.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rtwall {

namespace {
// Divided, not multiplied by the reciprocal: an axis-aligned edge gives exactly the axis, so a
// static head along a wall's x axis and a tracked head looking straight at it agree to the bit.
Float3 unit(Float3 a, Float3 fallback) {
    const float l = length(a);
    return l > 0 && std::isfinite(l) ? Float3{a.x / l, a.y / l, a.z / l} : fallback;
}
bool near(Float3 a, Float3 b, float tolerance) { return length(a - b) <= tolerance; }
}  // namespace

HeadPose staticHead(const StereoConfig& s) {
    HeadPose h;
    h.position = s.viewer;
    h.right = unit(s.lowerRight - s.lowerLeft, {1, 0, 0});
    h.up = unit(s.upperLeft - s.lowerLeft, {0, 1, 0});
    return h;
}

Float3 eyePosition(const HeadPose& head, double eyeSeparation, int eye) {
    const float half = float(eyeSeparation * 0.5);
    const float side = eye == 0 ? -half : eye == 1 ? half : 0.0f;
    return head.position + head.right * side;
}

EyeWindow wallEyeWindow(const StereoConfig& s, const HeadPose& head, int eye) {
    EyeWindow w;
    w.lowerLeft = s.lowerLeft;
    w.right = s.lowerRight - s.lowerLeft;
    w.up = s.upperLeft - s.lowerLeft;
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
        const float tolerance = 1e-5f * (length(w.right) + length(w.up));
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

WallToWorld wallToWorld(const Float3& viewer, const ViewPose& pose, double scale) {
    // The camera's orthonormal frame, as the engine's Camera builds it.
    const Float3 forward = unit(pose.lookAt - pose.position, {0, 0, -1});
    Float3 right = unit(cross(forward, pose.up), {0, 0, 0});
    if (length(right) == 0)
        right = unit(cross(forward, std::fabs(forward.y) < 0.9f ? Float3{0, 1, 0} : Float3{1, 0, 0}), {1, 0, 0});
    const Float3 up = cross(right, forward);
    return {pose.position, viewer, right, up, forward * -1.0f, float(scale)};
}


EyeWindow eyeWindowInWorld(const EyeWindow& wall, const Float3& viewer, const ViewPose& pose, double scale) {
    const WallToWorld m = wallToWorld(viewer, pose, scale);
    return {m.point(wall.eye), m.point(wall.lowerLeft), m.direction(wall.right) * m.scale, m.direction(wall.up) * m.scale};
}

ViewPose rescaledPose(const ViewPose& pose, const Float3& viewer, double scale, double newScale, const Float3& fixed) {
    // fixed lands at origin + s R (fixed - viewer); keeping it there at the new scale moves the
    // origin (the camera) by (s - s') R (fixed - viewer). In double: far from the scene's origin
    // the float pose would round the step.
    const WallToWorld m = wallToWorld(viewer, pose);
    const Float3 d = m.direction(fixed - viewer);
    const double k = scale - newScale;
    const std::array<double, 3> move{k * d.x, k * d.y, k * d.z};
    auto moved = [&](Float3 p) { return Float3{float(p.x + move[0]), float(p.y + move[1]), float(p.z + move[2])}; };
    ViewPose out = pose;
    out.position = moved(pose.position);
    out.lookAt = moved(pose.lookAt);
    return out;
}

namespace {
// One pixel-wide line from (x0, y0) to (x1, y1) (image pixels), 2 pixels thick, only inside
// `clip`, as rectangles of eye `eye`: each step a 2x2 square, clipped, merged with the one before
// where the two make a rectangle (the same rows, touching columns, or the other way round).
void lineRects(int eye, double x0, double y0, double x1, double y1, const PixelRect& clip, std::array<uint8_t, 3> colour,
               std::vector<EyePaint>& out) {
    // Cut to the clip rectangle first (Liang-Barsky): a point almost level with the eye projects
    // far off the screens.
    double t0 = 0, t1 = 1;
    const double ddx = x1 - x0, ddy = y1 - y0;
    const double p[4] = {-ddx, ddx, -ddy, ddy};
    const double q[4] = {x0 - (clip.x - 1), (clip.x + clip.width) - x0, y0 - (clip.y - 1), (clip.y + clip.height) - y0};
    for (int k = 0; k < 4; ++k) {
        if (p[k] == 0) {
            if (q[k] < 0) return;
            continue;
        }
        const double r = q[k] / p[k];
        if (p[k] < 0) t0 = std::max(t0, r);
        else t1 = std::min(t1, r);
    }
    if (!(t0 <= t1)) return;
    x1 = x0 + ddx * t1, y1 = y0 + ddy * t1;
    x0 = x0 + ddx * t0, y0 = y0 + ddy * t0;
    const double steps = std::ceil(std::max(std::fabs(x1 - x0), std::fabs(y1 - y0)));
    if (!(steps < 1e6)) return;  // not finite
    const size_t first = out.size();
    for (int i = 0; i <= int(steps); ++i) {
        const double t = steps > 0 ? i / steps : 0.0;
        const int px = int(std::floor(x0 + (x1 - x0) * t)), py = int(std::floor(y0 + (y1 - y0) * t));
        const TileRect r{std::max(px, clip.x), std::max(py, clip.y), std::min(px + 2, clip.x + clip.width), std::min(py + 2, clip.y + clip.height)};
        if (r.width() <= 0 || r.height() <= 0) continue;
        if (out.size() > first) {
            TileRect& last = out.back().rect;
            if (last.y0 == r.y0 && last.y1 == r.y1 && r.x0 <= last.x1 && r.x1 >= last.x0) {
                last.x0 = std::min(last.x0, r.x0), last.x1 = std::max(last.x1, r.x1);
                continue;
            }
            if (last.x0 == r.x0 && last.x1 == r.x1 && r.y0 <= last.y1 && r.y1 >= last.y0) {
                last.y0 = std::min(last.y0, r.y0), last.y1 = std::max(last.y1, r.y1);
                continue;
            }
        }
        out.push_back({eye, r, colour});
    }
}
}  // namespace

void applyPaints(const std::vector<EyePaint>& paints, int eye, Image& image) {
    for (const EyePaint& p : paints) {
        if (p.eye != eye) continue;
        for (int y = std::max(p.rect.y0, 0); y < std::min(p.rect.y1, image.height); ++y)
            for (int x = std::max(p.rect.x0, 0); x < std::min(p.rect.x1, image.width); ++x)
                std::memcpy(&image.rgb[(size_t(y) * size_t(image.width) + size_t(x)) * 3], p.colour.data(), 3);
    }
}

void drawWandRay(const WallConfig& wall, const HeadPose& head, int eye, const Float3& from, const Float3& to, Image& image,
                 std::array<uint8_t, 3> colour) {
    std::vector<EyePaint> paints;
    wandRayPaints(wall, head, eye, from, to, image.width, image.height, paints, colour);
    applyPaints(paints, eye == 1 ? 1 : 0, image);
}

void wandRayPaints(const WallConfig& wall, const HeadPose& head, int eye, const Float3& from, const Float3& to, int width,
                   int height, std::vector<EyePaint>& out, std::array<uint8_t, 3> colour) {
    if (width <= 0 || height <= 0 || wall.width <= 0 || wall.height <= 0) return;
    const double sx = double(width) / wall.width, sy = double(height) / wall.height;
    for (const WallView& v : wallViews(wall, head, eye)) {
        const EyeWindow& w = v.window;
        const Float3 n = cross(w.right, w.up);  // towards the viewer's side of the screens
        const double nn = double(length(n));
        if (!(nn > 0)) continue;
        // Signed distance of a point in front of the eye (towards the screens), along the normal.
        auto depth = [&](Float3 p) { return -double(n.x * (p.x - w.eye.x) + n.y * (p.y - w.eye.y) + n.z * (p.z - w.eye.z)) / nn; };
        Float3 a = from, b = to;
        double da = depth(a), db = depth(b);
        const double nearPlane = 1e-3;  // metres: the part of the ray behind the eye is not seen
        if (da < nearPlane && db < nearPlane) continue;
        if (da < nearPlane) a = a + (b - a) * float((nearPlane - da) / (db - da)), da = nearPlane;
        if (db < nearPlane) b = a + (b - a) * float((nearPlane - da) / (db - da)), db = nearPlane;
        const double screenDepth = depth(w.lowerLeft);
        // Onto the plane from the eye, then into the view's image coordinates (y down).
        auto project = [&](Float3 p, double d, double& px, double& py) {
            const double s = screenDepth / d;
            const double q[3] = {w.eye.x + (p.x - w.eye.x) * s - w.lowerLeft.x, w.eye.y + (p.y - w.eye.y) * s - w.lowerLeft.y,
                                 w.eye.z + (p.z - w.eye.z) * s - w.lowerLeft.z};
            const double rr = double(w.right.x) * w.right.x + double(w.right.y) * w.right.y + double(w.right.z) * w.right.z;
            const double uu = double(w.up.x) * w.up.x + double(w.up.y) * w.up.y + double(w.up.z) * w.up.z;
            const double u = (q[0] * w.right.x + q[1] * w.right.y + q[2] * w.right.z) / rr;
            const double vv = (q[0] * w.up.x + q[1] * w.up.y + q[2] * w.up.z) / uu;
            px = u * wall.width * sx;
            py = (1.0 - vv) * wall.height * sy;
        };
        double x0, y0, x1, y1;
        project(a, da, x0, y0);
        project(b, db, x1, y1);
        for (size_t i : v.screens) {
            const PixelRect& r = wall.screens[i].viewport;
            const int cx0 = int(std::floor(r.x * sx)), cy0 = int(std::floor(r.y * sy));
            const PixelRect clip{cx0, cy0, int(std::ceil((r.x + r.width) * sx)) - cx0, int(std::ceil((r.y + r.height) * sy)) - cy0};
            lineRects(eye == 1 ? 1 : 0, x0, y0, x1, y1, {clip.x, clip.y, std::min(clip.width, width - clip.x), std::min(clip.height, height - clip.y)},
                      colour, out);
        }
    }
}

}  // namespace rtwall
