// Issue 17: a camera update costs the master O(1), not O(instances). Measured without clocks:
// this program replaces operator new and counts the bytes allocated, on the calling thread during
// Master::setCamera (serialising or hashing the scene state allocates its bytes) and in the whole
// process during each frame (a copy of the scene state, anywhere: master, network thread or
// client). A scene of 20,000 instances must cost what a scene of 10 costs; a copy of the
// instances alone would add 20,000 x 104 bytes (2 MB) a frame.
#include "local_cluster.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>

namespace {

std::atomic<uint64_t> allocatedBytes{0};  // whole process
thread_local uint64_t threadAllocatedBytes = 0;

}  // namespace

void* operator new(std::size_t n) {
    allocatedBytes.fetch_add(n, std::memory_order_relaxed);
    threadAllocatedBytes += n;
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
// GCC sees free() meet a new-expression's pointer once these are inlined; they are the pair.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace rtwall {
namespace {

SceneDesc boxes(int count) {
    SceneDesc d;
    d.meshes.push_back({"box", "shape:box", std::make_shared<const TriangleMesh>(makeBox())});
    d.materials.push_back(Material{});
    const int side = int(std::ceil(std::sqrt(double(count))));
    for (int i = 0; i < count; ++i)
        d.instances.push_back({0, 0, Transform::translate(3.0 * (i % side), 0, 3.0 * (i / side))});
    d.lights.push_back(Light{});
    CameraDesc c;
    c.position = {0, 20, 40};
    d.cameras.push_back(c);
    d.settings.width = 16;
    d.settings.height = 16;
    d.settings.tileSize = 16;
    d.settings.shading = ShadingMode::EyeLight;
    return d;
}

struct Cost {
    double updateBytes = 0;  // allocated by the calling thread in setCamera, per call
    double frameBytes = 0;   // allocated by the whole process per setCamera + renderFrame
};

// `update(master, f)` is the f-th update of the run.
template <class Update> Cost updateCost(int instances, Update&& update) {
    const SceneDesc desc = boxes(instances);
    test::LocalCluster cluster(desc, test::inStep(), 1);
    Master& master = *cluster.master;
    EXPECT_TRUE(master.waitForClients(1, 60'000));
    for (int i = 0; i < 3; ++i) master.renderFrame();
    constexpr int kFrames = 20;
    Cost cost;
    for (int f = 0; f < kFrames; ++f) {
        const uint64_t process0 = allocatedBytes.load();
        const uint64_t thread0 = threadAllocatedBytes;
        update(master, f);
        cost.updateBytes += double(threadAllocatedBytes - thread0);
        master.renderFrame();
        cost.frameBytes += double(allocatedBytes.load() - process0);
    }
    cost.updateBytes /= kFrames;
    cost.frameBytes /= kFrames;
    return cost;
}

Cost cameraUpdateCost(int instances) {
    CameraDesc camera = boxes(1).cameras.front();
    return updateCost(instances, [&](Master& master, int) {
        camera.position.x += 0.25f;
        master.setCamera(camera);
    });
}

// The cost of `what` updates (costOf(instances)) with 10 and with 20,000 instances, printed. The
// same messages and objects either way; what may differ is noise of other threads (heartbeats,
// ZeroMQ's own allocations), which is far below one copy of the instances. `updateCopies` and
// `frameCopies` say what a failure of the update's and of the frame's bound means.
template <class CostOf>
void expectTheSameCostWhateverTheInstanceCount(const char* what, CostOf&& costOf, const char* updateCopies,
                                               const char* frameCopies) {
    const Cost few = costOf(10);
    const Cost many = costOf(20'000);
    std::printf("bytes allocated per %s update: %.0f with 10 instances, %.0f with 20,000; per update and frame: "
                "%.0f and %.0f\n", what, few.updateBytes, many.updateBytes, few.frameBytes, many.frameBytes);
    EXPECT_LT(many.updateBytes, few.updateBytes + 1024) << updateCopies;
    EXPECT_LT(many.frameBytes, few.frameBytes + 256 * 1024) << frameCopies;
}

TEST(Issue17, ACameraUpdateCostsTheSameWhateverTheInstanceCount) {
    expectTheSameCostWhateverTheInstanceCount("camera", cameraUpdateCost, "setCamera serialises or copies the scene state",
                                              "a frame copies the scene state");
}

// Issue 20: moving a section plane costs the master and the clients the same whatever the
// scene's size: the master sends one change, a client sets six floats and a cap material; no BVH
// (a top level of 20,000 instances is megabytes) is rebuilt, nothing of the scene is copied.
Cost sectionUpdateCost(int instances) {
    SectionPlane plane;
    plane.enabled = true;
    plane.normal = {1, 0, 0};
    return updateCost(instances, [&](Master& master, int f) {
        plane.point.x = 3.0f * float(f);  // sweeps across the boxes
        master.setSection(0, plane);
    });
}

TEST(Issue20, ASectionPlaneUpdateCostsTheSameWhateverTheInstanceCount) {
    expectTheSameCostWhateverTheInstanceCount("section", sectionUpdateCost, "setSection serialises or copies the scene state",
                                              "a plane update copies the scene or rebuilds a BVH");
}

}  // namespace
}  // namespace rtwall
