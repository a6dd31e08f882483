// Hide, isolate and highlight over the cluster (issue 20): the master sends one visibility
// change per instance that changes (protocol 9), the clients disable or tint those instances,
// and every frame stays bit-identical to one machine's render of the same state, on loopback.
#include "local_cluster.h"
#include "parts_scene.h"
#include "test_util.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <algorithm>

namespace rtwall {
namespace {

using test::LocalCluster;
using test::differingBytes;
using test::singleMachine;

bool complete(const FrameReport& r) {
    return !r.tileOwners.empty() && std::count(r.tileOwners.begin(), r.tileOwners.end(), UINT32_MAX) == 0;
}

TEST(PartsCluster, HideIsolateHighlightBitIdenticalToOneMachine) {
    SceneDesc d = test::partsScene();
    ClusterSettings cs = test::inStep();
    cs.prefetch = 2;
    LocalCluster cluster(d, cs, 2);
    ASSERT_TRUE(cluster.ready());
    FrameReport r;
    Image first = cluster.master->renderFrame(&r);
    ASSERT_TRUE(complete(r));
    ASSERT_EQ(differingBytes(first, singleMachine(d, r.frame)), 0u);

    // Each step: the view's visibilities, sent as the changes from the state before.
    const std::vector<PartView> steps = {
        PartView{{"left"}, {}, {}},           // hide one box (and its shadow)
        PartView{{}, {"asm/right"}, {}},      // isolate the right box and its knob
        PartView{{"knob"}, {"right"}, {"right"}},  // and hide the knob, highlight the box
        PartView{{}, {}, {"asm"}},            // everything back, the assembly highlighted
        PartView{},                           // as loaded
    };
    Image previous = first;
    for (const PartView& view : steps) {
        const std::vector<Visibility> v = visibilityOf(d, view);
        size_t changes = 0;
        for (size_t i = 0; i < v.size(); ++i) {
            if (d.instances[i].visibility == v[i]) continue;
            cluster.master->setInstanceVisibility(uint32_t(i), v[i]);
            d.instances[i].visibility = v[i];
            ++changes;
        }
        ASSERT_GT(changes, 0u);
        const Image frame = cluster.master->renderFrame(&r);
        EXPECT_TRUE(complete(r));
        EXPECT_EQ(differingBytes(frame, singleMachine(d, r.frame)), 0u);
        EXPECT_GT(differingBytes(frame, previous), 0u) << "the change shows";
        previous = frame;
    }
    EXPECT_EQ(differingBytes(previous, first), 0u);
    EXPECT_THROW(cluster.master->setInstanceVisibility(4, Visibility::Hidden), std::exception);
}

// Parts the scene marks movable (issue 29) reach the clients (protocol 20), which keep them in
// their moving top level from the start: each frame of a drag equals one machine's render of
// the same state, marked or not, on 1, 2 and 3 clients. (The boxes are lifted off the floor:
// at coincident faces the two top levels tie, a known debt: see the issue 29 note.)
TEST(PartsCluster, MovablePartsDraggedBitIdenticalToOneMachine) {
    SceneDesc d = test::partsScene();
    for (size_t i = 1; i < d.instances.size(); ++i)
        d.instances[i].transform = Transform::translate(0, 0.05 * double(i), 0) * d.instances[i].transform;
    d.instances[2].movable = true;
    SceneDesc unmarked = d;
    unmarked.instances[2].movable = false;
    for (int clients : {1, 2, 3}) {
        SCOPED_TRACE(std::to_string(clients) + " clients");
        ClusterSettings cs = test::inStep();
        LocalCluster cluster(d, cs, clients);
        ASSERT_TRUE(cluster.ready());
        SceneDesc state = unmarked;
        for (int step = 0; step < 3; ++step) {
            const Transform t = Transform::translate(0.2 * step, 0.1 * step, -0.15 * step) * d.instances[2].transform;
            if (step > 0) cluster.master->setInstanceTransform(2, t);
            state.instances[2].transform = t;
            FrameReport r;
            const Image frame = cluster.master->renderFrame(&r);
            ASSERT_TRUE(complete(r));
            EXPECT_EQ(differingBytes(frame, singleMachine(state, r.frame)), 0u) << "step " << step;
        }
    }
}

}  // namespace
}  // namespace rtwall
