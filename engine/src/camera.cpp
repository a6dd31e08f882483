#include "vec.h"

#include <rtwall/engine.h>

#include <cmath>
#include <numbers>

namespace rtwall {

Camera::Camera(const CameraDesc& desc, int width, int height) {
    const Float3 w = normalize(desc.lookAt - desc.position);  // forward
    Float3 u = normalize(cross(w, desc.up));                   // right
    if (!(dot(u, u) > 0.0f)) u = normalize(cross(w, std::fabs(w.y) < 0.9f ? Float3{0, 1, 0} : Float3{1, 0, 0}));
    const Float3 v = cross(u, w);  // up, orthogonal to both
    const float halfH = std::tan(float(desc.fovY * std::numbers::pi / 360.0));
    const float aspect = height > 0 ? float(width) / float(height) : 1.0f;
    const float halfW = halfH * aspect;
    origin_ = desc.position;
    // Image y grows downwards.
    du_ = u * (2.0f * halfW / float(width));
    dv_ = v * (-2.0f * halfH / float(height));
    corner_ = w - u * halfW + v * halfH;
}

}  // namespace rtwall
