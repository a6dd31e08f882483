// Section planes (issue 20): analytic areas of a clipped sphere and of its cap, the shadow of a
// clipped occluder, the kernels and packet widths bit-identical with planes, picking through a
// cut, and a plane update that rebuilds nothing.
#include "image_compare.h"
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace rtwall {
namespace {

constexpr double kPi = std::numbers::pi;

// A camera 1000 units up the +z axis (or wherever `position` says) with a field of view that
// shows `extent` x `extent` units around `lookAt`: orthographic to about (r/1000)^2 = 1e-6.
CameraDesc farCamera(Float3 position, Float3 lookAt, Float3 up, double extent) {
    CameraDesc c;
    c.position = position;
    c.lookAt = lookAt;
    c.up = up;
    const double dist = std::sqrt(double(position.x - lookAt.x) * (position.x - lookAt.x) +
                                  double(position.y - lookAt.y) * (position.y - lookAt.y) +
                                  double(position.z - lookAt.z) * (position.z - lookAt.z));
    c.fovY = float(2.0 * std::atan(0.5 * extent / dist) * 180.0 / kPi);
    return c;
}

// A unit sphere (fine enough that the polygon's area is within 0.05% of the circle's), green,
// lit by ambient light alone: a pixel is exactly its albedo, so green = sphere, red = cap.
SceneDesc sphereScene(const Transform& placement, int size) {
    SceneDesc s;
    s.meshes.push_back({"sphere", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(128, 256))});
    Material green;
    green.color = {0, 1, 0};
    s.materials.push_back(green);
    s.instances.push_back({0, 0, placement});
    test::setImage(s.settings, size, size, 32);
    s.settings.ambient = {1, 1, 1};
    s.settings.background = {0, 0, 0};
    s.settings.threads = 2;
    return s;
}

SectionPlane plane(Float3 point, Float3 normal, Color cap = {1, 0, 0}) {
    SectionPlane p;
    p.enabled = true;
    p.point = point;
    p.normal = normal;
    p.capColor = cap;
    return p;
}

struct Counts {
    size_t sphere = 0, cap = 0, background = 0;
};
Counts countPixels(const Image& img) {
    Counts c;
    for (size_t i = 0; i < img.rgb.size(); i += 3) {
        const uint8_t r = img.rgb[i], g = img.rgb[i + 1], b = img.rgb[i + 2];
        if (r > 128 && g < 64 && b < 64) ++c.cap;
        else if (g > 128 && r < 64 && b < 64) ++c.sphere;
        else if (r == 0 && g == 0 && b == 0) ++c.background;
    }
    return c;
}

Image render(const SceneDesc& d, const CameraDesc& camera) {
    const Scene scene(d);
    return renderFrame(scene, Camera(camera, d.settings.width, d.settings.height), d.settings);
}

// 300 x 300 pixels over 3 x 3 units: a pixel is 1e-4 square units. The boundary of a unit disk
// crosses about 630 pixels, each counted whole or not at all by its centre: the count is within
// 0.5% of the area (sqrt(630) pixels of noise, 0.05% of polygon error).
constexpr int kSize = 300;
constexpr double kPixelArea = (3.0 / kSize) * (3.0 / kSize);

TEST(Section, HalvedSphereShowsHalfItsSilhouette) {
    SceneDesc d = sphereScene(Transform{}, kSize);
    const CameraDesc cam = farCamera({0, 0, 1000}, {0, 0, 0}, {0, 1, 0}, 3.0);
    const Counts whole = countPixels(render(d, cam));
    EXPECT_NEAR(whole.sphere * kPixelArea, kPi, 0.005 * kPi);
    // Keep y >= 0: seen from the side, the upper half disk; the cap is edge-on.
    d.sections[2] = plane({0, 0, 0}, {0, 1, 0});
    const Counts half = countPixels(render(d, cam));
    EXPECT_NEAR((half.sphere + half.cap) * kPixelArea, kPi / 2, 0.005 * kPi);
    EXPECT_LT(half.cap, 2 * size_t(kSize)) << "the cap is seen edge-on";
    // At an offset: keep y >= 0.5, a circular segment of area acos(0.5) - 0.5 sqrt(0.75).
    d.sections[2] = plane({0, 0.5f, 0}, {0, 2, 0});  // the normal need not be unit length
    const Counts segment = countPixels(render(d, cam));
    const double area = std::acos(0.5) - 0.5 * std::sqrt(0.75);
    EXPECT_NEAR((segment.sphere + segment.cap) * kPixelArea, area, 0.01 * area + 300 * kPixelArea);
}

// The cut faces the camera: the cap is a disk of radius sqrt(1 - d^2) where the plane lies at
// distance d from the centre, in the cap colour; the rest of the kept part around it shows the
// sphere. The sphere is placed by a rotated, translated instance: the cap must follow the
// instance (the back-face test uses its normal matrix).
TEST(Section, CapAreaIsTheCutDisk) {
    const Transform placement = Transform::translate(0.25, -0.5, 3.0) * Transform::rotateDegrees(1, 1, 0, 40);
    for (double offset : {0.0, 0.5, -0.6}) {
        SCOPED_TRACE("plane at distance " + std::to_string(offset) + " from the centre");
        SceneDesc d = sphereScene(placement, kSize);
        const CameraDesc cam = farCamera({0.25f, -0.5f, 1000}, {0.25f, -0.5f, 3}, {0, 1, 0}, 3.0);
        // Keep z <= 3 + offset: everything nearer the camera is cut away.
        d.sections[0] = plane({0.25f, -0.5f, float(3.0 + offset)}, {0, 0, -1});
        const Counts c = countPixels(render(d, cam));
        const double capArea = kPi * (1.0 - offset * offset);
        EXPECT_NEAR(c.cap * kPixelArea, capArea, 0.005 * kPi);
        // Beyond the centre the kept part's outline is the equator; before it, the cap's rim.
        const double outline = offset >= 0 ? kPi : capArea;
        EXPECT_NEAR((c.cap + c.sphere) * kPixelArea, outline, 0.005 * kPi);
        // Without caps the inside of the sphere shows through the cut (its back faces, green).
        d.sections[0].caps = false;
        const Counts open = countPixels(render(d, cam));
        EXPECT_EQ(open.cap, 0u);
        EXPECT_NEAR(open.sphere * kPixelArea, outline, 0.005 * kPi);
    }
}

// Two planes cut a wedge: only what both keep is left, and each cap has its own colour.
TEST(Section, TwoPlanesKeepTheirIntersectionWithACapEach) {
    SceneDesc d = sphereScene(Transform{}, kSize);
    const CameraDesc cam = farCamera({0, 0, 1000}, {0, 0, 0}, {0, 1, 0}, 3.0);
    d.sections[0] = plane({0, 0, 0}, {0, 0, -1});           // cut the front half away: a red cap disk
    d.sections[4] = plane({0, 0, 0}, {1, 0, 0}, {0, 0, 1});  // and keep x >= 0
    const Image img = render(d, cam);
    const Counts c = countPixels(img);
    EXPECT_NEAR(c.cap * kPixelArea, kPi / 2, 0.005 * kPi) << "the front cap, halved by the second plane";
    size_t blue = 0;
    for (size_t i = 0; i < img.rgb.size(); i += 3) blue += img.rgb[i + 2] > 128 && img.rgb[i] < 64;
    EXPECT_LT(blue, 2 * size_t(kSize)) << "the second cap is edge-on";
    EXPECT_NEAR(c.background * kPixelArea, 9.0 - kPi / 2, 0.005 * kPi);
}

// A disabled plane and a scene without planes give the same bytes.
TEST(Section, DisabledPlanesCutNothing) {
    SceneDesc d = test::materialZoo(test::scratchDir());
    const Image reference = render(d, d.cameras.front());
    d.sections[3] = plane({0, 0, 0}, {1, 0, 0});
    d.sections[3].enabled = false;
    const Image disabled = render(d, d.cameras.front());
    EXPECT_EQ(disabled.rgb, reference.rgb);
    d.sections[3].enabled = true;
    EXPECT_NE(render(d, d.cameras.front()).rgb, reference.rgb);
}

// A directional light at 45 degrees casts a unit sphere's shadow onto the floor 4 below it: an
// ellipse of area pi sqrt(2). With the half x < 0 cut away the shadow is that of the half ball,
// (1 + sqrt(2)) pi / 2 (for each z, the half disk of radius rho projects onto a segment of length
// rho (1 + sqrt(2)) instead of 2 sqrt(2) rho).
TEST(Section, AClippedOccludersShadowShrinks) {
    SceneDesc s;
    s.meshes.push_back({"sphere", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(128, 256))});
    s.meshes.push_back({"quad", "shape:quad", std::make_shared<const TriangleMesh>(makeQuad())});
    Material white;
    white.color = {1, 1, 1};
    s.materials.push_back(white);
    s.instances.push_back({0, 0, Transform{}});
    s.instances.push_back({1, 0, Transform::translate(4, -4, 0) * Transform::scale(5, 1, 5)});
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {1, -1, 0};
    sun.intensity = 3.0f;
    s.lights.push_back(sun);
    s.settings.width = s.settings.height = kSize;
    s.settings.ambient = {0.05f, 0.05f, 0.05f};
    s.settings.background = {0, 0, 0};
    s.settings.threads = 2;
    // From straight above, 3 x 3 units around the shadow's centre (4, -4, 0): the sphere itself
    // (x within [-1, 1]) is outside the picture.
    const CameraDesc cam = farCamera({4, 1000, 0}, {4, -4, 0}, {0, 0, -1}, 3.0);
    auto shadowArea = [&](const SceneDesc& d) {
        const Image img = render(d, cam);
        size_t dark = 0;
        for (size_t i = 0; i < img.rgb.size(); i += 3) dark += img.rgb[i] > 0 && img.rgb[i] < 128;
        return double(dark) * kPixelArea;
    };
    EXPECT_NEAR(shadowArea(s), kPi * std::sqrt(2.0), 0.01 * kPi);
    s.sections[1] = plane({0, 0, 0}, {1, 0, 0});
    EXPECT_NEAR(shadowArea(s), (1.0 + std::sqrt(2.0)) * kPi / 2, 0.01 * kPi);
}

