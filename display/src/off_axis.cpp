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
Float3 unit(Float3 a, Float3 fallback) {
    const float l = len(a);
    return l > 0 && std::isfinite(l) ? mul(a, 1.0f / l) : fallback;
}
}  // namespace

EyeWindow wallEyeWindow(const StereoConfig& s, int eye) {
    EyeWindow w;
    w.lowerLeft = s.lowerLeft;
    w.right = sub(s.lowerRight, s.lowerLeft);
    w.up = sub(s.upperLeft, s.lowerLeft);
    const float half = float(s.eyeSeparation * 0.5);
    const float side = eye == 0 ? -half : eye == 1 ? half : 0.0f;
    w.eye = add(s.viewer, mul(unit(w.right, {1, 0, 0}), side));
    return w;
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
