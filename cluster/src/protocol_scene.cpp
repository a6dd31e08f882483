// Scene state on the wire: the snapshot, numbered updates and their changes, the mesh and asset
// exchange, a client's Ready and ResyncRequest; the state hash and a scene value's bytes.
#include "protocol_values.h"

#include <algorithm>

namespace rtwall::cluster {

// -- Changes -------------------------------------------------------------------------------------

RTWALL_WIRE_FIELDS(TransformChange, 2) {
    io.u32(m.instance);
    fields(io, m.transform);
}

RTWALL_WIRE_FIELDS(MaterialChange, 3) {
    static const size_t assetBytes = minEncodedSize(AssetRef{});
    io.u32(m.material);
    fields(io, m.value);
    vectorOf(io, m.files, assetBytes, kMaxFilesPerMaterial);
}

RTWALL_WIRE_FIELDS(LightChange, 2) {
    io.u32(m.light);
    fields(io, m.value);
}

RTWALL_WIRE_FIELDS(SettingsChange, 1) { fields(io, m.settings); }

RTWALL_WIRE_FIELDS(SectionChange, 2) {
    io.u32(m.section);
    io.expect(m.section < uint32_t(kMaxSections), [&] { return "section " + std::to_string(m.section) + " does not exist"; });
    fields(io, m.value);
}

RTWALL_WIRE_FIELDS(VisibilityChange, 2) {
    io.u32(m.instance);
    io.enumUpTo(m.visibility, Visibility::Highlighted, "instance visibility");
}

namespace {

// The reader's side of a change: the alternative its kind names.
template <size_t... I> void readChange(FieldReader& io, Change& c, uint8_t kind, std::index_sequence<I...>) {
    const bool known = ((kind == I ? (c = std::variant_alternative_t<I, Change>{}, fields(io, std::get<I>(c)), true)
                                   : false) ||
                        ...);
    if (!known) fail("unknown change kind " + std::to_string(kind));
}

}  // namespace

// A change is its variant index (u8) and then the alternative.
template <class Io> void fields(Io& io, In<Io, Change> c) {
    uint8_t kind = uint8_t(c.index());
    io.u8(kind);
    if constexpr (Io::decoding) readChange(io, c, kind, std::make_index_sequence<std::variant_size_v<Change>>{});
    else std::visit([&](const auto& alt) { fields(io, alt); }, c);
}

namespace {

size_t minChangeSize() {
    MaterialChange material;
    material.value.name.clear();
    return 1 + std::min({minEncodedSize(TransformChange{}), minEncodedSize(material), minEncodedSize(LightChange{}),
                         minEncodedSize(SettingsChange{}), minEncodedSize(SectionChange{}),
                         minEncodedSize(VisibilityChange{})});
}

}  // namespace

// -- Messages ------------------------------------------------------------------------------------

RTWALL_WIRE_COUNT(BvhSettings, 4);  // written with the snapshot
// Everything that affects the image, i.e. the snapshot without its sequence number; stateHash
// hashes exactly these bytes.
template <class Io> void stateFields(Io& io, In<Io, SceneSnapshot> m) {
    static const size_t meshRefBytes = minEncodedSize(MeshRef{});
    static const size_t materialBytes = minEncodedSize(Material{});
    static const size_t instanceBytes = minEncodedSize(InstanceDesc{});
    static const size_t lightBytes = minEncodedSize(Light{});
    static const size_t assetBytes = minEncodedSize(AssetRef{});
    vectorOf(io, m.meshes, meshRefBytes, kMaxSceneObjects);
    vectorOf(io, m.materials, materialBytes, kMaxSceneObjects);
    vectorOf(io, m.instances, instanceBytes, kMaxSceneObjects);
    vectorOf(io, m.lights, lightBytes, kMaxSceneObjects);
    fields(io, m.settings);
    io.enumInRange(m.bvh.quality, BvhSettings::Quality::High, "BVH quality");
    io.boolean(m.bvh.compact);
    io.boolean(m.bvh.robust);
    io.enumInRange(m.bvh.primitives, BvhSettings::Primitives::Triangles, "BVH primitives");
    for (auto& o : m.origin) io.f64(o);  // finite
    vectorOf(io, m.assets, assetBytes, kMaxSceneObjects);
    for (auto& p : m.sections) fields(io, p);  // version 9
    // The engine indexes meshes and materials with these without further checks.
    for (size_t i = 0; i < m.instances.size(); ++i) {
        const InstanceDesc& in = m.instances[i];
        io.expect(in.mesh < m.meshes.size(), [&] {
            return "instance " + std::to_string(i) + " refers to mesh " + std::to_string(in.mesh) + " of " +
                   std::to_string(m.meshes.size());
        });
        io.expect(in.material < m.materials.size(), [&] {
            return "instance " + std::to_string(i) + " refers to material " + std::to_string(in.material) + " of " +
                   std::to_string(m.materials.size());
        });
    }
}

RTWALL_WIRE_MESSAGE(SceneSnapshot, 10) {
    io.u32(m.updateSeq);
    stateFields(io, m);
}

RTWALL_WIRE_MESSAGE(MeshRequest, 1) { io.hash(m.hash); }

RTWALL_WIRE_MESSAGE(MeshData, 2) {
    io.hash(m.hash);
    io.blob(m.mesh, kMaxMeshBytes);
    // Checked here so that a corrupted mesh can never enter a client's cache under a hash it does not have.
    if constexpr (Io::decoding)
        if (hashBytes(m.mesh.data(), m.mesh.size()) != m.hash) fail("mesh bytes do not match their hash");
}

RTWALL_WIRE_MESSAGE(AssetRequest, 1) { io.hash(m.hash); }

// The file's bytes: the receiver checks the hash, so that it can count and report a mismatch.
RTWALL_WIRE_MESSAGE(AssetData, 2) {
    io.hash(m.hash);
    io.blob(m.bytes, kMaxAssetBytes);
}

RTWALL_WIRE_MESSAGE(Update, 3) {
    static const size_t changeBytes = minChangeSize();
    io.u32(m.seq);
    vectorOf(io, m.changes, changeBytes, kMaxChangesPerUpdate);
    io.u32(m.baseSeq);
}

RTWALL_WIRE_MESSAGE(Ready, 2) {
    io.u32(m.updateSeq);
    io.hash(m.stateHash);
}

RTWALL_WIRE_MESSAGE(ResyncRequest, 1) { io.u32(m.lastSeq); }

// -- Scene state -----------------------------------------------------------------------------------

template <class T> std::vector<uint8_t> encodeValue(const T& value) {
    return measureAndWrite([&](Writer& w) {
        FieldWriter io(w);
        fields(io, value);
    });
}
template std::vector<uint8_t> encodeValue(const Material&);
template std::vector<uint8_t> encodeValue(const Light&);
template std::vector<uint8_t> encodeValue(const CameraDesc&);
template std::vector<uint8_t> encodeValue(const InstanceDesc&);
template std::vector<uint8_t> encodeValue(const RenderSettings&);
template std::vector<uint8_t> encodeValue(const SectionPlane&);

Hash128 stateHash(const SceneSnapshot& snapshot) {
    const std::vector<uint8_t> bytes = measureAndWrite([&](Writer& w) {
        FieldWriter io(w);
        stateFields(io, snapshot);
    });
    return hashBytes(bytes.data(), bytes.size());
}

EncodedSnapshot encodeSnapshot(const Header& header, const SceneSnapshot& snapshot) {
    EncodedSnapshot out;
    out.message = encodeMessage(header, snapshot);
    // The payload is the sequence number (u32) and then stateFields' bytes: hashed in place.
    constexpr size_t kState = kHeaderSize + sizeof(uint32_t);
    out.stateHash = hashBytes(out.message.data() + kState, out.message.size() - kState);
    return out;
}

}  // namespace rtwall::cluster
