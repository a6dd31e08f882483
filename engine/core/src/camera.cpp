#include <rtwall/camera.h>

#include <cmath>
#include <numbers>

namespace rtwall {

Camera::Camera(const CameraDesc& desc, int width, int height) {
    origin_ = desc.position;
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

bool samePose(const CameraDesc& a, const CameraDesc& b) {
    return a.position == b.position && a.lookAt == b.lookAt && a.up == b.up && a.fovY == b.fovY && a.window == b.window;
}

}  // namespace rtwall
