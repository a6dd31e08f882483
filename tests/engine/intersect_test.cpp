// Intersection and shading normals against an analytic sphere.
#include <rtwall/engine.h>
#include <rtwall/engine_embree.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace rtwall {
namespace {

double linearOf(uint8_t srgb) {
    float v;
    srgb8ToLinear(&srgb, 1, &v);
    return v;
}

// Distance along unit ray (o, d) to a sphere (c, r), or -1.
double analyticHit(const Float3& o, const Float3& d, const Float3& c, double r, double* discriminant = nullptr) {
    const double ox = o.x - c.x, oy = o.y - c.y, oz = o.z - c.z;
    const double b = ox * d.x + oy * d.y + oz * d.z;
    const double cc = ox * ox + oy * oy + oz * oz - r * r;
    const double disc = b * b - cc;
    if (discriminant) *discriminant = disc;
    if (disc < 0) return -1;
    const double t = -b - std::sqrt(disc);
    return t > 0 ? t : -1;
}

SceneDesc sphereScene(const Transform& placement, int rings, int segments) {
    SceneDesc s;
    s.meshes.push_back({"sphere", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(rings, segments))});
    Material white;
    white.color = {1, 1, 1};
    s.materials.push_back(white);
    s.instances.push_back({0, 0, placement});
    return s;
}

TEST(Intersection, TessellatedSphereDistancesMatchAnalytic) {
    const Float3 center{3, -1, 2};
    const double radius = 2.0;
    const Scene scene(sphereScene(Transform::translate(center.x, center.y, center.z) * Transform::scale(radius, radius, radius), 256, 512));
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    std::mt19937 rng(1234);
    std::normal_distribution<float> g;
    int tested = 0;
    for (int i = 0; i < 20000; ++i) {
        const Float3 from = center + normalize(Float3{g(rng), g(rng), g(rng)}) * 10.0f;
        const Float3 to = center + normalize(Float3{g(rng), g(rng), g(rng)}) * 1.5f;
        const Float3 d = normalize(to - from);
        const double t = analyticHit(from, d, center, radius);
        ASSERT_GT(t, 0.0);
        // Stay away from grazing angles, where a chord error of the tessellation turns into a large distance error.
        const Float3 p = from + d * float(t);
        const float cosA = -dot(d, normalize(p - center));
        if (cosA < 0.2f) continue;
        RTCRayHit rh{};
        rh.ray = {from.x, from.y, from.z, 0.0f, d.x, d.y, d.z, 0.0f, INFINITY, 0xFFFFFFFFu, 0, 0};
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(embreeScene(scene), &ctx, &rh);
        ASSERT_NE(rh.hit.geomID, RTC_INVALID_GEOMETRY_ID) << "ray " << i << " missed";
        EXPECT_EQ(rh.hit.instID[0], 0u);
        // Chord error of a 256x512 UV sphere of radius 2 is below 4e-5; divided by cosA >= 0.2.
        EXPECT_NEAR(rh.ray.tfar, t, 2e-4 * radius) << "ray " << i;
        ++tested;
    }
    EXPECT_GT(tested, 15000);
}

TEST(Intersection, LambertImageOfSphereMatchesAnalyticNormals) {
    // A white Lambert sphere under a directional light of irradiance pi has radiance n.l, with
    // n the interpolated shading normal: the image encodes the normals. Compare every pixel,
    // in linear space, with the analytic sphere.
    SceneDesc desc = sphereScene(Transform{}, 128, 256);
    const CameraDesc cam{"c", {0.3f, 0.4f, 4.0f}, {0, 0, 0}, {0, 1, 0}, 40.0f, std::nullopt};
    const Float3 l = normalize(Float3{0.5f, 0.7f, 1.0f});  // towards the light
    desc.lights.push_back({LightType::Directional, {}, -l, {1, 1, 1}, float(M_PI)});
    RenderSettings s;
    s.width = 160;
    s.height = 120;
    s.shadows = false;  // the test is about normals, not the shadow terminator
    s.background = {0, 0, 0};
    const Scene scene(desc);
    const Camera camera(cam, s.width, s.height);
    const Image img = renderFrame(scene, camera, s);
    int compared = 0, bad = 0;
    double worst = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const Float3 d = normalize(camera.direction(x + 0.5f, y + 0.5f));
            double disc;
            const double t = analyticHit(camera.origin(), d, {0, 0, 0}, 1.0, &disc);
            if (std::fabs(disc) < 0.02) continue;  // silhouette: tessellated and analytic outlines differ
            const uint8_t* px = img.pixel(x, y);
            double expect = 0;
            if (t > 0) expect = std::max(0.0f, dot(normalize(camera.origin() + d * float(t)), l));
            ++compared;
            // Tolerance: interpolated normals of a 128x256 sphere are within ~1e-3 of the
            // true normal; add one 8-bit sRGB step at this brightness for quantisation.
            const double got = linearOf(px[0]);
            const double step = px[0] == 255 ? got - linearOf(254) : linearOf(uint8_t(px[0] + 1)) - got;
            const double err = std::fabs(got - expect);
            worst = std::max(worst, err);
            if (err > 3e-3 + step || px[0] != px[1] || px[1] != px[2]) ++bad;
        }
    EXPECT_GT(compared, 15000);
    EXPECT_EQ(bad, 0) << "worst linear error " << worst;
}

TEST(Intersection, EyeLightUsesTheGeometricNormal) {
    // Preview shading is |ng . d| with Embree's geometric normal: facing the camera squarely, a
    // box face is exactly white.
    SceneDesc desc;
    desc.meshes.push_back({"box", "shape:box", std::make_shared<const TriangleMesh>(makeBox())});
    Material white;
    white.color = {1, 1, 1};
    desc.materials.push_back(white);
    desc.instances.push_back({0, 0, Transform{}});
    RenderSettings s;
    s.width = s.height = 8;
    s.shading = ShadingMode::EyeLight;
    const Scene scene(desc);
    const Image img = renderFrame(scene, Camera({"c", {0, 0, 10}, {0, 0, 0}, {0, 1, 0}, 2.0f, std::nullopt}, 8, 8), s);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) EXPECT_GE(img.pixel(x, y)[0], 254) << x << "," << y;
}

TEST(Intersection, NonUniformScaleKeepsNormalsPerpendicular) {
    // An ellipsoid x^2/4 + y^2 + z^2 = 1: its normal at the +x/+y diagonal is known analytically.
    SceneDesc desc = sphereScene(Transform::scale(2, 1, 1), 128, 256);
    const Scene scene(desc);
    const CameraDesc cam{"c", {6, 0, 0}, {0, 0, 0}, {0, 1, 0}, 10.0f, std::nullopt};
    RenderSettings s;
    s.width = s.height = 9;
    s.shading = ShadingMode::EyeLight;
    const Image img = renderFrame(scene, Camera(cam, s.width, s.height), s);
    // Looking straight down -x at the tip (2,0,0): the normal is +x, |n.d| = 1, white.
    EXPECT_GE(img.pixel(4, 4)[0], 253);
}

}  // namespace
}  // namespace rtwall
