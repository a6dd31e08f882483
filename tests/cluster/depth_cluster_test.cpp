// Depth with every tile (issue 27): with ClusterSettings::depth the cluster's depth of a frame is
// one machine's (renderFrameWithDepth) through the 16-bit depth code, exactly, for 1, 2 and 3
// loopback clients, mono and a two-view frame (outside a view's regions: NaN); its images are
// unchanged; a depth payload that does not decode is dropped and its tile rendered again.
#include "local_cluster.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <rtwall/cluster.h>
#include <rtwall/cluster_testing.h>
#include <rtwall/depth_codec.h>
#include <rtwall/engine.h>

#include <cmath>
#include <cstring>

namespace rtwall {
namespace {

// What the cluster must give for one machine's depth: each value through the wire's code.
std::vector<float> throughCode(const std::vector<float>& depth) {
    std::vector<float> out(depth.size());
    for (size_t i = 0; i < depth.size(); ++i) out[i] = decodeDepth(encodeDepth(depth[i]));
    return out;
}

// Pixels whose bits differ (NaN equals NaN of the same bits: decodeDepth's hole).
size_t differingDepths(const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size()) return std::max(a.size(), b.size());
    size_t n = 0;
    for (size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(float)) != 0;
    return n;
}

// The demo scene's small quick frame: surfaces and background in view.
SceneDesc depthScene() { return test::quickDemo(96, 64, 16); }

// In step (a frame's report is that frame's), with depth.
ClusterSettings withDepth() {
    ClusterSettings cs = test::inStep();
    cs.depth = true;
    return cs;
}

TEST(DepthCluster, MonoDepthIsOneMachinesThroughTheCode) {
    const SceneDesc d = depthScene();
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 96, 64);
    for (int clients : {1, 2, 3}) {
        SCOPED_TRACE(std::to_string(clients) + " clients");
        test::LocalCluster cluster(d, withDepth(), clients);
        ASSERT_TRUE(cluster.ready());
        for (int f = 0; f < 2; ++f) {
            FrameReport r;
            std::vector<float> depth;
            const Image img = cluster.master->renderFrame(&r, nullptr, &depth);
            EXPECT_TRUE(r.depth);
            const RenderedFrame one = renderFrameWithDepth(scene, camera, d.settings, r.frame);
            EXPECT_EQ(img.rgb, one.image.rgb) << "depth must not change the image";
            ASSERT_EQ(depth.size(), size_t(96 * 64));
            EXPECT_EQ(differingDepths(depth, throughCode(one.depth)), 0u);
            // Both kinds of pixel are there, or the test proves little.
            const size_t background = size_t(std::count(depth.begin(), depth.end(), kBackgroundDepth));
            EXPECT_GT(background, 0u);
            EXPECT_LT(background, depth.size());
        }
        EXPECT_EQ(cluster.master->counters().dropped(), 0u);
    }
}

TEST(DepthCluster, TwoViewsEachGetTheirDepthAndHolesOutsideTheirRegions) {
    const SceneDesc d = depthScene();
    const Scene scene(d);
    // The left view the whole image; the right one only its right half's screen (a CAVE plane).
    std::vector<FrameView> views(2);
    views[0].camera = d.cameras.front();
    views[1].camera = d.cameras.front();
    views[1].camera.position.x += 0.3f;
    views[1].camera.lookAt.x += 0.3f;
    views[1].regions = {{480, 0, 480, 640}};
    views[1].refWidth = 960;
    views[1].refHeight = 640;
    for (int clients : {1, 2, 3}) {
        test::LocalCluster cluster(d, withDepth(), clients);
        ASSERT_TRUE(cluster.ready()) << clients << " clients";
        cluster.master->setViews(views);
        FrameReport r;
        std::vector<std::vector<float>> depth;
        const std::vector<Image> images = cluster.master->renderViews(&r, nullptr, &depth);
        ASSERT_EQ(images.size(), 2u);
        ASSERT_EQ(depth.size(), 2u);
        for (size_t v = 0; v < 2; ++v) {
            const RenderedFrame one = renderFrameWithDepth(scene, Camera(views[v].camera, 96, 64), d.settings, r.frame);
            std::vector<float> want = throughCode(one.depth);
            if (v == 1)  // left of its region no tile is rendered: holes
                for (int y = 0; y < 64; ++y)
                    for (int x = 0; x < 48; ++x) want[size_t(y) * 96 + size_t(x)] = std::numeric_limits<float>::quiet_NaN();
            ASSERT_EQ(depth[v].size(), want.size());
            size_t differing = 0;
            for (size_t i = 0; i < want.size(); ++i)
                differing += std::isnan(want[i]) ? !std::isnan(depth[v][i]) : depth[v][i] != want[i];
            EXPECT_EQ(differing, 0u) << "view " << v << ", " << clients << " clients";
        }
        EXPECT_NE(depth[0], depth[1]) << "the views must differ, or the test proves little";
    }
}

TEST(DepthCluster, WithoutDepthTheBufferIsEmptied) {
    const SceneDesc d = depthScene();
    test::LocalCluster cluster(d, test::inStep(), 1);
    ASSERT_TRUE(cluster.ready());
    std::vector<float> depth(5, 1.0f);
    FrameReport r;
    const Image img = cluster.master->renderFrame(&r, nullptr, &depth);
    EXPECT_FALSE(r.depth);
    EXPECT_TRUE(depth.empty());
    EXPECT_EQ(test::differingBytes(img, test::singleMachine(d, r.frame)), 0u);
}

TEST(DepthCluster, ADepthThatDoesNotDecodeIsDroppedAndItsTileRenderedAgain) {
    const SceneDesc d = depthScene();
    const Scene scene(d);
    test::LocalCluster cluster(d, withDepth(), 0);
    ClientSettings bad;
    auto faults = std::make_shared<ClientFaults>();
    faults->corruptEveryNthDepth = 3;  // a third of its tiles' depth arrives cut in half
    bad.faults = faults;
    cluster.add(bad);
    cluster.add();
    ASSERT_TRUE(cluster.ready());
    for (int f = 0; f < 3; ++f) {
        FrameReport r;
        std::vector<float> depth;
        const Image img = cluster.master->renderFrame(&r, nullptr, &depth);
        const RenderedFrame one = renderFrameWithDepth(scene, Camera(d.cameras.front(), 96, 64), d.settings, r.frame);
        EXPECT_EQ(img.rgb, one.image.rgb);
        EXPECT_EQ(differingDepths(depth, throughCode(one.depth)), 0u);
    }
    const MasterCounters c = cluster.master->counters();
    EXPECT_GT(c.undecodableTiles, 0u);
    EXPECT_EQ(c.malformed, 0u);
}

}  // namespace
}  // namespace rtwall
