// rtwall core: what a rendered view is, for every library that renders, moves or shows one: the
// camera it was rendered with (CameraDesc, and Camera's rays through its pixels), its pixel
// rectangles and its depth convention. In core, not in the engine, because the display warps
// rendered views to a new pose (issue 27) and links no engine.
#pragma once

#include <rtwall/vec.h>

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rtwall {

struct TileRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // half-open pixel rectangle [x0,x1) x [y0,y1)
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    bool operator==(const TileRect&) const = default;
};

// An off-axis (generalised perspective) projection: the image is the world-space rectangle with
// lower-left corner `lowerLeft` and edges `right` (to the lower-right corner) and `up` (to the
// upper-left corner), seen from the camera's `position`. Pixel (0, 0)'s corner is lowerLeft + up,
// pixel (width, height)'s corner is lowerLeft + right. lookAt, up and fovY are then unused.
struct ProjectionWindow {
    Float3 lowerLeft, right, up;
    bool operator==(const ProjectionWindow&) const = default;
};

// A calibrated projector's pixels (issue 30, docs/mpcdi.md): where each one looks, one sample
// per grid point, top row first, the grid spanning its rectangle of the image edge to edge with
// samples at pixel centres (a grid of the rectangle's size: one sample per pixel). Between
// samples the ray's target is interpolated bilinearly, so supersamples and texture footprints
// follow the warp. A NaN component: that pixel lands on no screen and is black.
struct PixelWarp {
    enum class Kind {
        ScreenOffsets,  // (dx, dy, unused): the pixel looks where the flat camera's pixel (x + dx, y + dy) does (2D profile)
        SurfacePoints,  // (x, y, z): the screen surface point the pixel lands on, room coordinates (metres; 3D profiles)
    };
    Kind kind = Kind::ScreenOffsets;
    int width = 0, height = 0;
    std::vector<Float3> samples;
    bool operator==(const PixelWarp&) const = default;
};
// Room (wall) coordinates to the world, as the display's navigation map (WallToWorld):
// world = origin + (x (p - viewer).x + y (p - viewer).y + z (p - viewer).z) scale.
struct RoomToWorld {
    Float3 origin, viewer;
    Float3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
    float scale = 1.0f;
    Float3 direction(Float3 v) const { return x * v.x + y * v.y + z * v.z; }  // turned only: a unit direction stays unit
    Float3 point(Float3 p) const { return origin + direction(p - viewer) * scale; }
    bool operator==(const RoomToWorld&) const = default;
};
// A warp over one rectangle of a view's image (a screen's viewport); pixels outside every
// rectangle look as the flat camera's do.
struct ScreenWarp {
    TileRect rect;
    std::shared_ptr<const PixelWarp> warp;
    RoomToWorld room;  // SurfacePoints: where the room is in the world this frame
    // ScreenOffsets: image pixels per offset unit (an image smaller than the wall the offsets
    // were made for); 1 multiplies nothing.
    float offsetScaleX = 1.0f, offsetScaleY = 1.0f;
    bool operator==(const ScreenWarp& o) const {
        return rect == o.rect && room == o.room && offsetScaleX == o.offsetScaleX && offsetScaleY == o.offsetScaleY &&
               (warp == o.warp || (warp && o.warp && *warp == *o.warp));
    }
};

// A warp grid's value at image position (px, py) (pixels from the image's top left) inside
// `rect`: bilinear between the samples at pixel centres, clamped at the rectangle's edges; a
// NaN neighbour reaches only where its weight is above zero. What Camera's rays follow, and
// what the post-warp (rtwall/display.h) resamples by.
Float3 sampleWarp(const PixelWarp& warp, const TileRect& rect, float px, float py);

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

// Pinhole camera with derived per-image state computed once; with `warps` (issue 30: a wall's
// calibrated projectors, not scene state) their pixels look where the warps say.
class Camera {
public:
    Camera(const CameraDesc& desc, int width, int height, std::vector<ScreenWarp> warps = {});
    // Direction (unnormalised) through image position (px, py), pixels from the top-left corner.
    // Inline: the kernel calls it for every primary ray. Through a warp a pixel that lands on no
    // screen gets NaN components: the kernel leaves it black.
    Float3 direction(float px, float py) const {
        if (!warps_.empty()) return warpedDirection(px, py);
        return flatDirection(px, py);
    }
    Float3 flatDirection(float px, float py) const {
        return {corner_.x + du_.x * px + dv_.x * py, corner_.y + du_.y * px + dv_.y * py,
                corner_.z + du_.z * px + dv_.z * py};
    }
    bool warped() const { return !warps_.empty(); }
    Float3 origin() const { return origin_; }
    // direction(px, py) = corner() + du() * px + dv() * py: what re-projection inverts to find
    // where a world point lands in this camera's image.
    Float3 corner() const { return corner_; }
    Float3 du() const { return du_; }
    Float3 dv() const { return dv_; }

private:
    Float3 warpedDirection(float px, float py) const;
    Float3 origin_, corner_, du_, dv_;
    std::vector<ScreenWarp> warps_;
};


// A pixel's depth is the distance from the camera's origin along its primary ray to the surface
// it sees (rtwall/engine.h, "Depth with every tile"). Pixels whose rays hit nothing get
// kBackgroundDepth: the largest float, not infinity, so that an infinity or NaN from anywhere
// else stays a hole to the warp.
inline constexpr float kBackgroundDepth = std::numeric_limits<float>::max();

}  // namespace rtwall