// Every material (mirror, glass, metal, alpha masks, a volume, an area light) cut by two planes
// with caps: the single-ray kernel and packets of every width give the same bytes, with and
// without path tracing.
TEST(Section, PacketsOfEveryWidthMatchTheSingleRayKernel) {
    SceneDesc d = test::materialZoo(test::scratchDir(), 96, 64);
    d.settings.threads = 2;
    d.sections[0] = plane({0.2f, 0, 0}, {-1, 0, 0.3f}, {0.9f, 0.5f, 0.1f});
    d.sections[5] = plane({0, 0, -0.1f}, {0, -0.2f, -1}, {0.1f, 0.3f, 0.9f});
    for (bool gi : {false, true}) {
        d.settings.gi = gi;
        const Scene scene(d);
        const Camera camera(d.cameras.front(), d.settings.width, d.settings.height);
        for (uint32_t f = 1; f <= 2; ++f) {
            RenderSettings single = d.settings;
            single.kernel = KernelType::Single;
            const Image reference = renderFrame(scene, camera, single, f);
            for (int width : {4, 8, 16}) {
                TraceOptions trace;
                trace.packetWidth = width;
                EXPECT_EQ(test::differingBytes(renderFrame(scene, camera, d.settings, f, nullptr, trace), reference), 0u)
                    << "packets of " << width << ", frame " << f << (gi ? ", GI" : "");
            }
            RenderSettings eye = d.settings;
            eye.shading = ShadingMode::EyeLight;
            RenderSettings eyeSingle = eye;
            eyeSingle.kernel = KernelType::Single;
            EXPECT_EQ(test::differingBytes(renderFrame(scene, camera, eye, f), renderFrame(scene, camera, eyeSingle, f)), 0u)
                << "eye-light preview";
        }
    }
}

