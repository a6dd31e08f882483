// `rtwall bench updates --moving K [--movable]` (issue 29) behaves before its figures mean
// anything: every field the docs name is there; dragging unmarked parts rebuilds the static
// level in the background once, marked (movable) parts never do. No timing is asserted.
#include <bench.h>

#include <gtest/gtest.h>

namespace rtwall::bench {
namespace {

TEST(UpdatesBench, MovesPrintTheirFieldsAndMarkedPartsNeedNoStaticRebuild) {
    for (const bool movable : {false, true}) {
        SCOPED_TRACE(movable ? "movable" : "unmarked");
        UpdatesOptions o;
        o.text = nullptr;
        o.instances = 3000;
        o.moving = 7;
        o.frames = 6;
        o.movable = movable;
        const toml::table t = updates(o);
        EXPECT_EQ(t["instances"].value_or(0), 3000);
        EXPECT_EQ(t["moving"].value_or(0), 7);
        EXPECT_EQ(t["movable"].value_or(!movable), movable);
        for (const char* f : {"commit_ms", "bare_embree_top_rebuild_ms", "frame_ms_still", "frame_ms_moving"}) {
            EXPECT_GT(t[f]["median"].value_or(-1.0), 0.0) << f;
            EXPECT_GE(t[f]["p95"].value_or(-1.0), t[f]["median"].value_or(0.0)) << f;
        }
        if (movable) EXPECT_EQ(t["static_rebuild_ms"].value_or(-1.0), 0.0) << "marked parts never make the static level stale";
        else EXPECT_GT(t["static_rebuild_ms"].value_or(0.0), 0.0) << "the first move rebuilds the static level without the movers";
    }
}

}  // namespace
}  // namespace rtwall::bench
