// Scene state: the application's changes (Master::set*), and how the state reaches the clients:
// snapshots for joiners, merged updates, meshes and files on request.
#include "master_impl.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace rtwall {

namespace cluster {

// The files a material names: its texture image, alpha-mask image and volume.
std::vector<std::string> filesNamedBy(const Material& m) {
    std::vector<std::string> paths;
    if (m.texture.kind == TextureKind::Image && !m.texture.file.empty()) paths.push_back(m.texture.file);
    if (m.alpha.kind == TextureKind::Image && !m.alpha.file.empty()) paths.push_back(m.alpha.file);
    if (m.type == MaterialType::Volume && !m.volumeFile.empty()) paths.push_back(m.volumeFile);
    return paths;
}

// A file a material names, from `files` (SceneDesc::files) when they hold it, else from disk,
// with its hash. Throws InputError naming the file when it cannot be read or is too large.
Asset readAsset(const std::string& path, const decltype(SceneDesc::files)& files) {
    FileBytes bytes;
    if (auto it = files.find(path); it != files.end() && it->second) {
        bytes = it->second;
    } else {
        std::error_code ec;
        const auto size = std::filesystem::file_size(path, ec);
        if (ec) throw InputError(path + ": cannot read the file a material names (" + ec.message() + ")");
        if (size > kMaxAssetBytes)
            throw InputError(path + ": " + std::to_string(size) + " bytes is more than the cluster sends (" +
                             std::to_string(kMaxAssetBytes) + ")");
        std::ifstream in(path, std::ios::binary);
        auto v = std::make_shared<std::vector<uint8_t>>(size_t(size));
        if (!in.read(reinterpret_cast<char*>(v->data()), std::streamsize(size)))
            throw InputError(path + ": cannot read the file a material names");
        bytes = std::move(v);
    }
    if (bytes->size() > kMaxAssetBytes)
        throw InputError(path + ": more bytes than the cluster sends (" + std::to_string(kMaxAssetBytes) + ")");
    return {AssetRef{path, hashBytes(bytes->data(), bytes->size()), bytes->size()}, bytes};
}

}  // namespace cluster

// A file of the state by the path materials use (under stateMutex once the network runs).
// A path is read once per session: later changes to the file on disk are not seen.
const AssetRef* Master::Impl::findAsset(const std::string& path) const {
    for (const AssetRef& a : app.assetRefs)
        if (a.path == path) return &a;
    return nullptr;
}

void Master::Impl::addAsset(Asset asset) {
    app.assetBytes[asset.first.hash] = std::move(asset.second);
    app.assetRefs.push_back(std::move(asset.first));
}

// A joining or resyncing client gets the state of the frame being rendered (so that it can
// help with it at once) and then the updates sent since, exactly as the others got them.
// What does not fit its queue is sent again, whole, by retryPending. The state is encoded
// and hashed here, once per frame state however many clients need it, not at every update:
// a client proves the state it was sent (Ready), and only that one.
void Master::Impl::sendState(ClientState& c) {
    if (!frameStateMessage) frameStateMessage = encodeSnapshot(header(MsgType::SceneSnapshot), frameState);
    c.needsState = false;
    c.stateSeq = frameState.updateSeq;
    c.stateHash = frameStateMessage->stateHash;
    if (sendBytes(c, MsgType::SceneSnapshot, frameStateMessage->message) != SendResult::Sent) {
        c.needsState = !c.deathReason;
        return;
    }
    c.stateInFlight = true;
    // The history since the snapshot, merged into one message whatever its length.
    if (!sentSince.empty() && send(c, sentSince.update()) != SendResult::Sent) c.needsState = !c.deathReason;
}

