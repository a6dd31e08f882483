// A render client's scene cache: meshes and files by content hash (from memory, this PC or the
// master), the master's snapshots and updates, and the scene build on its own thread.
#include "client_runtime.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace rtwall::cluster {

namespace {

// A content hash as file names in the cache show it.
std::string hexOf(const Hash128& h) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", (unsigned long long)h[1], (unsigned long long)h[0]);
    return buf;
}

}  // namespace

std::shared_ptr<const TriangleMesh> ClientRuntime::localMesh(const MeshRef& ref) {
    if (auto it = meshes_.find(ref.hash); it != meshes_.end()) return it->second;
    std::vector<std::filesystem::path> candidates;
    if (!ref.source.empty() && !ref.source.starts_with("shape:")) candidates.push_back(ref.source);
    if (!settings_.cacheDir.empty()) candidates.push_back(settings_.cacheDir / (hexOf(ref.hash) + ".rtmesh"));
    for (const auto& path : candidates) {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(path, ec)) continue;
        try {
            std::vector<uint8_t> bytes;
            if (path.extension() == ".rtmesh") {
                std::ifstream in(path, std::ios::binary);
                bytes.assign(std::istreambuf_iterator<char>(in), {});
            } else {
                bytes = encodeMesh(loadMesh(path));
            }
            if (hashBytes(bytes.data(), bytes.size()) != ref.hash) continue;  // a different file: not trusted
            auto mesh = std::make_shared<const TriangleMesh>(decodeMesh(bytes.data(), bytes.size()));
            meshes_[ref.hash] = mesh;
            return mesh;
        } catch (const std::exception&) {
            continue;  // unreadable or stale: fetch it from the master instead
        }
    }
    return nullptr;
}

// A texture or volume file by content hash: from memory, the material's path on this PC or
// the cache, each used only when its bytes have the hash (another file of the same name is
// not trusted).
std::shared_ptr<const std::vector<uint8_t>> ClientRuntime::localAsset(const AssetRef& ref) {
    if (auto it = assets_.find(ref.hash); it != assets_.end()) return it->second;
    std::vector<std::filesystem::path> candidates{ref.path};
    if (!settings_.cacheDir.empty()) candidates.push_back(settings_.cacheDir / (hexOf(ref.hash) + ".rtasset"));
    for (const auto& path : candidates) {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(path, ec)) continue;
        const auto size = std::filesystem::file_size(path, ec);
        if (ec || size != ref.bytes) continue;  // also bounds what is read (ref.bytes <= kMaxAssetBytes)
        auto bytes = std::make_shared<std::vector<uint8_t>>(size_t(size));
        std::ifstream in(path, std::ios::binary);
        if (!in.read(reinterpret_cast<char*>(bytes->data()), std::streamsize(size))) continue;
        if (hashBytes(bytes->data(), bytes->size()) != ref.hash) continue;
        assets_[ref.hash] = bytes;
        if (settings_.counters) ++settings_.counters->assetsLocal;
        return bytes;
    }
    return nullptr;
}

// Files that an update's material change names: fetched as soon as the update arrives (it
// comes before the frame that needs it), unless this PC has the same bytes.
void ClientRuntime::fetchFilesOf(const Update& u) {
    for (const Change& c : u.changes)
        if (auto* m = std::get_if<MaterialChange>(&c))
            for (const AssetRef& ref : m->files) {
                if (assets_.count(ref.hash) || updateFiles_.count(ref.hash)) continue;
                updateFiles_[ref.hash] = ref;
                if (!localAsset(ref)) send(AssetRequest{ref.hash});
            }
}

// A new connection or session: files still on their way may never come (what arrived stays,
// by hash).
void ClientRuntime::forgetPendingFiles() {
    std::erase_if(updateFiles_, [&](const auto& e) { return !assets_.count(e.first); });
    deferredFrame_.reset();
    blockedFrame_.reset();
}

bool ClientRuntime::updateFilesMissing() const {
    for (const auto& [hash, ref] : updateFiles_)
        if (!assets_.count(hash)) return true;
    return false;
}

void ClientRuntime::onAssetData(AssetData ad) {
    const AssetRef* ref = nullptr;
    if (snapshot_)
        for (const AssetRef& a : snapshot_->assets)
            if (a.hash == ad.hash) ref = &a;
    if (auto it = updateFiles_.find(ad.hash); !ref && it != updateFiles_.end()) ref = &it->second;
    if (!ref || assets_.count(ad.hash)) {
        drop();  // not asked for by this state, or already here
        return;
    }
    if (ad.bytes.size() != ref->bytes || hashBytes(ad.bytes.data(), ad.bytes.size()) != ad.hash) {
        ++dropped_;
        if (settings_.counters) ++settings_.counters->rejectedAssets;
        std::fprintf(stderr, "rtwall client %u: %s: %zu bytes from the master do not match the file's hash %s: rejected\n",
                     id_, ref->path.c_str(), ad.bytes.size(), hexOf(ad.hash).c_str());
        return;
    }
    auto bytes = std::make_shared<const std::vector<uint8_t>>(std::move(ad.bytes));
    assets_[ad.hash] = bytes;
    if (settings_.counters) ++settings_.counters->assetsReceived;
    if (!settings_.cacheDir.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(settings_.cacheDir, ec);
        const auto path = settings_.cacheDir / (hexOf(ad.hash) + ".rtasset");
        const auto tmp = path.string() + ".tmp";
        std::ofstream(tmp, std::ios::binary).write(reinterpret_cast<const char*>(bytes->data()), std::streamsize(bytes->size()));
        std::filesystem::rename(tmp, path, ec);
    }
    tryBuildScene();
    if (deferredFrame_ && !updateFilesMissing()) {  // the frame that waited for this file
        const FrameBegin fb = *deferredFrame_;
        deferredFrame_.reset();
        onFrameBegin(fb);
    }
}

