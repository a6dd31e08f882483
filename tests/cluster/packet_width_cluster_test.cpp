// A cluster of render clients with different CPUs (issue 15): one traces 16-wide packets as an
// AVX-512 server does, one 8-wide as an AVX2 PC, one 4-wide; the frames they assemble together
// are one machine's bytes, on the scene that hung rtcOccluded16 and on every material with
// progressive frames.
#include "shading_scenes.h"
#include "local_cluster.h"
#include "test_util.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <map>

namespace rtwall {
namespace {

using test::LocalCluster;
using test::differingBytes;
using test::singleMachine;

// Renders `frames` frames on three clients of widths 16, 8 and 4 and compares each with one
// machine (its own CPU's width); every client must have rendered tiles, or the widths were not
// all put to the test.
void expectMixedClusterMatchesOneMachine(const SceneDesc& desc, int frames) {
    ClusterSettings cs = test::inStep();
    cs.prefetch = 2;
    cs.affinity = false;
    cs.wideAccumulation = false;  // 8-bit tiles, compared with one machine's 8-bit frames
    LocalCluster cluster(desc, cs, 3, {}, {16, 8, 4});
    ASSERT_TRUE(cluster.ready());
    const Scene scene(desc);
    std::map<uint32_t, uint64_t> tilesBy;
    for (int f = 0; f < frames; ++f) {
        FrameReport r;
        const Image img = cluster.master->renderFrame(&r);
        EXPECT_EQ(differingBytes(img, singleMachine(scene, desc, r.frame)), 0u) << "frame " << r.frame;
        for (const ClientReport& c : r.clients) tilesBy[c.id] += c.tiles;
    }
    ASSERT_EQ(tilesBy.size(), 3u);
    for (const auto& [id, tiles] : tilesBy) EXPECT_GT(tiles, 0u) << "client " << id << " rendered no tile";
}

TEST(MixedPacketWidths, KnotsFromThreeWidthsAreOneMachinesBytes) {
    SceneDesc d = builtinScene("knots", 5000);
    d.settings.width = 96;
    d.settings.height = 64;
    d.settings.tileSize = 8;
    expectMixedClusterMatchesOneMachine(d, 2);
}

TEST(MixedPacketWidths, EveryMaterialWithGiFromThreeWidthsIsOneMachinesBytes) {
    SceneDesc d = test::materialZoo(test::scratchDir(), 64, 48);
    d.settings.tileSize = 8;
    d.settings.gi = true;
    d.settings.samples = 2;
    expectMixedClusterMatchesOneMachine(d, 3);
}

}  // namespace
}  // namespace rtwall