void Master::Impl::onMeshRequest(ClientState& c, const uint8_t* data, size_t size) {
    const MeshRequest req = decodePayload<MeshRequest>(data, size);
    size_t i = 0;
    while (i < app.meshRefs.size() && app.meshRefs[i].hash != req.hash) ++i;
    if (i == app.meshRefs.size()) {
        unexpected("a request for a mesh this scene does not have");
        return;
    }
    if (!c.meshesSent.insert(req.hash).second) {
        // Asked before: it has it, or it is replaying requests to fill its queue.
        replayed("a request for a mesh it was sent before");
        return;
    }
    MeshData md{req.hash, encodeMesh(*app.scene.meshes[i].mesh)};
    if (send(c, md) == SendResult::Full) {
        // It asks again when the state comes again.
        c.meshesSent.erase(req.hash);
        c.needsState = true;
    }
}

void Master::Impl::onAssetRequest(ClientState& c, const uint8_t* data, size_t size) {
    const AssetRequest req = decodePayload<AssetRequest>(data, size);
    FileBytes bytes;
    {
        std::lock_guard lock(app.stateMutex);  // Master::setMaterial may add files meanwhile
        if (auto it = app.assetBytes.find(req.hash); it != app.assetBytes.end()) bytes = it->second;
    }
    if (!bytes) {
        unexpected("a request for a file this scene does not have");
        return;
    }
    if (!c.assetsSent.insert(req.hash).second) {
        replayed("a request for a file it was sent before");
        return;
    }
    if (send(c, AssetData{req.hash, *bytes}) == SendResult::Full) {
        c.assetsSent.erase(req.hash);
        c.needsState = true;
    }
}

void Master::Impl::onResyncRequest(ClientState& c, const uint8_t* data, size_t size) {
    decodePayload<ResyncRequest>(data, size);
    if (c.stateInFlight) {
        replayed("a resync request while its state is on its way");  // or the request is a replay
        return;
    }
    ++resyncCount;
    if (c.ready) {
        c.ready = false;
        std::lock_guard lock(m);
        --readyClients;
    }
    // It drops its work when the state arrives: what it was given goes to whoever asks.
    const size_t lost = scheduler.release(c.id);
    add(&MasterCounters::lostHandOuts, lost);
    c.credits = 0;
    c.window = 0;
    sendState(c);
    if (lost > 0) serveAll();
}

// An update that does not fit a client's queue is lost to it like a dropped packet: the
// client sees the gap when a frame needs the update and asks for a resync.
void Master::Impl::sendUpdate(const Update& update) {
    for (auto& [peer, c] : clients) {
        if (c.deathReason) continue;
        const int n = settings.faults ? settings.faults->dropEveryNthUpdate : 0;
        if (n > 0 && ++c.updatesSent % uint64_t(n) == 0) {  // injected loss
            ++injectedLosses;
            continue;
        }
        send(c, update);
    }
    sentSince.add(Update(update));
}

void Master::Impl::flushUpdates() {
    if (unsent.empty()) return;
    sendUpdate(unsent.take());
    lastUpdateSent = nowSeconds();
}

namespace {

// O(1) in the size of the scene: the change is applied to the application's state and queued;
// nothing is copied, serialised or hashed whole.
// `files`: ones the change names that the state does not hold yet; they join it with the change.
void pushUpdate(Master::Impl& s, Change change, std::vector<Asset> files = {}) {
    {
        std::lock_guard lock(s.app.stateMutex);
        applyChange(s.app.scene, change);  // throws for an index out of range, before anything changed
        for (Asset& file : files)
            if (!s.findAsset(file.first.path)) s.addAsset(std::move(file));
        if (!std::holds_alternative<TransformChange>(change))
            s.app.stochasticStale = true;
        ++s.app.seq;
        Command cmd{.kind = Command::kUpdate};
        cmd.update.seq = s.app.seq;
        cmd.update.baseSeq = s.app.seq - 1;
        cmd.update.changes.push_back(std::move(change));
        queueLocked(s, std::move(cmd));
    }
    s.wake();
}

}  // namespace