// Moving a plane is O(1): it touches neither a BVH nor an instance (Embree allocates nothing and
// there is nothing to commit), and the moved scene renders exactly as one built with the plane.
TEST(Section, MovingAPlaneRebuildsNothing) {
    SceneDesc d = test::materialZoo(test::scratchDir());
    Scene scene(d);
    const size_t bytes = scene.embreeBytes();
    const SectionPlane moved = plane({0.5f, 0, 0}, {-1, 0, 0});
    scene.setSection(2, moved);
    EXPECT_EQ(scene.embreeBytes(), bytes);
    EXPECT_EQ(scene.desc().sections[2], moved);
    const Camera camera(d.cameras.front(), d.settings.width, d.settings.height);
    d.sections[2] = moved;
    const Scene fresh(d);
    EXPECT_EQ(test::differingBytes(renderFrame(scene, camera, d.settings), renderFrame(fresh, camera, d.settings)), 0u);
    EXPECT_THROW(scene.setSection(kMaxSections, moved), std::out_of_range);
    EXPECT_THROW(scene.setSection(0, plane({0, 0, 0}, {0, 0, 0})), std::invalid_argument);
    EXPECT_THROW(scene.setSection(0, plane({NAN, 0, 0}, {1, 0, 0})), std::invalid_argument);
    EXPECT_EQ(scene.desc().sections[0], SectionPlane{}) << "a refused plane changes nothing";
}

// Picking: what is cut away cannot be picked; a cap picks the part it closes, on the plane.
TEST(Section, PickSeesTheCutAndItsCap) {
    SceneDesc d = sphereScene(Transform::translate(0, 0, 0), 100);
    Scene scene(d);
    const CameraDesc cd = farCamera({0, 0, 10}, {0, 0, 0}, {0, 1, 0}, 3.0);
    const Camera cam(cd, 100, 100);
    auto hit = pick(scene, cam, 50, 50);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->point.z, 1.0f, 1e-3f);
    scene.setSection(0, plane({0, 0, 0.25f}, {0, 0, -1}));
    hit = pick(scene, cam, 50, 50);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->instance, 0u);
    EXPECT_NEAR(hit->point.z, 0.25f, 1e-4f) << "the cap";
    SectionPlane open = plane({0, 0, 0.25f}, {0, 0, -1});
    open.caps = false;
    scene.setSection(0, open);
    hit = pick(scene, cam, 50, 50);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->point.z, -1.0f, 1e-3f) << "without a cap: the inside of the far side";
    scene.setSection(0, plane({0, 0, -2}, {0, 0, -1}));
    EXPECT_FALSE(pick(scene, cam, 50, 50)) << "all of the sphere is cut away";
}

}  // namespace
}  // namespace rtwall
