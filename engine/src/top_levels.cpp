// Part moves (issue 29): the static top level rebuilt in the background, published by commit()
// (scene_impl.h, "part moves", says how the two top levels work together).
#include "material.h"
#include "scene_impl.h"

#include <rtwall/engine_embree.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <thread>
#include <vector>

namespace rtwall {

RTCGeometry instanceGeometry(RTCDevice device, RTCScene mesh, const float objectToWorld[12], unsigned mask, bool hidden) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, mesh);
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, objectToWorld);
    rtcSetGeometryMask(g, mask);
    if (hidden) rtcDisableGeometry(g);
    rtcCommitGeometry(g);
    return g;
}

namespace {

// A mover that has not changed for this many commits is folded back into the static top level
// by the next rebuild.
constexpr uint64_t kSettleCommits = 8;

}  // namespace

struct TopRebuild {
    struct Entry {
        unsigned id;
        RTCScene mesh;
        float objectToWorld[12];
        unsigned mask;
        bool hidden;
    };
    std::vector<Entry> entries;     // what the new top level holds, as it was at the start
    std::vector<uint8_t> included;  // per instance
    uint64_t generation = 0, stamp = 0;
    RTCScene scene = nullptr;
    std::atomic<bool> done{false};
    std::thread thread;

    ~TopRebuild() {
        if (thread.joinable()) thread.join();
        if (scene) rtcReleaseScene(scene);
    }
};

Scene::Impl::Impl() = default;
Scene::Impl::~Impl() = default;

namespace {

// Starts a rebuild of the static top level on a thread of its own: every instance but those
// moving now (movers settled for kSettleCommits commits are folded back in; the scene's movable
// ones never are), as they are now.
void launchRebuild(Scene::Impl& s) {
    auto r = std::make_unique<TopRebuild>();
    r->generation = s.topGeneration;
    r->stamp = s.changeStamp;
    r->included.assign(s.instances.size(), 0);
    r->entries.reserve(s.instances.size());
    for (size_t i = 0; i < s.instances.size(); ++i) {
        // Movers stay out until settled; movable ones (InstanceDesc::movable) for good.
        if (s.inMoving[i] && (s.desc.instances[i].movable || s.commits - s.movedCommit[i] < kSettleCommits)) continue;
        const InstanceData& d = s.instances[i];
        TopRebuild::Entry e{unsigned(i), s.meshScenes[s.desc.instances[i].mesh], {}, instanceMask(s, d), d.hidden};
        std::copy(d.objectToWorld, d.objectToWorld + 12, e.objectToWorld);
        r->entries.push_back(e);
        r->included[i] = 1;
    }
    TopRebuild* job = r.get();
    RTCDevice device = s.device;
    const RTCSceneFlags flags = sceneFlags(s.desc.bvh);
    job->thread = std::thread([job, device, flags] {
        RTCScene top = rtcNewScene(device);
        rtcSetSceneFlags(top, flags);
        for (const TopRebuild::Entry& e : job->entries) {
            RTCGeometry g = instanceGeometry(device, e.mesh, e.objectToWorld, e.mask, e.hidden);
            rtcAttachGeometryByID(top, g, e.id);
            rtcReleaseGeometry(g);
        }
        rtcCommitScene(top);
        job->scene = top;
        job->done.store(true, std::memory_order_release);
    });
    s.rebuild = std::move(r);
}

// Publishes a finished rebuild: it becomes `top` unless `top` changed meanwhile (then it is
// dropped, and the next commit starts another). Movers it holds that have not changed since it
// started leave `moving`.
void publishRebuild(Scene::Impl& s) {
    std::unique_ptr<TopRebuild> r = std::move(s.rebuild);
    if (r->thread.joinable()) r->thread.join();
    if (r->generation != s.topGeneration || !r->scene) return;
    rtcReleaseScene(s.top);
    s.top = r->scene;
    r->scene = nullptr;
    s.staleCount = 0;
    for (size_t i = 0; i < s.instances.size(); ++i) {
        s.inTop[i] = r->included[i];
        s.staleInTop[i] = r->included[i] && s.movedStamp[i] > r->stamp;
        s.staleCount += s.staleInTop[i];
        if (s.inMoving[i] && r->included[i] && !s.staleInTop[i]) {
            rtcDetachGeometry(s.moving, unsigned(i));
            s.inMoving[i] = 0;
            --s.movingCount;
            s.movingDirty = true;
        }
    }
}

}  // namespace

void joinRebuild(Scene::Impl& s) {
    if (s.rebuild && s.rebuild->thread.joinable()) s.rebuild->thread.join();
}

void dropRebuild(Scene::Impl& s) { s.rebuild.reset(); }

void Scene::commit() {
    Impl& s = *impl_;
    ++s.commits;
    if (s.rebuild && s.rebuild->done.load(std::memory_order_acquire)) publishRebuild(s);
    if (s.dirty) {
        rtcCommitScene(s.top);
        s.dirty = false;
        checkDevice(s.device, s.lastError, "rebuilding the top-level BVH");
    }
    if (s.movingDirty) {
        rtcCommitScene(s.moving);
        s.movingDirty = false;
        checkDevice(s.device, s.lastError, "building the BVH of the moving instances");
    }
    if (!s.rebuild && s.staleCount > 0) launchRebuild(s);
}

void Scene::waitForRebuild() {
    Impl& s = *impl_;
    if (!s.rebuild) return;
    publishRebuild(s);
    if (s.movingDirty) {
        rtcCommitScene(s.moving);
        s.movingDirty = false;
    }
    checkDevice(s.device, s.lastError, "rebuilding the top-level BVH");
}

Scene::TopLevelState Scene::topLevelState() const {
    const Impl& s = *impl_;
    return {s.movingCount, s.staleCount, s.rebuild != nullptr};
}

}  // namespace rtwall
