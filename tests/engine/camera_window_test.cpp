// The off-axis (generalised perspective) camera: a projection window seen from the eye.
#include "test_util.h"

#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace rtwall {
namespace {

// Every component within `tol` (0: the same floats).
void expectNear(Float3 a, Float3 b, float tol, const char* what) {
    EXPECT_LE(maxAbsComponent(a - b), tol) << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") against ("
                                           << b.x << ", " << b.y << ", " << b.z << ")";
}

// The window a symmetric camera implies: the image rectangle at distance 1 along the view axis.
CameraDesc asWindow(const CameraDesc& c, int width, int height) {
    const Float3 w = normalize(c.lookAt - c.position);
    const Float3 u = normalize(cross(w, c.up));
    const Float3 v = cross(u, w);
    const float halfH = std::tan(float(c.fovY * std::numbers::pi / 360.0));
    const float halfW = halfH * float(width) / float(height);
    CameraDesc o = c;
    o.lookAt = {123, 45, 6};  // unused with a window
    o.fovY = 10;
    o.window = ProjectionWindow{(c.position + w) - (u * halfW + v * halfH), u * (2 * halfW), v * (2 * halfH)};
    return o;
}

TEST(CameraWindow, PixelCornersHitWindowCorners) {
    CameraDesc c;
    c.position = {0.3f, -0.2f, 2.0f};
    c.window = ProjectionWindow{{-1.0f, -0.75f, 0.0f}, {2.0f, 0.0f, 0.1f}, {0.0f, 1.5f, -0.05f}};
    const int W = 64, H = 48;
    const Camera cam(c, W, H);
    const ProjectionWindow& w = *c.window;
    expectNear(cam.origin(), c.position, 0, "origin is the eye");
    expectNear(cam.origin() + cam.direction(0, 0), w.lowerLeft + w.up, 1e-5f, "top-left");
    expectNear(cam.origin() + cam.direction(W, 0), w.lowerLeft + w.up + w.right, 1e-5f, "top-right");
    expectNear(cam.origin() + cam.direction(0, H), w.lowerLeft, 1e-5f, "bottom-left");
    expectNear(cam.origin() + cam.direction(W, H), w.lowerLeft + w.right, 1e-5f, "bottom-right");
    expectNear(cam.origin() + cam.direction(W / 2.0f, H / 2.0f), w.lowerLeft + (w.right + w.up) * 0.5f, 1e-5f, "centre");
}

TEST(CameraWindow, OffCentreEyeGivesHandComputedAsymmetricFrustum) {
    // A 2 x 1.5 window in the z = 0 plane, the eye 2 in front of it and 0.5 right of centre:
    // the frustum's left edge is atan(1.5 / 2) = 36.87 degrees off the axis, its right edge
    // atan(0.5 / 2) = 14.04 degrees; bottom and top are both atan(0.75 / 2).
    CameraDesc c;
    c.position = {0.5f, 0.0f, 2.0f};
    c.window = ProjectionWindow{{-1.0f, -0.75f, 0.0f}, {2.0f, 0.0f, 0.0f}, {0.0f, 1.5f, 0.0f}};
    const int W = 80, H = 60;
    const Camera cam(c, W, H);
    const Float3 left = cam.direction(0, H / 2.0f), right = cam.direction(W, H / 2.0f);
    const Float3 top = cam.direction(W * 0.75f, 0), bottom = cam.direction(W * 0.75f, H);
    EXPECT_NEAR(-left.x / -left.z, 0.75f, 1e-6f);
    EXPECT_NEAR(right.x / -right.z, 0.25f, 1e-6f);
    EXPECT_NEAR(top.y / -top.z, 0.375f, 1e-6f);
    EXPECT_NEAR(-bottom.y / -bottom.z, 0.375f, 1e-6f);
    // The ray along the axis (perpendicular to the wall) goes through pixel x = 0.75 W.
    const Float3 axis = cam.direction(W * 0.75f, H / 2.0f);
    EXPECT_NEAR(axis.x, 0.0f, 1e-6f);
    EXPECT_NEAR(axis.y, 0.0f, 1e-6f);
}

TEST(CameraWindow, SymmetricWindowMatchesOrdinaryCamera) {
    SceneDesc desc = test::demoScene(160, 120, 1);
    const Scene scene(desc);
    const CameraDesc plain = desc.cameras.front();
    const CameraDesc windowed = asWindow(plain, desc.settings.width, desc.settings.height);
    const Camera a(plain, desc.settings.width, desc.settings.height), b(windowed, desc.settings.width, desc.settings.height);
    // Rays agree to float rounding...
    for (float py : {0.0f, 37.5f, 120.0f})
        for (float px : {0.0f, 81.25f, 160.0f}) expectNear(a.direction(px, py), b.direction(px, py), 1e-5f, "ray");
    // ...and so do the images: rounding may move a silhouette by a pixel, nothing more. Tolerance:
    // at most 0.2% of the bytes differ at all, and the mean absolute difference is under 0.1 levels.
    const Image ia = renderFrame(scene, a, desc.settings), ib = renderFrame(scene, b, desc.settings);
    ASSERT_EQ(ia.rgb.size(), ib.rgb.size());
    size_t differ = 0;
    double sum = 0;
    for (size_t i = 0; i < ia.rgb.size(); ++i) {
        differ += ia.rgb[i] != ib.rgb[i];
        sum += std::abs(int(ia.rgb[i]) - int(ib.rgb[i]));
    }
    std::printf("symmetric window vs camera: %zu of %zu bytes differ, mean |diff| %.4f\n", differ, ia.rgb.size(),
                sum / double(ia.rgb.size()));
    EXPECT_LE(differ, ia.rgb.size() / 500);
    EXPECT_LT(sum / double(ia.rgb.size()), 0.1);
}

TEST(CameraWindow, AbsentWindowIsTheOrdinaryCamera) {
    CameraDesc c;
    c.position = {1, 2, 3};
    c.lookAt = {0, 0.5f, -1};
    c.fovY = 50;
    const Camera a(c, 32, 24);
    c.window.reset();
    const Camera b(c, 32, 24);
    for (float p : {0.0f, 7.5f, 24.0f}) {
        const Float3 da = a.direction(p, p), db = b.direction(p, p);
        EXPECT_EQ(da.x, db.x);
        EXPECT_EQ(da.y, db.y);
        EXPECT_EQ(da.z, db.z);
    }
}

}  // namespace
}  // namespace rtwall
