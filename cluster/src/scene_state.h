// The one mapping between a scene description (SceneDesc, the engine's) and the scene state as
// it travels (SceneSnapshot and the changes of an Update). The master, the clients and
// diffScenes all go through here: what a snapshot holds of a SceneDesc and how it becomes one
// again, what each change writes, which object a change is about (merging) and when two values
// differ for the clients. Each function static_asserts the member count of the structs it maps
// (fields.h), so that a member added to SceneDesc or SceneSnapshot fails the build here until it
// is mapped; the wire fields do the same for every struct they write (protocol_*.cpp), and
// tests/cluster/scene_state_test.cpp sets every member of every struct to a value other than its
// default and checks that SceneDesc -> snapshot -> bytes -> snapshot -> SceneDesc gives it back.
#pragma once

#include "protocol.h"

#include <map>
#include <memory>
#include <optional>
#include <unordered_map>

namespace rtwall::cluster {

using FileBytes = std::shared_ptr<const std::vector<uint8_t>>;

// A mesh as snapshots name it: by the hash of its canonical bytes (encodeMesh).
MeshRef meshRefOf(const MeshDesc& mesh);

// The state of `scene` at sequence number `seq`: its meshes as `meshes` (meshRefOf of each, in
// order) and the texture and volume files its materials name as `assets`. Not carried:
// SceneDesc::sourceFile (the master's own path) and the cameras (each frame carries its views).
SceneSnapshot snapshotOf(const SceneDesc& scene, std::vector<MeshRef> meshes,
                         std::vector<AssetRef> assets, uint32_t seq);

// And back: the scene a snapshot describes, its meshes and files taken from `meshes` and `files`
// by hash; nothing while one of them is missing. It has no camera.
std::optional<SceneDesc> sceneOf(const SceneSnapshot& snapshot,
                                 const std::map<Hash128, std::shared_ptr<const TriangleMesh>>& meshes,
                                 const std::map<Hash128, FileBytes>& files);

// A change applied to the state as plain data, held as a scene description (the master's
// application state) or as a snapshot (the state of the frame being
// rendered; a material change adds the files it names that the snapshot lacks). One
// implementation for both. Throws DecodeError for an object that does not exist, before
// anything changed. (A client applies changes to its engine Scene, which has its own
// differential calls; it dispatches with std::visit, so a new kind of change fails to compile
// there too.)
void applyChange(SceneDesc& scene, const Change& change);
void applyChange(SceneSnapshot& snapshot, const Change& change);

// The object a change writes (its kind and index): two changes with one key overwrite each other.
uint64_t objectOf(const Change& change);

// Consecutive updates merged into one message: the last change to each object (in the place of
// its first), covering the whole range of sequence numbers, and every file the merged changes
// brought (a material change that replaces another keeps its files). O(1) per change.
class MergedUpdate {
public:
    void add(Update&& update);
    bool empty() const { return update_.seq == 0; }
    const Update& update() const { return update_; }
    Update take();

private:
    Update update_;
    std::unordered_map<uint64_t, size_t> index_;  // objectOf -> position in update_.changes
};

// Two values as the clients get them: they differ for the renderer exactly when their wire
// bytes differ (encodeValue). For Material, Light, CameraDesc, InstanceDesc, RenderSettings and
// SectionPlane.
template <class T> bool sameOnWire(const T& a, const T& b) { return encodeValue(a) == encodeValue(b); }

}  // namespace rtwall::cluster
