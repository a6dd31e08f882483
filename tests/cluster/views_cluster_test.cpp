// Multi-view frames (issue 18): both eyes of a stereo wall and the planes of a CAVE rendered in
// one scheduler pass (Master::setViews, renderViews) over loopback clients give, view by view,
// the very bytes of a frame of that view's camera alone (as a stereo wall rendered before: one
// frame per eye), with asynchronous rendering off and on; a view with regions renders only the
// tiles that meet them; a stochastic scene's view tiles equal one machine's frame of that number.
#include "local_cluster.h"
#include "test_util.h"
#include "codec.h"

#include <gtest/gtest.h>

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

namespace rtwall {
namespace {

SceneDesc demoScene(int width, int height, int tile) { return test::quickDemo(width, height, tile); }

// The scene's camera moved sideways by `dx` and given an off-axis window: an eye of a wall.
CameraDesc eye(const SceneDesc& d, float dx) {
    CameraDesc c = d.cameras.front();
    c.position.x += dx;
    c.lookAt.x += dx;
    const Float3 f{c.lookAt.x - c.position.x, c.lookAt.y - c.position.y, c.lookAt.z - c.position.z};
    const Float3 centre{c.position.x + f.x, c.position.y + f.y, c.position.z + f.z};
    c.window = ProjectionWindow{{centre.x - 0.6f, centre.y - 0.45f, centre.z}, {1.2f, 0, 0}, {0, 0.9f, 0}};
    return c;
}

// Today's way: one frame per view, the state's camera set to the view's. With async the frame
// in flight comes back first; the one with this camera is the next.
Image separateRender(Master& master, const CameraDesc& camera, bool async = false) {
    master.setCamera(camera);
    if (async) master.renderFrame();
    return master.renderFrame();
}

bool sameInRect(const Image& a, const Image& b, const TileRect& r) {
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x)
            for (int k = 0; k < 3; ++k)
                if (a.pixel(x, y)[k] != b.pixel(x, y)[k]) return false;
    return true;
}

TEST(ViewsCluster, StereoInOnePassEqualsOneFramePerEye) {
    for (bool async : {false, true}) {
        SCOPED_TRACE(async ? "async" : "sync");
        const SceneDesc d = demoScene(96, 64, 16);
        ClusterSettings cs;
        cs.async = async;
        test::LocalCluster cluster(d, cs, 2);
        ASSERT_TRUE(cluster.ready());
        Master& m = *cluster.master;
        // Three head positions, each eye pair in one pass; then the separate renders.
        for (int step = 0; step < 3; ++step) {
            const float head = 0.1f * float(step);
            const std::vector<FrameView> views{{eye(d, head - 0.0325f), {}, 0, 0}, {eye(d, head + 0.0325f), {}, 0, 0}};
            m.setViews(views, uint64_t(100 + step));
            FrameReport r;
            std::vector<Image> images = m.renderViews(&r);
            if (async) {
                // The frame in flight came back (begun before these views: the separate renders'
                // last, without views, tag 0); the one begun with these views is next.
                if (step > 0) {
                    EXPECT_EQ(r.viewsTag, 0u);
                }
                images = m.renderViews(&r);
            }
            ASSERT_EQ(r.viewsTag, uint64_t(100 + step));
            ASSERT_EQ(r.views, 2u);
            ASSERT_EQ(images.size(), 2u);
            EXPECT_EQ(r.tileOwners.size(), 2 * makeTiles(96, 64, 16).size());
            m.setViews({});
            const Image left = separateRender(m, views[0].camera, async), right = separateRender(m, views[1].camera, async);
            EXPECT_EQ(images[0].rgb, left.rgb) << "left eye, head " << head;
            EXPECT_EQ(images[1].rgb, right.rgb) << "right eye, head " << head;
            EXPECT_NE(images[0].rgb, images[1].rgb) << "the eyes must differ, or the test proves nothing";
            // One machine agrees too (the one renderTile).
            const Scene scene(d);
            EXPECT_EQ(images[0].rgb, renderFrame(scene, Camera(views[0].camera, 96, 64), d.settings).rgb);
        }
        EXPECT_EQ(m.counters().dropped(), 0u);
    }
}

TEST(ViewsCluster, CavePlanesRenderOnlyTheirScreensTiles) {
    // Three planes side by side in a 96x32 image (a CAVE's left, front and right walls), each
    // with its own camera; tiles of 16: each plane needs 2 of the 6 tile columns.
    const SceneDesc d = demoScene(96, 32, 16);
    test::LocalCluster cluster(d, test::inStep(), 2);
    ASSERT_TRUE(cluster.ready());
    Master& m = *cluster.master;
    std::vector<FrameView> views;
    for (int plane = 0; plane < 3; ++plane) {
        FrameView v;
        v.camera = eye(d, -0.5f + 0.5f * float(plane));
        v.regions = {{plane * 960, 0, 960, 320}};  // in a 2880x320 reference: the wall's pixels
        v.refWidth = 2880;
        v.refHeight = 320;
        views.push_back(v);
    }
    const std::vector<ViewTile> tiles = viewTiles(views, 96, 32, 16);
    ASSERT_EQ(tiles.size(), 3 * 4u);  // 2 columns x 2 rows per plane, not 12 each
    m.setViews(views);
    FrameReport r;
    const std::vector<Image> images = m.renderViews(&r);
    ASSERT_EQ(images.size(), 3u);
    EXPECT_EQ(r.tileOwners.size(), tiles.size());
    m.setViews({});
    for (int plane = 0; plane < 3; ++plane) {
        const Image alone = separateRender(m, views[size_t(plane)].camera);
        const TileRect screen{plane * 32, 0, plane * 32 + 32, 32};
        EXPECT_TRUE(sameInRect(images[size_t(plane)], alone, screen)) << "plane " << plane;
    }
}

TEST(ViewsCluster, StochasticViewTilesEqualOneMachinesFrameOfThatNumber) {
    SceneDesc d = demoScene(64, 48, 16);
    d.settings.gi = true;

    ASSERT_TRUE(rendersStochastically(d));
    test::LocalCluster cluster(d, test::inStep(), 2);
    ASSERT_TRUE(cluster.ready());
    const std::vector<FrameView> views{{eye(d, -0.0325f), {}, 0, 0}, {eye(d, 0.0325f), {}, 0, 0}};
    cluster.master->setViews(views);
    const Scene scene(d);
    for (int i = 0; i < 2; ++i) {
        FrameReport r;
        std::vector<std::vector<float>> linear;
        const std::vector<Image> images = cluster.master->renderViews(&r, &linear);
        ASSERT_TRUE(r.stochastic);
        ASSERT_TRUE(r.linear);
        ASSERT_EQ(linear.size(), 2u);
        for (size_t v = 0; v < 2; ++v) {
            // Linear half-float tiles: one machine's linear frame of that number, rounded to halves.
            const std::vector<float> local = renderFrameLinear(scene, Camera(views[v].camera, 64, 48), d.settings, r.frame);
            ASSERT_EQ(linear[v].size(), local.size());
            size_t differing = 0;
            for (size_t k = 0; k < local.size(); ++k) differing += cluster::roundToHalf(local[k]) != linear[v][k];
            EXPECT_EQ(differing, 0u) << "view " << v << ", frame " << r.frame;
            EXPECT_EQ(images[v].width, 64);
        }
        EXPECT_NE(linear[0], linear[1]);
    }
}

}  // namespace
}  // namespace rtwall