// The next mono frame's view, not an update: it reaches the clients in that frame's FrameBegin.
void Master::setCamera(const CameraDesc& camera) {
    std::lock_guard lock(impl_->app.stateMutex);
    impl_->app.camera = camera;
    ++impl_->app.cameraMoves;
}
void Master::setInstanceTransform(uint32_t instance, const Transform& t) { pushUpdate(*impl_, TransformChange{instance, t}); }
void Master::setInstanceVisibility(uint32_t instance, Visibility v) { pushUpdate(*impl_, VisibilityChange{instance, v}); }
void Master::setMaterial(uint32_t material, const Material& value) {
    // The change names its files by hash. One the scene did not load is read now (an unreadable
    // file throws here, before anything changed) and travels like the snapshot's: each client
    // fetches it by hash unless it has the same bytes already.
    Impl& s = *impl_;
    MaterialChange change{material, value, {}};
    std::vector<Asset> fresh;
    for (const std::string& path : filesNamedBy(value)) {
        std::optional<AssetRef> known;
        {
            std::lock_guard lock(s.app.stateMutex);
            if (const AssetRef* a = s.findAsset(path)) known = *a;
        }
        if (known) {
            change.files.push_back(*known);
        } else {
            auto asset = readAsset(path, s.app.scene.files);
            change.files.push_back(asset.first);
            fresh.push_back(std::move(asset));
        }
    }
    pushUpdate(s, std::move(change), std::move(fresh));
}
void Master::setLight(uint32_t light, const Light& value) { pushUpdate(*impl_, LightChange{light, value}); }
void Master::setRenderSettings(const RenderSettings& settings) { pushUpdate(*impl_, SettingsChange{settings}); }
void Master::setSection(uint32_t section, const SectionPlane& plane) {
    // What the clients' decoders would refuse is refused here, before anything changed.
    const Float3 &p = plane.point, &n = plane.normal, &c = plane.capColor;
    for (float v : {p.x, p.y, p.z, n.x, n.y, n.z})
        if (!std::isfinite(v)) throw std::invalid_argument("section " + std::to_string(section) + " is not finite");
    if (!(n.x * n.x + n.y * n.y + n.z * n.z > 0.0f))
        throw std::invalid_argument("section " + std::to_string(section) + " has a zero normal");
    for (float v : {c.x, c.y, c.z})
        if (!(v >= 0.0f && v <= 1.0f))
            throw std::invalid_argument("section " + std::to_string(section) + ": cap colour outside [0, 1]");
    pushUpdate(*impl_, SectionChange{section, plane});
}

void Master::setCodec(const CodecSettings& codec) {
    Impl& s = *impl_;
    {
        std::lock_guard lock(s.app.stateMutex);
        ++s.app.seq;
        Command cmd{.kind = Command::kCodec, .codec = codec};
        cmd.update.seq = s.app.seq;
        cmd.update.baseSeq = s.app.seq - 1;
        queueLocked(s, std::move(cmd));
    }
    s.wake();
}

void Master::setDenoise(const DenoiseSettings& settings, int ring) {
    if (ring < 0 || ring > 16384) throw InputError("a denoise ring of " + std::to_string(ring) + " pixels");
    Impl& s = *impl_;
    std::lock_guard lock(s.app.stateMutex);
    s.app.denoise = settings;
    s.app.denoiseRing = ring;
}

void Master::setViews(std::vector<FrameView> views, uint64_t tag, std::optional<std::array<Float3, 2>> roomEyes) {
    if (views.size() > kMaxViews) throw InputError("a frame has at most " + std::to_string(kMaxViews) + " views");
    Impl& s = *impl_;
    for (const FrameView& v : views)
        for (const WarpRef& w : v.warps)
            if (w.grid >= s.settings.warpGrids.size() || v.refWidth <= 0 || v.refHeight <= 0)
                throw InputError("a view names warp grid " + std::to_string(w.grid) + " of " +
                                 std::to_string(s.settings.warpGrids.size()) + (v.refWidth <= 0 ? " without a reference size" : ""));
    std::lock_guard lock(s.app.stateMutex);
    s.app.views = std::move(views);
    s.app.viewsTag = tag;
    s.app.roomEyes = roomEyes;
}

}  // namespace rtwall
