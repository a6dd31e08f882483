// rtwall core: what a rendered view is, for every library that renders, moves or shows one: the
// camera it was rendered with (CameraDesc, and Camera's rays through its pixels), its pixel
// rectangles and its depth convention. In core, not in the engine, because the display warps
// rendered views to a new pose (issue 27) and links no engine.
#pragma once

#include <rtwall/vec.h>

#include <limits>
#include <optional>
#include <string>

namespace rtwall {

// An off-axis (generalised perspective) projection: the image is the world-space rectangle with
// lower-left corner `lowerLeft` and edges `right` (to the lower-right corner) and `up` (to the
// upper-left corner), seen from the camera's `position`. Pixel (0, 0)'s corner is lowerLeft + up,
// pixel (width, height)'s corner is lowerLeft + right. lookAt, up and fovY are then unused.
struct ProjectionWindow {
    Float3 lowerLeft, right, up;
    bool operator==(const ProjectionWindow&) const = default;
};

struct CameraDesc {
    std::string name = "default";
    Float3 position{0, 0, 5};
    Float3 lookAt{0, 0, 0};
    Float3 up{0, 1, 0};
    float fovY = 45.0f;  // vertical field of view in degrees
    std::optional<ProjectionWindow> window;  // absent: the symmetric camera above
    bool operator==(const CameraDesc&) const = default;
};

// The same geometry, any name: whether two cameras see alike.
bool samePose(const CameraDesc& a, const CameraDesc& b);

// Pinhole camera with derived per-image state computed once.
class Camera {
public:
    Camera(const CameraDesc& desc, int width, int height);
    // Direction (unnormalised) through image position (px, py), pixels from the top-left corner.
    // Inline: the kernel calls it for every primary ray.
    Float3 direction(float px, float py) const {
        return {corner_.x + du_.x * px + dv_.x * py, corner_.y + du_.y * px + dv_.y * py,
                corner_.z + du_.z * px + dv_.z * py};
    }
    Float3 origin() const { return origin_; }
    // direction(px, py) = corner() + du() * px + dv() * py: what re-projection inverts to find
    // where a world point lands in this camera's image.
    Float3 corner() const { return corner_; }
    Float3 du() const { return du_; }
    Float3 dv() const { return dv_; }

private:
    Float3 origin_, corner_, du_, dv_;
};

struct TileRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // half-open pixel rectangle [x0,x1) x [y0,y1)
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    bool operator==(const TileRect&) const = default;
};

// A pixel's depth is the distance from the camera's origin along its primary ray to the surface
// it sees (rtwall/engine.h, "Depth with every tile"). Pixels whose rays hit nothing get
// kBackgroundDepth: the largest float, not infinity, so that an infinity or NaN from anywhere
// else stays a hole to the warp.
inline constexpr float kBackgroundDepth = std::numeric_limits<float>::max();

}  // namespace rtwall
