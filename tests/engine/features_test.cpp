// The denoiser's features with every tile (issue 28, FeatureView): asking for them leaves the
// colour and depth as they are; they are known values on a known scene; both kernels and every
// packet width give the same features (to Embree's rounding of hit distances, as for depth).
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/engine.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace rtwall {
namespace {

template <class T> bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

float worstDifference(const std::vector<float>& a, const std::vector<float>& b) {
    float worst = a.size() == b.size() ? 0.0f : INFINITY;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i) worst = std::max(worst, std::fabs(a[i] - b[i]));
    return worst;
}

// A red floor (instance 0) under a box (instance 1) of another colour, seen from above at an
// angle, background around; path traced.
SceneDesc floorAndBox() {
    SceneDesc d;
    test::addQuadAndBox(d);
    d.materials.push_back(test::material("floor", MaterialType::Lambert, {0.7f, 0.2f, 0.1f}));
    d.materials.push_back(test::material("box", MaterialType::Lambert, {0.1f, 0.3f, 0.9f}));
    Transform floor;
    floor.m = {1.5, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1.5, 0};
    d.instances.push_back({0, 0, floor});
    Transform box;
    box.m = {0.5f, 0, 0, 0, 0, 0.5f, 0, 0.5f, 0, 0, 0.5f, 0};
    d.instances.push_back({1, 1, box});
    d.lights.push_back(test::sunFromAbove());
    d.cameras.push_back(test::cameraAt({0, 5, 6}, {0, 0, 0}));
    test::setImage(d.settings, 64, 48, 16);
    d.settings.threads = 2;
    d.settings.gi = true;
    return d;
}

TEST(KernelFeatures, LeaveColourAndDepthAsTheyAre) {
    const SceneDesc d = floorAndBox();
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 64, 48);
    const FeatureFrame f = renderFrameFeatures(scene, camera, d.settings, 3);
    EXPECT_TRUE(sameBits(f.linear, renderFrameLinear(scene, camera, d.settings, 3)));
    EXPECT_TRUE(sameBits(f.depth, renderFrameWithDepth(scene, camera, d.settings, 3).depth));
}

TEST(KernelFeatures, AreTheHitsAlbedoNormalAndInstance) {
    const SceneDesc d = floorAndBox();  // one sample a pixel: each pixel's features are one hit's
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 64, 48);
    const FeatureFrame f = renderFrameFeatures(scene, camera, d.settings, 1);
    size_t floor = 0, box = 0, background = 0;
    for (size_t i = 0; i < f.id.size(); ++i) {
        const Float3 a{f.albedo[3 * i], f.albedo[3 * i + 1], f.albedo[3 * i + 2]};
        const Float3 n{f.normal[3 * i], f.normal[3 * i + 1], f.normal[3 * i + 2]};
        EXPECT_EQ(f.id[i] == 0, f.depth[i] == kBackgroundDepth) << i;
        if (f.id[i] == 0) {
            ++background;
            EXPECT_EQ(a, (Float3{1, 1, 1}));
            EXPECT_EQ(n, (Float3{0, 0, 0}));
        } else if (f.id[i] == 1) {
            ++floor;
            EXPECT_NEAR(a.x, 0.7f, 1e-6f);
            EXPECT_NEAR(a.z, 0.1f, 1e-6f);
            EXPECT_NEAR(n.y, 1.0f, 1e-5f);
        } else {
            ASSERT_EQ(f.id[i], 2u);
            ++box;
            EXPECT_NEAR(a.z, 0.9f, 1e-6f);
            EXPECT_GT(dot(n, camera.origin() - Float3{0, 0.5f, 0}), 0.0f) << "a normal faces the camera";
        }
    }
    EXPECT_GT(floor, 200u);
    EXPECT_GT(box, 50u);
    EXPECT_GT(background, 100u);
}

TEST(KernelFeatures, AverageThePixelsSamples) {
    SceneDesc d = floorAndBox();
    d.settings.supersample = 2;  // four samples: a pixel on an edge averages two surfaces
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 64, 48);
    const FeatureFrame f = renderFrameFeatures(scene, camera, d.settings, 1);
    size_t pure = 0, mixed = 0;
    for (size_t i = 0; i < f.id.size(); ++i) {
        const float red = f.albedo[3 * i];
        if (red == 0.7f || red == 0.1f || red == 1.0f) ++pure;
        else if (red > 0.1f && red < 1.0f) ++mixed;
        else ADD_FAILURE() << "pixel " << i << ": albedo " << red << " is no mean of the surfaces'";
    }
    EXPECT_GT(mixed, 20u) << "edge pixels average samples of two surfaces";
    EXPECT_GT(pure, 10 * mixed);
}

TEST(KernelFeatures, EveryWidthAndBothKernelsGiveTheSameFeatures) {
    SceneDesc d = test::materialZoo(test::scratchDir(), 96, 64);
    d.settings.threads = 2;
    d.settings.gi = true;
    d.cameras.front() = test::cameraAt({0, 3, 9}, {0, 0, 0});
    d.sections[0].enabled = true;  // caps have features too
    d.sections[0].point = {0.2f, 0, 0};
    d.sections[0].normal = {1, 0, -0.3f};  // the camera on the side cut away: it looks at the cuts
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 96, 64);
    RenderSettings single = d.settings;
    single.kernel = KernelType::Single;
    const FeatureFrame ref = renderFrameFeatures(scene, camera, single, 2);
    size_t caps = 0;
    for (uint32_t id : ref.id) caps += id == kCapFeatureId;
    EXPECT_GT(caps, 10u) << "the section plane's cap should show";
    for (int width : {4, 8, 16})
        for (KernelType kernel : {KernelType::Packet, KernelType::Single}) {
            RenderSettings s = d.settings;
            s.kernel = kernel;
            TraceOptions trace;
            trace.packetWidth = width;
            const FeatureFrame got = renderFrameFeatures(scene, camera, s, 2, nullptr, trace);
            EXPECT_TRUE(sameBits(got.linear, ref.linear)) << width;
            EXPECT_TRUE(sameBits(got.id, ref.id)) << width;
            if (kernel == KernelType::Single) {
                EXPECT_TRUE(sameBits(got.albedo, ref.albedo)) << width;
                EXPECT_TRUE(sameBits(got.normal, ref.normal)) << width;
            } else {  // a hit distance an ulp apart moves a textured albedo or a bumped normal by as little
                EXPECT_LE(worstDifference(got.albedo, ref.albedo), 1e-4f) << width;
                EXPECT_LE(worstDifference(got.normal, ref.normal), 1e-4f) << width;
            }
        }
}

}  // namespace
}  // namespace rtwall