void ClientRuntime::onSnapshot(SceneSnapshot snap) {
    // Within a session the master's states to one client never go back in time (it sends
    // the current frame's state): one older than what this client holds is a replay.
    if (snapshot_ && snap.updateSeq < stateSeq_) {
        drop();
        return;
    }
    dropWork();
    ready_ = false;
    ++buildGeneration_;
    snapshot_ = std::move(snap);
    updates_.reset(snapshot_->updateSeq);
    for (const MeshRef& ref : snapshot_->meshes)
        if (!localMesh(ref)) send(MeshRequest{ref.hash});
    for (const AssetRef& ref : snapshot_->assets)
        if (!localAsset(ref)) send(AssetRequest{ref.hash});
    tryBuildScene();
}

void ClientRuntime::onMeshData(MeshData md) {
    if (hashBytes(md.mesh.data(), md.mesh.size()) != md.hash) {
        drop();
        return;
    }
    meshes_[md.hash] = std::make_shared<const TriangleMesh>(decodeMesh(md.mesh.data(), md.mesh.size()));
    if (!settings_.cacheDir.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(settings_.cacheDir, ec);
        const auto path = settings_.cacheDir / (hexOf(md.hash) + ".rtmesh");
        const auto tmp = path.string() + ".tmp";
        std::ofstream(tmp, std::ios::binary).write(reinterpret_cast<const char*>(md.mesh.data()), std::streamsize(md.mesh.size()));
        std::filesystem::rename(tmp, path, ec);
    }
    tryBuildScene();
}

// Builds the scene (Embree's BVH: seconds for millions of triangles on a slow PC) on its own
// thread, so that this thread keeps reading and sending heartbeats: a joining client that
// went silent for longer than the master's timeout would be dropped and, rejoining, build
// again, never getting in.
void ClientRuntime::tryBuildScene() {
    if (!snapshot_ || ready_ || building_.valid() || built_) return;  // a stale build is redone when it ends
    std::optional<SceneDesc> desc = sceneOf(*snapshot_, meshes_, assets_);
    if (!desc) return;  // still waiting for a mesh, texture or volume
    building_ = std::async(std::launch::async, [desc = std::move(*desc), delay = faults_.extraSceneBuildMs] {
        if (delay > 0) std::this_thread::sleep_for(std::chrono::milliseconds(delay));
        return std::make_unique<Scene>(desc);
    });
    buildingFor_ = buildGeneration_;
}

// Installs a finished build if it is still for the current snapshot, and proves the state.
// The scene is swapped only while no render thread is inside the old one; one that is stuck
// there must not block this thread, so the built scene waits and the swap is tried again.
void ClientRuntime::finishBuild() {
    if (!built_) {
        if (!building_.valid() || building_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
        try {
            built_ = building_.get();
        } catch (const std::exception& e) {
            std::lock_guard lock(workMutex_);
            failure_ = std::string("cannot use the master's scene: ") + e.what();
            return;
        }
    }
    if (buildingFor_ != buildGeneration_ || !snapshot_) {  // another snapshot came meanwhile
        built_.reset();
        tryBuildScene();
        return;
    }
    std::unique_lock lock(sceneMutex_, std::chrono::milliseconds(20));
    if (!lock.owns_lock()) return;
    const Hash128 hash = stateHash(*snapshot_);
    scene_ = std::move(built_);
    setRenderSettings(snapshot_->settings);
    stateSeq_ = snapshot_->updateSeq;
    lock.unlock();
    ready_ = true;
    send(Ready{stateSeq_, hash});
}

// The master's settings plus what is this client's own (under sceneMutex_).
void ClientRuntime::setRenderSettings(const RenderSettings& fromMaster) {
    renderSettings_ = fromMaster;
    renderSettings_.threads = 1;  // each render thread renders its own tiles
    trace_.clientId = id_;  // the id the master gave us, for the client false-colour view
    trace_.packetWidth = settings_.packetWidth;  // this PC's CPU decides
    trace_.fault = faults_.tileFault ? injectFault(*faults_.tileFault) : nullptr;
}

void ClientRuntime::requestResync() {
    ready_ = false;
    send(ResyncRequest{stateSeq_});
}

ClientRuntime::CatchUp ClientRuntime::catchUp(uint32_t seq) {
    if (seq == updates_.state()) return CatchUp::Done;
    if (seq < updates_.state()) return CatchUp::CannotRender;
    std::unique_lock lock(sceneMutex_, std::chrono::milliseconds(20));
    if (!lock.owns_lock()) return CatchUp::Busy;
    std::vector<Update> ups;
    if (updates_.catchUp(seq, ups) != UpdateSequencer::CatchUp::Ready) {
        lock.unlock();
        requestResync();
        return CatchUp::CannotRender;
    }
    for (const Update& u : ups)
        for (const Change& c : u.changes) std::visit([this](const auto& change) { apply(change); }, c);
    scene_->commit();
    stateSeq_ = seq;
    return CatchUp::Done;
}

}  // namespace rtwall::cluster
