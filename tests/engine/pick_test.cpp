// Picking (the display's object selection): the first instance along a pixel's primary ray.
#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <cmath>

namespace rtwall {
namespace {

TEST(Pick, FindsTheInstanceUnderAPixelAndWhereItWasHit) {
    SceneDesc s;
    s.meshes.push_back({"sphere", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(32, 64))});
    s.materials.push_back({});
    s.instances.push_back({0, 0, Transform::translate(-2, 0, 0)});
    s.instances.push_back({0, 0, Transform::translate(2, 0, 0)});
    s.settings.width = 200;
    s.settings.height = 100;
    CameraDesc cd;
    cd.position = {0, 0, 10};
    cd.lookAt = {0, 0, 0};
    Scene scene(s);
    const Camera cam(cd, 200, 100);
    EXPECT_FALSE(pick(scene, cam, 100, 50).has_value()) << "between the spheres";
    EXPECT_FALSE(pick(scene, cam, 100, 2).has_value()) << "above them";
    // The pixel column through x = +2 at the focal plane z = 0.
    float px = 100;
    while (px < 200 && cam.origin().x + cam.direction(px, 50).x * 10.0f / -cam.direction(px, 50).z < 2.0f) px += 0.25f;
    const auto hit = pick(scene, cam, px, 50);
    ASSERT_TRUE(hit.has_value());
    EXPECT_EQ(hit->instance, 1u);
    // The ray from (0, 0, 10) through (2, 0, 0) meets the unit sphere at (2, 0, 0) where
    // 104 (1 - s)^2 = 1: s = 1 - 1/sqrt(104), the point (2s, 0, 10 - 10s).
    const float s1 = 1.0f - 1.0f / std::sqrt(104.0f);
    EXPECT_NEAR(hit->point.z, 10.0f - 10.0f * s1, 0.01f);
    EXPECT_NEAR(hit->point.x, 2.0f * s1, 0.02f);
    const auto left = pick(scene, cam, 200 - px, 50);
    ASSERT_TRUE(left.has_value());
    EXPECT_EQ(left->instance, 0u);
    // After a transform update the pick follows the object.
    scene.setInstanceTransform(1, Transform::translate(2, 10, 0));
    scene.commit();
    EXPECT_FALSE(pick(scene, cam, px, 50).has_value());
}

}  // namespace
}  // namespace rtwall
