// The denoiser's features with every tile (issue 28): with ClusterSettings::features a linear
// frame's features are one machine's through the feature codec, exactly, for 1, 2 and 3 loopback
// clients; frames denoised from a cluster's views are bit-identical to one machine's denoised
// frames (quantiseAsSent) whatever the number of clients; features never come without depth,
// and an 8-bit frame carries none.
#include "local_cluster.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <rtwall/cluster.h>
#include <rtwall/denoise.h>
#include <rtwall/engine.h>
#include <rtwall/frame.h>

#include <cstring>

namespace rtwall {
namespace {

// The demo scene with path tracing: its frames are stochastic, so they travel as linear tiles.
SceneDesc giScene() {
    SceneDesc d = test::quickDemo(96, 64, 16);
    d.settings.gi = true;
    return d;
}

ClusterSettings withFeatures(uint8_t bits = kFeatureAll) {
    ClusterSettings cs = test::inStep();
    cs.depth = true;
    cs.features = bits;
    return cs;
}

template <class T> size_t differing(const std::vector<T>& a, const std::vector<T>& b) {
    if (a.size() != b.size()) return std::max(a.size(), b.size()) + 1;
    size_t n = 0;
    for (size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(T)) != 0;
    return n;
}

TEST(FeaturesCluster, AreOneMachinesThroughTheCode) {
    const SceneDesc d = giScene();
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 96, 64);
    for (uint8_t bits : {uint8_t(kFeatureAll), featureBitsFor(DenoiseSettings::Mode::Temporal)})
        for (int clients : {1, 2, 3}) {
            SCOPED_TRACE(std::to_string(clients) + " clients, feature bits " + std::to_string(int(bits)));
            test::LocalCluster cluster(d, withFeatures(bits), clients);
            ASSERT_TRUE(cluster.ready());
            FrameReport r;
            std::vector<std::vector<float>> linear, depth;
            std::vector<FeatureImages> features;
            cluster.master->renderViews(&r, &linear, &depth, &features);
            ASSERT_TRUE(r.linear);
            EXPECT_EQ(r.features, bits);
            FeatureFrame one = renderFrameFeatures(scene, camera, d.settings, r.frame);
            quantiseAsSent(one, bits);
            ASSERT_EQ(features.size(), 1u);
            EXPECT_EQ(differing(linear.at(0), one.linear), 0u);
            EXPECT_EQ(differing(depth.at(0), one.depth), 0u);
            EXPECT_EQ(differing(features[0].albedo, one.albedo), 0u);
            EXPECT_EQ(differing(features[0].normal, one.normal), 0u);
            EXPECT_EQ(differing(features[0].id, one.id), 0u);
            EXPECT_EQ((bits & kFeatureAlbedo) != 0, !features[0].albedo.empty());
            size_t objects = 0;
            for (uint32_t id : features[0].id) objects += id != 0;
            EXPECT_GT(objects, 100u) << "the frame should show objects";
            EXPECT_EQ(cluster.master->counters().dropped(), 0u);
        }
}

// A camera moving for a few frames, then standing: each frame denoised by the compositor, on
// the cluster's views and on one machine's. Bit for bit, whatever the number of clients.
TEST(FeaturesCluster, DenoisedFramesAreOneMachinesOnAnyNumberOfClients) {
    SceneDesc d = giScene();
    const Scene scene(d);
    DenoiseSettings ds;
    ds.mode = DenoiseSettings::Mode::Svgf;
    ds.levels = 3;
    auto cameraOf = [&](int k) {
        CameraDesc c = d.cameras.front();
        const float dx = 0.05f * float(std::min(k, 3));
        c.position.x += dx;
        c.lookAt.x += dx;
        return c;
    };
    auto compose = [&](Compositor& comp, const CameraDesc& cam, std::vector<std::vector<float>>& linear,
                       std::vector<std::vector<float>>& depth, std::vector<FeatureImages>& features) {
        ComposeFrame f;
        f.stochastic = true;
        f.linear = true;
        f.denoise = ds;
        f.depth = depth;
        f.features = features;
        f.camera = cam;
        f.keepForWarp = false;
        f.stateSeq = 7;
        std::vector<Image> img(1);
        img[0].width = 96;
        img[0].height = 64;
        img[0].rgb.resize(96 * 64 * 3);
        return comp.compose(f, std::move(img), linear).left;
    };
    // One machine's denoised frames 1..6.
    std::vector<Image> want;
    {
        Compositor comp;
        for (int k = 0; k < 6; ++k) {
            const CameraDesc cam = cameraOf(k);
            FeatureFrame f = renderFrameFeatures(scene, Camera(cam, 96, 64), d.settings, uint32_t(k + 1));
            quantiseAsSent(f, kFeatureAll);
            std::vector<std::vector<float>> linear{f.linear}, depth{f.depth};
            std::vector<FeatureImages> features{{f.albedo, f.normal, f.id}};
            want.push_back(compose(comp, cam, linear, depth, features));
        }
        EXPECT_EQ(comp.denoisedFrames(), 6);
    }
    for (int clients : {1, 2, 3}) {
        test::LocalCluster cluster(d, withFeatures(), clients);
        ASSERT_TRUE(cluster.ready()) << clients << " clients";
        Compositor comp;
        for (int k = 0; k < 6; ++k) {
            cluster.master->setCamera(cameraOf(k));
            FrameReport r;
            std::vector<std::vector<float>> linear, depth;
            std::vector<FeatureImages> features;
            cluster.master->renderViews(&r, &linear, &depth, &features);
            ASSERT_EQ(r.frame, uint32_t(k + 1));
            EXPECT_EQ(r.camera, cameraOf(k));
            const Image got = compose(comp, r.camera, linear, depth, features);
            EXPECT_EQ(test::differingBytes(got, want[size_t(k)]), 0u) << clients << " clients, frame " << r.frame;
        }
        EXPECT_EQ(comp.denoisedFrames(), 6);
    }
}

TEST(FeaturesCluster, NeedDepthAndComeOnlyWithLinearFrames) {
    SceneDesc d = giScene();
    ClusterSettings cs = test::inStep();
    cs.features = kFeatureAll;  // without depth
    try {
        Master m(d, cs);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "features for the denoiser need depth with every tile (and bits 1 to 7)");
    }
    // 8-bit tiles (no wide accumulation): the frame carries no features, and the caller's
    // buffers are emptied.
    cs = withFeatures();
    cs.wideAccumulation = false;
    test::LocalCluster cluster(d, cs, 1);
    ASSERT_TRUE(cluster.ready());
    FrameReport r;
    std::vector<FeatureImages> features(2);
    cluster.master->renderViews(&r, nullptr, nullptr, &features);
    EXPECT_FALSE(r.linear);
    EXPECT_EQ(r.features, 0);
    EXPECT_TRUE(features.empty());
}

}  // namespace
}  // namespace rtwall
