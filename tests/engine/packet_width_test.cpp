// Packet widths (issue 15): every width the packet kernel can run (4, 8 and 16, forced through
// TraceOptions::packetWidth, so any CPU runs all three: Embree emulates what it lacks) gives
// the single-ray kernel's bytes on the scenes that hung rtcOccluded16 on AVX-512 CPUs and on
// the material zoo; and 16-wide shadow rays finish from every stack position (the Embree hang
// came and went with the stack's address).
#include "image_compare.h"
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/engine.h>
#include <rtwall/engine_embree.h>

#include <gtest/gtest.h>

#include <alloca.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

namespace rtwall {
namespace {

// The scene of TileProfile.RecordsEveryTileOfARealRender, the first test seen to hang: 5000
// triangles of knots (as Embree quads), one tile of its floor in shadow.
SceneDesc smallKnots() {
    SceneDesc d = builtinScene("knots", 5000);
    test::setImage(d.settings, 96, 64, 32);
    d.settings.threads = 1;
    return d;
}

// Renders frames 1..frames with the single-ray kernel and with packets of every width; all
// must agree bit for bit.
void expectEveryWidthMatchesSingle(const SceneDesc& d, int frames) {
    const Scene scene(d);
    const Camera camera(d.cameras.front(), d.settings.width, d.settings.height);
    for (int f = 1; f <= frames; ++f) {
        RenderSettings single = d.settings;
        single.kernel = KernelType::Single;
        const Image reference = renderFrame(scene, camera, single, uint32_t(f));
        for (int width : {4, 8, 16}) {
            RenderSettings packet = d.settings;
            packet.kernel = KernelType::Packet;
            TraceOptions trace;
            trace.packetWidth = width;
            EXPECT_EQ(test::differingBytes(renderFrame(scene, camera, packet, uint32_t(f), nullptr, trace), reference), 0u)
                << "packets of " << width << ", frame " << f;
            // The single-ray kernel shapes its primary blocks like packets of the width too.
            EXPECT_EQ(test::differingBytes(renderFrame(scene, camera, single, uint32_t(f), nullptr, trace), reference), 0u)
                << "single-ray kernel in blocks of " << width << ", frame " << f;
        }
    }
}

TEST(PacketWidths, KnotsAsQuadsMatchTheSingleRayKernel) { expectEveryWidthMatchesSingle(smallKnots(), 1); }

// The far CAD scene's BVH settings (high quality, compact, robust) and plain triangles.
TEST(PacketWidths, KnotsWithEveryBvhSettingMatchTheSingleRayKernel) {
    SceneDesc d = smallKnots();
    d.bvh.quality = BvhSettings::Quality::High;
    d.bvh.compact = true;
    d.bvh.robust = true;
    d.bvh.primitives = BvhSettings::Primitives::Triangles;
    expectEveryWidthMatchesSingle(d, 1);
}

// Every material, textures, alpha masks (Embree filter functions in packets), a volume, glass,
// an area light: stochastic, so three frames with their own seeds; and with path tracing.
TEST(PacketWidths, MaterialZooMatchesTheSingleRayKernel) {
    SceneDesc d = test::materialZoo(test::scratchDir());
    d.settings.threads = 2;
    expectEveryWidthMatchesSingle(d, 3);
    d.settings.gi = true;
    d.settings.samples = 2;
    expectEveryWidthMatchesSingle(d, 2);
}

TEST(PacketWidths, AWidthOtherThan4_8Or16IsRefused) {
    const SceneDesc d = smallKnots();
    const Scene scene(d);
    TraceOptions trace;
    trace.packetWidth = 12;
    EXPECT_THROW(renderFrame(scene, Camera(d.cameras.front(), d.settings.width, d.settings.height), d.settings, 0, nullptr, trace),
                 TileError);
}

// Debian's Embree 3.13.5 never returned from some rtcOccluded16 calls on AVX-512 CPUs (its
// coherent occlusion kernel reads garbage mask bits: engine/src/kernel.cpp). Whether a call hung
// depended on what ran before it and on the stack's address: with the unmended kernel, the
// render below hung at every one of these stack offsets here. Each offset renders in a child
// process of its own under a watchdog, so a hang fails the test instead of stalling CI.
TEST(PacketWidths, SixteenWideShadowsFinishFromEveryStackOffset) {
    const SceneDesc d = smallKnots();
    const Scene scene(d);
    const Camera camera(d.cameras.front(), d.settings.width, d.settings.height);
    const RenderSettings s = d.settings;
    TraceOptions sixteen;
    sixteen.packetWidth = 16;
    RenderSettings single = d.settings;
    single.kernel = KernelType::Single;
    const Image reference = renderFrame(scene, camera, single, 0);
    // What ran before the frame that hung first: an eye-light pass over the tiles (profileTiles).
    RenderSettings eye = s;
    eye.shading = ShadingMode::EyeLight;
    for (int offset = 0; offset < 4096; offset += 256) {
        std::fflush(nullptr);
        const pid_t child = fork();
        ASSERT_GE(child, 0) << "fork failed";
        if (child == 0) {
            volatile char* pad = static_cast<char*>(alloca(size_t(offset) + 16));
            pad[0] = 0;
            Image scratch = reference;
            for (const TileRect& r : makeTiles(d.settings.width, d.settings.height, d.settings.tileSize))
                renderTile(scene, camera, r, 1, eye, {scratch.pixel(r.x0, r.y0), size_t(scratch.width) * 3}, sixteen);
            const Image img = renderFrame(scene, camera, s, 0, nullptr, sixteen);
            std::_Exit(test::differingBytes(img, reference) == 0 ? 0 : 2);
        }
        int status = 0;
        bool finished = false;
        for (int waited = 0; waited < 30'000 && !finished; waited += 10) {
            finished = waitpid(child, &status, WNOHANG) == child;
            if (!finished) std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        if (!finished) {
            kill(child, SIGKILL);
            waitpid(child, &status, 0);
            FAIL() << "stack offset " << offset << ": the 16-wide render did not finish in 30 s";
        }
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
            << "stack offset " << offset << ": the 16-wide render differs from the single-ray kernel (status " << status << ")";
    }
}

}  // namespace
}  // namespace rtwall
