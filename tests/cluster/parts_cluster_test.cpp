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

}  // namespace
}  // namespace rtwall
