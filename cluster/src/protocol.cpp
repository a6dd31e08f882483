#include "protocol.h"

#include "codec.h"
#include "fields.h"

#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace rtwall::cluster {

namespace {

// Ranges the engine relies on; the same bounds the scene-file loader enforces.
constexpr int kMaxImageSide = 16384;
constexpr int kMaxTileSize = 1024;
constexpr int kMaxDepth = 64;
constexpr int kMaxSupersample = 16;
constexpr int kMaxThreads = 1024;
constexpr int kMaxViewReference = 1 << 20;  // a view region's reference image (the wall's pixels)

[[noreturn]] void fail(const std::string& what) { throw DecodeError(what); }

// Next to every writer: the struct has exactly the members this writer and its reader handle.
// A member added to one of these structs fails the build here until it is written and read
// (and set to a non-default value in the round-trip tests, which check that they set them all).
#define RTWALL_WIRE_FIELDS(T, n)                                                                     \
    static_assert(fieldCount<T>() == (n), #T " has a member that its wire writer does not handle: " \
                                              "write and read it here and update this count")

// -- Field helpers -----------------------------------------------------------------------------

int readInt(Reader& r, int lo, int hi, const char* what) {
    const int32_t v = r.i32();
    if (v < lo || v > hi)
        fail(std::string(what) + " " + std::to_string(v) + " is out of range [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "]");
    return v;
}

template <class E> void writeEnum(Writer& w, E v) { w.u8(uint8_t(v)); }

template <class E> E readEnum(Reader& r, E last, const char* what) {
    const uint8_t v = r.u8();
    if (v > uint8_t(last)) fail(std::string("unknown ") + what + " " + std::to_string(v));
    return E(v);
}

RTWALL_WIRE_FIELDS(Float3, 3);
void write(Writer& w, const Float3& v) {
    w.f32(v.x);
    w.f32(v.y);
    w.f32(v.z);
}

Float3 readFloat3(Reader& r) {
    Float3 v;
    v.x = r.f32();
    v.y = r.f32();
    v.z = r.f32();
    return v;
}

Color readUnitColor(Reader& r, const char* what) {
    // A surface cannot reflect more than it receives; the shading code assumes it.
    const Color c = readFloat3(r);
    for (float v : {c.x, c.y, c.z})
        if (!(v >= 0.0f && v <= 1.0f))
            fail(std::string(what) + " component " + std::to_string(v) + " is outside [0, 1]");
    return c;
}

void write(Writer& w, const Hash128& h) {
    w.u64(h[0]);
    w.u64(h[1]);
}

Hash128 readHash(Reader& r) {
    Hash128 h;
    h[0] = r.u64();
    h[1] = r.u64();
    return h;
}

// -- Scene values --------------------------------------------------------------------------------

RTWALL_WIRE_FIELDS(CodecSettings, 4);
void write(Writer& w, const CodecSettings& c) {
    writeEnum(w, c.codec);
    w.i32(c.jpegQuality);
    w.boolean(c.jpegSubsample);
    w.i32(c.zstdLevel);
}

void read(Reader& r, CodecSettings& c) {
    c.codec = readEnum(r, TileCodec::Jpeg, "tile codec");
    c.jpegQuality = readInt(r, 1, 100, "JPEG quality");
    c.jpegSubsample = r.boolean();
    c.zstdLevel = readInt(r, 1, 19, "zstd level");
}

RTWALL_WIRE_FIELDS(Transform, 1);
void write(Writer& w, const Transform& t) {
    for (double v : t.m) w.f64(v);
}

void read(Reader& r, Transform& t) {
    for (double& v : t.m) v = r.f64();
}

RTWALL_WIRE_FIELDS(TextureDesc, 5);
void write(Writer& w, const TextureDesc& t) {
    writeEnum(w, t.kind);
    w.string(t.file);
    write(w, t.color2);
    w.f32(t.scale);
    writeEnum(w, t.mapping);
}

void read(Reader& r, TextureDesc& t) {
    t.kind = readEnum(r, TextureKind::Image, "texture kind");
    // Clients open texture files themselves (a shared file system), like mesh sources.
    t.file = r.string(kMaxStringBytes);
    t.color2 = readUnitColor(r, "texture color2");
    t.scale = r.f32();
    if (!(t.scale > 0.0f && std::isfinite(t.scale))) fail("texture scale " + std::to_string(t.scale) + " is not positive");
    t.mapping = readEnum(r, TextureMapping::Auto, "texture mapping");
}

Color readNonNegativeColor(Reader& r, const char* what) {
    const Color c = readFloat3(r);
    for (float v : {c.x, c.y, c.z})
        if (!(v >= 0.0f && std::isfinite(v))) fail(std::string(what) + " component " + std::to_string(v) + " is negative");
    return c;
}

float readFloatIn(Reader& r, float lo, float hi, const char* what) {
    const float v = r.f32();
    if (!(v >= lo && v <= hi)) fail(std::string(what) + " " + std::to_string(v) + " is out of range");
    return v;
}

RTWALL_WIRE_FIELDS(Material, 19);
RTWALL_WIRE_FIELDS(TransferPoint, 3);  // written with the material
void write(Writer& w, const Material& m) {
    w.string(m.name);
    writeEnum(w, m.type);
    write(w, m.color);
    write(w, m.specular);
    w.f32(m.shininess);
    w.f32(m.ior);
    w.f32(m.roughness);
    write(w, m.absorption);
    write(w, m.emission);
    write(w, m.texture);
    w.f32(m.bump);
    w.f32(m.bumpScale);
    writeEnum(w, m.bumpMapping);  // version 5
    write(w, m.alpha);
    w.f32(m.alphaCutoff);
    w.string(m.volumeFile);
    w.u32(uint32_t(m.transfer.size()));
    for (const TransferPoint& p : m.transfer) {
        w.f32(p.value);
        write(w, p.color);
        w.f32(p.density);
    }
    w.f32(m.volumeStep);
    w.boolean(m.twoSided);  // version 6
}

void read(Reader& r, Material& m) {
    m.name = r.string(kMaxStringBytes);
    m.type = readEnum(r, MaterialType::Volume, "material type");
    m.color = readUnitColor(r, "material color");
    m.specular = readUnitColor(r, "material specular");
    m.shininess = r.f32();
    // A negative exponent makes pow() blow up at grazing angles.
    if (m.shininess < 0.0f) fail("material shininess " + std::to_string(m.shininess) + " is negative");
    m.ior = r.f32();
    if (!(m.ior >= 1.0f && m.ior <= 4.0f)) fail("material ior " + std::to_string(m.ior) + " is outside [1, 4]");
    m.roughness = readFloatIn(r, 0.0f, 1.0f, "material roughness");
    m.absorption = readNonNegativeColor(r, "material absorption");
    m.emission = readNonNegativeColor(r, "material emission");
    read(r, m.texture);
    m.bump = readFloatIn(r, 0.0f, 100.0f, "material bump");
    m.bumpScale = readFloatIn(r, 1e-6f, 1e6f, "material bump scale");
    m.bumpMapping = readEnum(r, TextureMapping::Object, "bump mapping");
    if (m.bumpMapping != TextureMapping::Auto && m.bumpMapping != TextureMapping::Uv && m.bumpMapping != TextureMapping::Object)
        fail("bump mapping must be auto, uv or object");
    read(r, m.alpha);
    m.alphaCutoff = readFloatIn(r, 0.0f, 1.0f, "material alpha cutoff");
    m.volumeFile = r.string(kMaxStringBytes);
    const uint32_t points = r.u32();
    if (points > 4096) fail("transfer function of " + std::to_string(points) + " points exceeds the limit");
    m.transfer.clear();
    for (uint32_t i = 0; i < points; ++i) {
        TransferPoint p;
        p.value = r.f32();
        if (!std::isfinite(p.value)) fail("transfer function value is not finite");
        p.color = readNonNegativeColor(r, "transfer function colour");
        p.density = readFloatIn(r, 0.0f, 3.4e38f, "transfer function density");
        m.transfer.push_back(p);
    }
    m.volumeStep = readFloatIn(r, 0.01f, 100.0f, "volume step");
    m.twoSided = r.boolean();
    // A volume material without a file cannot be built; refuse it here rather than in the engine.
    if (m.type == MaterialType::Volume && m.volumeFile.empty()) fail("volume material without a volume file");
    if (m.texture.kind == TextureKind::Image && m.texture.file.empty()) fail("image texture without a file");
    if (m.alpha.kind == TextureKind::Image && m.alpha.file.empty()) fail("image alpha mask without a file");
}

RTWALL_WIRE_FIELDS(Light, 8);
void write(Writer& w, const Light& l) {
    writeEnum(w, l.type);
    write(w, l.position);
    write(w, l.direction);
    write(w, l.edge1);
    write(w, l.edge2);
    write(w, l.color);
    w.f32(l.intensity);
    w.boolean(l.twoSided);  // version 6
}

void read(Reader& r, Light& l) {
    l.type = readEnum(r, LightType::Area, "light type");
    l.position = readFloat3(r);
    l.direction = readFloat3(r);
    l.edge1 = readFloat3(r);
    l.edge2 = readFloat3(r);
    l.color = readFloat3(r);
    l.intensity = r.f32();
    if (l.intensity < 0.0f) fail("light intensity " + std::to_string(l.intensity) + " is negative");
    l.twoSided = r.boolean();
}

RTWALL_WIRE_FIELDS(SectionPlane, 5);
void write(Writer& w, const SectionPlane& p) {
    w.boolean(p.enabled);
    write(w, p.point);
    write(w, p.normal);
    write(w, p.capColor);
    w.boolean(p.caps);
}

void read(Reader& r, SectionPlane& p) {
    p.enabled = r.boolean();
    p.point = readFloat3(r);
    p.normal = readFloat3(r);
    for (const Float3& v : {p.point, p.normal})
        if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z))) fail("section plane is not finite");
    if (!(p.normal.x * p.normal.x + p.normal.y * p.normal.y + p.normal.z * p.normal.z > 0.0f))
        fail("section plane normal is zero");
    p.capColor = readUnitColor(r, "section cap colour");
    p.caps = r.boolean();
}

RTWALL_WIRE_FIELDS(CameraDesc, 6);
RTWALL_WIRE_FIELDS(ProjectionWindow, 3);  // written with the camera
void write(Writer& w, const CameraDesc& c) {
    w.string(c.name);
    write(w, c.position);
    write(w, c.lookAt);
    write(w, c.up);
    w.f32(c.fovY);
    w.boolean(c.window.has_value());
    if (c.window) {
        write(w, c.window->lowerLeft);
        write(w, c.window->right);
        write(w, c.window->up);
    }
}

void read(Reader& r, CameraDesc& c) {
    c.name = r.string(kMaxStringBytes);
    c.position = readFloat3(r);
    c.lookAt = readFloat3(r);
    c.up = readFloat3(r);
    c.fovY = r.f32();
    if (!(c.fovY > 0.0f && c.fovY < 180.0f)) fail("camera fov " + std::to_string(c.fovY) + " is outside (0, 180)");
    c.window.reset();
    if (r.boolean()) {
        ProjectionWindow w;
        w.lowerLeft = readFloat3(r);
        w.right = readFloat3(r);
        w.up = readFloat3(r);
        for (const Float3& v : {w.lowerLeft, w.right, w.up})
            if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z))) fail("camera window is not finite");
        c.window = w;
    }
}

RTWALL_WIRE_FIELDS(InstanceDesc, 5);
void write(Writer& w, const InstanceDesc& in) {
    w.u32(in.mesh);
    w.u32(in.material);
    write(w, in.transform);
    w.i32(in.part);
    writeEnum(w, in.visibility);
}

void read(Reader& r, InstanceDesc& in) {
    in.mesh = r.u32();
    in.material = r.u32();
    read(r, in.transform);
    // The part's index only: the names stay with the master (SceneDesc::parts does not travel),
    // so a client can say which part a failed tile shows to the master, which can name it.
    in.part = r.i32();
    if (in.part < -1) fail("instance part " + std::to_string(in.part) + " is out of range");
    in.visibility = readEnum(r, Visibility::Highlighted, "instance visibility");
}

RTWALL_WIRE_FIELDS(RenderSettings, 15);  // what is each process's own is TraceOptions, not sent
void write(Writer& w, const RenderSettings& s) {
    w.i32(s.width);
    w.i32(s.height);
    w.i32(s.tileSize);
    writeEnum(w, s.kernel);
    writeEnum(w, s.shading);
    w.i32(s.maxDepth);
    w.i32(s.supersample);
    w.boolean(s.shadows);
    write(w, s.background);
    write(w, s.ambient);
    w.i32(s.threads);
    w.f32(s.pruneThreshold);
    w.boolean(s.gi);
    w.i32(s.samples);
    writeEnum(w, s.view);
}

void read(Reader& r, RenderSettings& s) {
    s.width = readInt(r, 1, kMaxImageSide, "image width");
    s.height = readInt(r, 1, kMaxImageSide, "image height");
    s.tileSize = readInt(r, 1, kMaxTileSize, "tile size");
    s.kernel = readEnum(r, KernelType::Single, "kernel type");
    s.shading = readEnum(r, ShadingMode::EyeLight, "shading mode");
    s.maxDepth = readInt(r, 1, kMaxDepth, "max depth");
    s.supersample = readInt(r, 1, kMaxSupersample, "supersample");
    s.shadows = r.boolean();
    s.background = readFloat3(r);
    s.ambient = readFloat3(r);
    s.threads = readInt(r, 0, kMaxThreads, "thread count");
    s.pruneThreshold = readFloatIn(r, 0.0f, 1.0f, "prune threshold");
    s.gi = r.boolean();
    s.samples = readInt(r, 1, 4096, "samples");
    s.view = readEnum(r, ViewMode::Client, "view mode");
}

RTWALL_WIRE_FIELDS(MeshRef, 4);
void write(Writer& w, const MeshRef& m) {
    w.string(m.name);
    w.string(m.source);
    write(w, m.hash);
    w.u64(m.bytes);
}

void read(Reader& r, MeshRef& m) {
    m.name = r.string(kMaxStringBytes);
    m.source = r.string(kMaxStringBytes);
    m.hash = readHash(r);
    m.bytes = r.u64();
    if (m.bytes > kMaxMeshBytes) fail("mesh size " + std::to_string(m.bytes) + " exceeds the limit");
}

RTWALL_WIRE_FIELDS(AssetRef, 3);
void write(Writer& w, const AssetRef& m) {
    w.string(m.path);
    write(w, m.hash);
    w.u64(m.bytes);
}

void read(Reader& r, AssetRef& m) {
    m.path = r.string(kMaxStringBytes);
    if (m.path.empty()) fail("asset with an empty path");
    m.hash = readHash(r);
    m.bytes = r.u64();
    if (m.bytes > kMaxAssetBytes) fail("asset size " + std::to_string(m.bytes) + " exceeds the limit");
}

// Defined with the changes below; declared here for the vector helpers, which unqualified
// lookup at their definition must find (these overloads are invisible to ADL).
void write(Writer& w, const Change& c);
void read(Reader& r, Change& c);
// The same for the node list's entries (display nodes, further down).
void write(Writer& w, const NodeEndpoint& m);
void read(Reader& r, NodeEndpoint& m);

// The smallest encoding of a value (empty strings), measured with the writer itself so that
// the element-count checks below cannot drift from the format.
// Written and read with the messages (FrameBegin), declared here for writeVector and readVector.
void write(Writer& w, const ViewRegion& g);
void read(Reader& r, ViewRegion& g);
void write(Writer& w, const FrameView& v);
void read(Reader& r, FrameView& v);

template <class T> size_t minEncodedSize(const T& emptyValue) {
    Writer w;
    write(w, emptyValue);
    return w.size();
}

template <class T> void writeVector(Writer& w, const std::vector<T>& v) {
    if (v.size() > std::numeric_limits<uint32_t>::max())
        throw std::length_error("protocol: vector of " + std::to_string(v.size()) + " elements");
    w.u32(uint32_t(v.size()));
    for (const T& e : v) write(w, e);
}

template <class T> void readVector(Reader& r, std::vector<T>& v, size_t minElementSize, uint64_t maxCount) {
    const uint32_t n = r.u32();
    r.expectElements(n, minElementSize, maxCount);
    v.resize(n);
    for (T& e : v) read(r, e);
}

// -- Changes -------------------------------------------------------------------------------------

RTWALL_WIRE_FIELDS(TransformChange, 2);
void write(Writer& w, const TransformChange& c) {
    w.u32(c.instance);
    write(w, c.transform);
}
void read(Reader& r, TransformChange& c) {
    c.instance = r.u32();
    read(r, c.transform);
}

RTWALL_WIRE_FIELDS(MaterialChange, 3);
void write(Writer& w, const MaterialChange& c) {
    w.u32(c.material);
    write(w, c.value);
    writeVector(w, c.files);
}
void read(Reader& r, MaterialChange& c) {
    c.material = r.u32();
    read(r, c.value);
    static const size_t assetBytes = minEncodedSize(AssetRef{});
    readVector(r, c.files, assetBytes, kMaxFilesPerMaterial);
}

RTWALL_WIRE_FIELDS(LightChange, 2);
void write(Writer& w, const LightChange& c) {
    w.u32(c.light);
    write(w, c.value);
}
void read(Reader& r, LightChange& c) {
    c.light = r.u32();
    read(r, c.value);
}

RTWALL_WIRE_FIELDS(SettingsChange, 1);
void write(Writer& w, const SettingsChange& c) { write(w, c.settings); }
void read(Reader& r, SettingsChange& c) { read(r, c.settings); }

RTWALL_WIRE_FIELDS(SectionChange, 2);
void write(Writer& w, const SectionChange& c) {
    w.u32(c.section);
    write(w, c.value);
}
void read(Reader& r, SectionChange& c) {
    c.section = r.u32();
    if (c.section >= uint32_t(kMaxSections)) fail("section " + std::to_string(c.section) + " does not exist");
    read(r, c.value);
}

RTWALL_WIRE_FIELDS(VisibilityChange, 2);
void write(Writer& w, const VisibilityChange& c) {
    w.u32(c.instance);
    writeEnum(w, c.visibility);
}
void read(Reader& r, VisibilityChange& c) {
    c.instance = r.u32();
    c.visibility = readEnum(r, Visibility::Highlighted, "instance visibility");
}

// A change is its variant index (u8) and then the alternative.
void write(Writer& w, const Change& c) {
    w.u8(uint8_t(c.index()));
    std::visit([&](const auto& alt) { write(w, alt); }, c);
}

template <size_t I> void readAlternative(Reader& r, Change& c) {
    std::variant_alternative_t<I, Change> alt;
    read(r, alt);
    c = std::move(alt);
}

void read(Reader& r, Change& c) {
    const uint8_t kind = r.u8();
    static_assert(std::variant_size_v<Change> == 6, "a new change kind needs a case here");
    switch (kind) {
        case 0: readAlternative<0>(r, c); break;
        case 1: readAlternative<1>(r, c); break;
        case 2: readAlternative<2>(r, c); break;
        case 3: readAlternative<3>(r, c); break;
        case 4: readAlternative<4>(r, c); break;
        case 5: readAlternative<5>(r, c); break;
        default: fail("unknown change kind " + std::to_string(kind));
    }
}

size_t minChangeSize() {
    MaterialChange material;
    material.value.name.clear();
    return 1 + std::min({minEncodedSize(TransformChange{}), minEncodedSize(material),
                         minEncodedSize(LightChange{}), minEncodedSize(SettingsChange{}),
                         minEncodedSize(SectionChange{}), minEncodedSize(VisibilityChange{})});
}

// -- Messages ------------------------------------------------------------------------------------

RTWALL_WIRE_FIELDS(Hello, 3);
void write(Writer& w, const Hello& m) {
    w.u16(m.protocolVersion);
    w.u32(m.threads);
    w.string(m.host);
}
void read(Reader& r, Hello& m) {
    m.protocolVersion = r.u16();  // returned as read, so that the master can name both versions
    m.threads = r.u32();
    if (m.threads > uint32_t(kMaxThreads)) fail("thread count " + std::to_string(m.threads) + " exceeds the limit");
    m.host = r.string(kMaxStringBytes);
}

RTWALL_WIRE_FIELDS(Welcome, 5);
void write(Writer& w, const Welcome& m) {
    w.u32(m.clientId);
    write(w, m.codec);
    w.u32(m.prefetch);
    w.u32(m.heartbeatMs);
    w.u32(m.timeoutMs);
}
void read(Reader& r, Welcome& m) {
    m.clientId = r.u32();
    read(r, m.codec);
    m.prefetch = r.u32();
    // A client never needs more tiles in flight than one assignment can carry.
    if (m.prefetch > kMaxTilesPerMessage) fail("prefetch " + std::to_string(m.prefetch) + " exceeds the limit");
    m.heartbeatMs = r.u32();
    m.timeoutMs = r.u32();
    // The client turns these into socket options (ints) and timers: keep them sane.
    if (m.heartbeatMs > kMaxTimeoutMs || m.timeoutMs > kMaxTimeoutMs)
        fail("heartbeat " + std::to_string(m.heartbeatMs) + " ms or timeout " + std::to_string(m.timeoutMs) +
             " ms exceeds the limit");
}

RTWALL_WIRE_FIELDS(SceneSnapshot, 10);
RTWALL_WIRE_FIELDS(BvhSettings, 4);  // written with the snapshot
// Everything that affects the image, i.e. the snapshot without its sequence number; stateHash
// hashes exactly these bytes.
void writeState(Writer& w, const SceneSnapshot& m) {
    writeVector(w, m.meshes);
    writeVector(w, m.materials);
    writeVector(w, m.instances);
    writeVector(w, m.lights);
    write(w, m.settings);
    w.u8(uint8_t(m.bvh.quality));
    w.boolean(m.bvh.compact);
    w.boolean(m.bvh.robust);
    w.u8(uint8_t(m.bvh.primitives));
    for (double o : m.origin) w.f64(o);
    writeVector(w, m.assets);
    for (const SectionPlane& p : m.sections) write(w, p);  // version 9
}

void write(Writer& w, const SceneSnapshot& m) {
    w.u32(m.updateSeq);
    writeState(w, m);
}
void read(Reader& r, SceneSnapshot& m) {
    static const size_t meshRefBytes = minEncodedSize(MeshRef{});
    static const size_t materialBytes = minEncodedSize(Material{});
    static const size_t instanceBytes = minEncodedSize(InstanceDesc{});
    static const size_t lightBytes = minEncodedSize(Light{});
    m.updateSeq = r.u32();
    readVector(r, m.meshes, meshRefBytes, kMaxSceneObjects);
    readVector(r, m.materials, materialBytes, kMaxSceneObjects);
    readVector(r, m.instances, instanceBytes, kMaxSceneObjects);
    readVector(r, m.lights, lightBytes, kMaxSceneObjects);
    read(r, m.settings);
    const uint8_t quality = r.u8();
    if (quality > uint8_t(BvhSettings::Quality::High)) fail("BVH quality " + std::to_string(quality) + " is out of range");
    m.bvh.quality = BvhSettings::Quality(quality);
    m.bvh.compact = r.boolean();
    m.bvh.robust = r.boolean();
    const uint8_t primitives = r.u8();
    if (primitives > uint8_t(BvhSettings::Primitives::Triangles))
        fail("BVH primitives " + std::to_string(primitives) + " is out of range");
    m.bvh.primitives = BvhSettings::Primitives(primitives);
    for (double& o : m.origin) o = r.f64();  // f64 rejects NaN and infinity
    static const size_t assetBytes = minEncodedSize(AssetRef{});
    readVector(r, m.assets, assetBytes, kMaxSceneObjects);
    for (SectionPlane& p : m.sections) read(r, p);
    // The engine indexes meshes and materials with these without further checks.
    for (size_t i = 0; i < m.instances.size(); ++i) {
        const InstanceDesc& in = m.instances[i];
        if (in.mesh >= m.meshes.size())
            fail("instance " + std::to_string(i) + " refers to mesh " + std::to_string(in.mesh) + " of " +
                 std::to_string(m.meshes.size()));
        if (in.material >= m.materials.size())
            fail("instance " + std::to_string(i) + " refers to material " + std::to_string(in.material) + " of " +
                 std::to_string(m.materials.size()));
    }
}

RTWALL_WIRE_FIELDS(MeshRequest, 1);
void write(Writer& w, const MeshRequest& m) { write(w, m.hash); }
void read(Reader& r, MeshRequest& m) { m.hash = readHash(r); }

RTWALL_WIRE_FIELDS(MeshData, 2);
void write(Writer& w, const MeshData& m) {
    write(w, m.hash);
    w.blob(m.mesh.data(), m.mesh.size());
}
void read(Reader& r, MeshData& m) {
    m.hash = readHash(r);
    const auto [p, n] = r.blobView(kMaxMeshBytes);
    // Checked here so that a corrupted mesh can never enter a client's cache under a hash it does not have.
    if (hashBytes(p, n) != m.hash) fail("mesh bytes do not match their hash");
    m.mesh.assign(p, p + n);
}

RTWALL_WIRE_FIELDS(AssetRequest, 1);
void write(Writer& w, const AssetRequest& m) { write(w, m.hash); }
void read(Reader& r, AssetRequest& m) { m.hash = readHash(r); }

RTWALL_WIRE_FIELDS(AssetData, 2);
void write(Writer& w, const AssetData& m) {
    write(w, m.hash);
    w.blob(m.bytes.data(), m.bytes.size());
}
void read(Reader& r, AssetData& m) {
    m.hash = readHash(r);
    const auto [p, n] = r.blobView(kMaxAssetBytes);
    m.bytes.assign(p, p + n);
}

RTWALL_WIRE_FIELDS(Update, 3);
void write(Writer& w, const Update& m) {
    w.u32(m.seq);
    writeVector(w, m.changes);
    w.u32(m.baseSeq);
}
void read(Reader& r, Update& m) {
    static const size_t changeBytes = minChangeSize();
    m.seq = r.u32();
    readVector(r, m.changes, changeBytes, kMaxChangesPerUpdate);
    m.baseSeq = r.u32();
}

RTWALL_WIRE_FIELDS(ViewRegion, 4);
void write(Writer& w, const ViewRegion& g) {
    w.i32(g.x);
    w.i32(g.y);
    w.i32(g.width);
    w.i32(g.height);
}
void read(Reader& r, ViewRegion& g) {
    // The bounds of the view's reference image are checked with the view.
    g.x = readInt(r, 0, kMaxViewReference, "view region x");
    g.y = readInt(r, 0, kMaxViewReference, "view region y");
    g.width = readInt(r, 0, kMaxViewReference, "view region width");
    g.height = readInt(r, 0, kMaxViewReference, "view region height");
}

RTWALL_WIRE_FIELDS(FrameView, 4);
void write(Writer& w, const FrameView& v) {
    write(w, v.camera);
    writeVector(w, v.regions);
    w.i32(v.refWidth);
    w.i32(v.refHeight);
}
void read(Reader& r, FrameView& v) {
    read(r, v.camera);
    readVector(r, v.regions, 16, kMaxRegionsPerView);
    const bool regions = !v.regions.empty();
    // Without regions the view is the whole image and the reference size means nothing.
    v.refWidth = readInt(r, regions ? 1 : 0, kMaxViewReference, "view reference width");
    v.refHeight = readInt(r, regions ? 1 : 0, kMaxViewReference, "view reference height");
    for (const ViewRegion& g : v.regions)
        if (int64_t(g.x) + g.width > v.refWidth || int64_t(g.y) + g.height > v.refHeight)
            fail("view region " + std::to_string(g.x) + "," + std::to_string(g.y) + "," + std::to_string(g.width) + "," +
                 std::to_string(g.height) + " is outside its " + std::to_string(v.refWidth) + "x" +
                 std::to_string(v.refHeight) + " reference image");
}

RTWALL_WIRE_FIELDS(FrameBegin, 4);
void write(Writer& w, const FrameBegin& m) {
    w.u32(m.frame);
    w.u32(m.updateSeq);
    writeEnum(w, m.pixels);
    writeVector(w, m.views);
}
void read(Reader& r, FrameBegin& m) {
    m.frame = r.u32();
    m.updateSeq = r.u32();
    m.pixels = readEnum(r, TilePixels::LinearHalf, "tile pixel format");
    static const size_t viewBytes = [] {
        FrameView v;
        v.camera.name.clear();
        return minEncodedSize(v);
    }();
    readVector(r, m.views, viewBytes, kMaxViews);
    // Version 13: the views are the frame's only camera; a frame without one cannot be rendered.
    if (m.views.empty()) fail("frame " + std::to_string(m.frame) + " has no view");
}

RTWALL_WIRE_FIELDS(TileRequest, 2);
void write(Writer& w, const TileRequest& m) {
    w.u32(m.frame);
    w.u32(m.count);
}
void read(Reader& r, TileRequest& m) {
    m.frame = r.u32();
    m.count = r.u32();
    if (m.count > kMaxTilesPerMessage) fail("tile request for " + std::to_string(m.count) + " tiles exceeds the limit");
}

RTWALL_WIRE_FIELDS(TileAssign, 2);
void write(Writer& w, const TileAssign& m) {
    w.u32(m.frame);
    if (m.tiles.size() > std::numeric_limits<uint32_t>::max())
        throw std::length_error("protocol: too many tiles in one assignment");
    w.u32(uint32_t(m.tiles.size()));
    for (uint32_t t : m.tiles) w.u32(t);
}
void read(Reader& r, TileAssign& m) {
    m.frame = r.u32();
    const uint32_t n = r.u32();
    r.expectElements(n, sizeof(uint32_t), kMaxTilesPerMessage);
    m.tiles.resize(n);
    for (uint32_t& t : m.tiles) t = r.u32();
}

RTWALL_WIRE_FIELDS(TileResult, 6);
void write(Writer& w, const TileResult& m) {
    w.u32(m.frame);
    w.u32(m.tile);
    writeEnum(w, m.codec);
    w.u32(m.renderMicros);
    w.blob(m.pixels.data(), m.pixels.size());
    writeEnum(w, m.format);
}
// A TileResult with its pixels as a view into the message: the one reader of its layout, for
// decodePayload (which copies the pixels) and peekTileResult (which does not).
struct TileResultView {
    TileResult fields;  // all but the pixels
    std::pair<const uint8_t*, size_t> pixels;
};
void read(Reader& r, TileResultView& v) {
    // A half-float tile is encoded as an 8-bit tile twice as wide.
    static const size_t maxPixelBytes = maxEncodedTileBytes(2 * kMaxTileSize, kMaxTileSize);
    TileResult& m = v.fields;
    m.frame = r.u32();
    m.tile = r.u32();
    m.codec = readEnum(r, TileCodec::Jpeg, "tile codec");
    m.renderMicros = r.u32();
    v.pixels = r.blobView(maxPixelBytes);
    m.format = readEnum(r, TilePixels::LinearHalf, "tile pixel format");
}
void read(Reader& r, TileResult& m) {
    TileResultView v;
    read(r, v);
    m = std::move(v.fields);
    m.pixels.assign(v.pixels.first, v.pixels.first + v.pixels.second);
}

RTWALL_WIRE_FIELDS(Heartbeat, 3);
void write(Writer& w, const Heartbeat& m) {
    w.u32(m.frame);
    w.u32(m.tilesSeen);
    w.boolean(m.idle);
}
void read(Reader& r, Heartbeat& m) {
    m.frame = r.u32();
    m.tilesSeen = r.u32();
    m.idle = r.boolean();
}

RTWALL_WIRE_FIELDS(TileStalled, 3);
void write(Writer& w, const TileStalled& m) {
    w.u32(m.frame);
    w.u32(m.tile);
    w.u32(m.elapsedMs);
}
void read(Reader& r, TileStalled& m) {
    m.frame = r.u32();
    m.tile = r.u32();
    m.elapsedMs = r.u32();
}

RTWALL_WIRE_FIELDS(TileFailed, 5);
RTWALL_WIRE_FIELDS(TileRect, 4);  // written with TileFailed
void write(Writer& w, const TileFailed& m) {
    w.u32(m.frame);
    w.u32(m.tile);
    for (int v : {m.rect.x0, m.rect.y0, m.rect.x1, m.rect.y1}) w.i32(v);
    w.i32(m.packetWidth);
    w.string(m.reason);
}
void read(Reader& r, TileFailed& m) {
    m.frame = r.u32();
    m.tile = r.u32();
    m.rect.x0 = readInt(r, 0, kMaxImageSide - 1, "failed tile x0");
    m.rect.y0 = readInt(r, 0, kMaxImageSide - 1, "failed tile y0");
    m.rect.x1 = readInt(r, m.rect.x0 + 1, kMaxImageSide, "failed tile x1");
    m.rect.y1 = readInt(r, m.rect.y0 + 1, kMaxImageSide, "failed tile y1");
    m.packetWidth = readInt(r, 4, 16, "packet width");
    if (m.packetWidth != 4 && m.packetWidth != 8 && m.packetWidth != 16)
        fail("packet width " + std::to_string(m.packetWidth) + " is not 4, 8 or 16");
    m.reason = r.string(kMaxStringBytes);
}

RTWALL_WIRE_FIELDS(Goodbye, 1);
void write(Writer& w, const Goodbye& m) { w.string(m.reason); }
void read(Reader& r, Goodbye& m) { m.reason = r.string(kMaxStringBytes); }

RTWALL_WIRE_FIELDS(Ready, 2);
void write(Writer& w, const Ready& m) {
    w.u32(m.updateSeq);
    write(w, m.stateHash);
}
void read(Reader& r, Ready& m) {
    m.updateSeq = r.u32();
    m.stateHash = readHash(r);
}

RTWALL_WIRE_FIELDS(ResyncRequest, 1);
void write(Writer& w, const ResyncRequest& m) { w.u32(m.lastSeq); }
void read(Reader& r, ResyncRequest& m) { m.lastSeq = r.u32(); }

// -- Display nodes (version 11) ------------------------------------------------------------------

constexpr size_t kMaxEndpointBytes = 256;
constexpr size_t kZ85KeyChars = 40;

std::string readNodeName(Reader& r, const char* what) {
    std::string name = r.string(32);
    if (!isNodeName(name)) fail(std::string(what) + " '" + name + "' is not a node name (1 to 32 letters, digits, '-' or '_')");
    return name;
}

std::string readEndpoint(Reader& r) {
    std::string e = r.string(kMaxEndpointBytes);
    if (e.empty()) fail("empty node endpoint");
    for (char c : e)
        if (c <= ' ' || c > '~') fail("node endpoint has a control, space or non-ASCII character");
    return e;
}

std::string readKey(Reader& r, const char* what) {
    std::string key = r.string(kZ85KeyChars);
    if (!key.empty() && key.size() != kZ85KeyChars)
        fail(std::string(what) + " has " + std::to_string(key.size()) + " characters, not 40 (Z85) or 0");
    for (char c : key)
        if (c <= ' ' || c > '~' || c == '"' || c == '\'' || c == ',' || c == ';' || c == '\\' || c == '_' || c == '`' ||
            c == '|' || c == '~')
            fail(std::string(what) + " is not Z85");
    return key;
}

uint32_t readNodeIndex(Reader& r) {
    const uint32_t node = r.u32();
    if (node >= kMaxNodes) fail("node index " + std::to_string(node) + " is not below " + std::to_string(kMaxNodes));
    return node;
}

RTWALL_WIRE_FIELDS(NodeHello, 4);
void write(Writer& w, const NodeHello& m) {
    w.u16(m.protocolVersion);
    w.string(m.name);
    w.string(m.endpoint);
    w.string(m.publicKey);
}
void read(Reader& r, NodeHello& m) {
    m.protocolVersion = r.u16();
    m.name = readNodeName(r, "node name");
    m.endpoint = readEndpoint(r);
    m.publicKey = readKey(r, "node public key");
}

RTWALL_WIRE_FIELDS(NodeWelcome, 5);
void write(Writer& w, const NodeWelcome& m) {
    w.u32(m.node);
    w.u32(m.heartbeatMs);
    w.u32(m.timeoutMs);
    w.string(m.wall);
    if (m.clientKeys.size() > kMaxClientKeys) throw std::length_error("protocol: too many client keys for a node");
    w.u32(uint32_t(m.clientKeys.size()));
    for (const std::string& k : m.clientKeys) w.string(k);
}
void read(Reader& r, NodeWelcome& m) {
    m.node = readNodeIndex(r);
    m.heartbeatMs = r.u32();
    m.timeoutMs = r.u32();
    if (m.heartbeatMs < 1 || m.heartbeatMs > kMaxTimeoutMs || m.timeoutMs < m.heartbeatMs || m.timeoutMs > kMaxTimeoutMs)
        fail("node heartbeat " + std::to_string(m.heartbeatMs) + " ms and timeout " + std::to_string(m.timeoutMs) +
             " ms are out of range");
    m.wall = r.string(kMaxWallConfigBytes);
    if (m.wall.empty()) fail("node welcome without a wall config");
    const uint32_t keys = r.u32();
    r.expectElements(keys, sizeof(uint32_t) + kZ85KeyChars, kMaxClientKeys);
    m.clientKeys.resize(keys);
    for (std::string& k : m.clientKeys) {
        k = readKey(r, "client key");
        if (k.empty()) fail("empty client key");
    }
}

RTWALL_WIRE_FIELDS(NodeFrame, 9);
void write(Writer& w, const NodeFrame& m) {
    w.u32(m.frame);
    w.i32(m.width);
    w.i32(m.height);
    w.i32(m.tileSize);
    writeEnum(w, m.pixels);
    writeVector(w, m.views);
    if (m.eyes.size() > kMaxViews) throw std::length_error("protocol: more view eyes than views");
    w.u32(uint32_t(m.eyes.size()));
    for (int8_t eye : m.eyes) w.u8(uint8_t(eye));
    w.boolean(m.stochastic);
    w.u32(m.stateSeq);
}
void read(Reader& r, NodeFrame& m) {
    m.frame = r.u32();
    m.width = readInt(r, 1, kMaxImageSide, "node frame width");
    m.height = readInt(r, 1, kMaxImageSide, "node frame height");
    m.tileSize = readInt(r, 1, kMaxTileSize, "node frame tile size");
    const uint64_t tiles = uint64_t((m.width + m.tileSize - 1) / m.tileSize) * uint64_t((m.height + m.tileSize - 1) / m.tileSize);
    if (tiles > kMaxTilesPerFrame) fail("node frame of " + std::to_string(tiles) + " tiles exceeds the limit");
    m.pixels = readEnum(r, TilePixels::LinearHalf, "tile pixel format");
    static const size_t viewBytes = [] {
        FrameView v;
        v.camera.name.clear();
        return minEncodedSize(v);
    }();
    readVector(r, m.views, viewBytes, kMaxViews);
    // Every view may hold every tile: the node's tiling is bounded as one frame's.
    if (tiles * std::max<uint64_t>(1, m.views.size()) > kMaxTilesPerFrame)
        fail("node frame of " + std::to_string(m.views.size()) + " views of " + std::to_string(tiles) +
             " tiles exceeds the limit");
    const uint32_t eyes = r.u32();
    if (eyes != m.views.size())
        fail("node frame with " + std::to_string(eyes) + " view eyes for " + std::to_string(m.views.size()) + " views");
    r.expectElements(eyes, 1, kMaxViews);
    m.eyes.resize(eyes);
    for (int8_t& eye : m.eyes) {
        const uint8_t e = r.u8();
        if (e != 0 && e != 1 && e != 0xff) fail("view eye " + std::to_string(int(int8_t(e))) + " is not -1, 0 or 1");
        eye = int8_t(e);
    }
    m.stochastic = r.boolean();
    m.stateSeq = r.u32();
    if (m.pixels == TilePixels::LinearHalf && !m.stochastic) fail("linear tiles for a frame that is not accumulated");
}

RTWALL_WIRE_FIELDS(NodeHave, 1);
void write(Writer& w, const NodeHave& m) { w.u32(m.frame); }
void read(Reader& r, NodeHave& m) { m.frame = r.u32(); }

RTWALL_WIRE_FIELDS(NodeSwap, 2);
void write(Writer& w, const NodeSwap& m) {
    w.u32(m.frame);
    if (m.leftOut.size() > kMaxNodes) throw std::length_error("protocol: more left-out nodes than nodes");
    w.u32(uint32_t(m.leftOut.size()));
    for (const std::string& n : m.leftOut) w.string(n);
}
void read(Reader& r, NodeSwap& m) {
    m.frame = r.u32();
    const uint32_t n = r.u32();
    r.expectElements(n, sizeof(uint32_t) + 1, kMaxNodes);
    m.leftOut.resize(n);
    for (std::string& name : m.leftOut) name = readNodeName(r, "left-out node");
}

RTWALL_WIRE_FIELDS(NodeSwapped, 1);
void write(Writer& w, const NodeSwapped& m) { w.u32(m.frame); }
void read(Reader& r, NodeSwapped& m) { m.frame = r.u32(); }

RTWALL_WIRE_FIELDS(NodeEndpoint, 4);
void write(Writer& w, const NodeEndpoint& m) {
    w.u32(m.node);
    w.string(m.name);
    w.string(m.endpoint);
    w.string(m.serverKey);
}
void read(Reader& r, NodeEndpoint& m) {
    m.node = readNodeIndex(r);
    m.name = readNodeName(r, "node name");
    m.endpoint = readEndpoint(r);
    m.serverKey = readKey(r, "node server key");
}

RTWALL_WIRE_FIELDS(NodeList, 1);
void write(Writer& w, const NodeList& m) {
    if (m.nodes.size() > kMaxNodes) throw std::length_error("protocol: more than 64 nodes in a node list");
    writeVector(w, m.nodes);
}
void read(Reader& r, NodeList& m) {
    static const size_t endpointBytes = minEncodedSize(NodeEndpoint{});
    readVector(r, m.nodes, endpointBytes, kMaxNodes);
    uint64_t seen = 0;
    for (const NodeEndpoint& e : m.nodes) {
        if (seen & (uint64_t(1) << e.node)) fail("node " + std::to_string(e.node) + " is twice in the node list");
        seen |= uint64_t(1) << e.node;
    }
}

RTWALL_WIRE_FIELDS(TileRoutes, 2);
void write(Writer& w, const TileRoutes& m) {
    w.u32(m.frame);
    if (m.masks.size() > kMaxTilesPerFrame) throw std::length_error("protocol: too many tiles for tile routes");
    w.u32(uint32_t(m.masks.size()));
    for (uint64_t mask : m.masks) w.u64(mask);
}
void read(Reader& r, TileRoutes& m) {
    m.frame = r.u32();
    const uint32_t n = r.u32();
    r.expectElements(n, sizeof(uint64_t), kMaxTilesPerFrame);
    m.masks.resize(n);
    for (uint64_t& mask : m.masks) mask = r.u64();
}

RTWALL_WIRE_FIELDS(TileDone, 4);
void write(Writer& w, const TileDone& m) {
    w.u32(m.frame);
    w.u32(m.tile);
    w.u32(m.renderMicros);
    w.u32(m.bytes);
}
void read(Reader& r, TileDone& m) {
    m.frame = r.u32();
    m.tile = r.u32();
    m.renderMicros = r.u32();
    m.bytes = r.u32();
}

RTWALL_WIRE_FIELDS(Header, 6);
void writeHeader(Writer& w, const Header& h) {
    w.u32(kMagic);
    w.u16(h.version);
    w.u16(uint16_t(h.type));
    w.u64(h.session);
    w.u32(h.frame);
    w.u32(h.sceneVersion);
    w.u32(h.payloadLength);
    w.u32(0);  // reserved
}

// Measures with a counting writer, reserves exactly, then writes with the same code.
template <class F> std::vector<uint8_t> measureAndWrite(F&& writeAll) {
    Writer counter;
    writeAll(counter);
    std::vector<uint8_t> out;
    out.reserve(counter.size());
    Writer w(&out);
    writeAll(w);
    if (w.size() != counter.size())
        throw std::logic_error("protocol: measured " + std::to_string(counter.size()) + " bytes but wrote " +
                               std::to_string(w.size()));
    return out;
}

}  // namespace

// -- Public API ----------------------------------------------------------------------------------

Header decodeHeader(const uint8_t* data, size_t size) {
    if (size < kHeaderSize)
        fail("message of " + std::to_string(size) + " bytes is shorter than the " + std::to_string(kHeaderSize) +
             "-byte header");
    Reader r(data, kHeaderSize);
    const uint32_t magic = r.u32();
    if (magic != kMagic) fail("bad magic number " + std::to_string(magic));
    Header h;
    h.version = r.u16();
    const uint16_t type = r.u16();
    if (type < 1 || type > kMaxMsgType) fail("unknown message type " + std::to_string(type));
    h.type = MsgType(type);
    h.session = r.u64();
    h.frame = r.u32();
    h.sceneVersion = r.u32();
    h.payloadLength = r.u32();
    if (h.payloadLength != size - kHeaderSize)
        fail("header says " + std::to_string(h.payloadLength) + " payload bytes, message has " +
             std::to_string(size - kHeaderSize));
    const uint32_t reserved = r.u32();
    if (reserved != 0) fail("reserved header field is " + std::to_string(reserved) + ", not 0");
    return h;
}

template <class Msg> std::vector<uint8_t> encodeMessage(Header header, const Msg& msg) {
    // The type always follows the message, so a header copied from another message cannot mislabel it.
    header.type = messageTypeOf(msg);
    Writer counter;
    write(counter, msg);
    if (counter.size() > std::numeric_limits<uint32_t>::max())
        throw std::length_error("protocol: payload of " + std::to_string(counter.size()) + " bytes is too large");
    header.payloadLength = uint32_t(counter.size());

    std::vector<uint8_t> out;
    out.reserve(kHeaderSize + counter.size());
    Writer w(&out);
    writeHeader(w, header);
    write(w, msg);
    if (w.size() != kHeaderSize + counter.size())
        throw std::logic_error("protocol: measured " + std::to_string(kHeaderSize + counter.size()) +
                               " bytes but wrote " + std::to_string(w.size()));
    return out;
}

template <class Msg> Msg decodePayload(const uint8_t* data, size_t size) {
    Reader r(data, size);
    Msg msg;
    read(r, msg);
    r.expectEnd();
    return msg;
}

TileResultInfo peekTileResult(const uint8_t* data, size_t size) {
    Reader r(data, size);
    TileResultView v;
    read(r, v);
    r.expectEnd();
    return {v.fields.frame, v.fields.tile, v.fields.renderMicros, uint32_t(v.pixels.second)};
}

MsgType messageTypeOf(const Hello&) { return MsgType::Hello; }
MsgType messageTypeOf(const Welcome&) { return MsgType::Welcome; }
MsgType messageTypeOf(const SceneSnapshot&) { return MsgType::SceneSnapshot; }
MsgType messageTypeOf(const MeshRequest&) { return MsgType::MeshRequest; }
MsgType messageTypeOf(const MeshData&) { return MsgType::MeshData; }
MsgType messageTypeOf(const Update&) { return MsgType::Update; }
MsgType messageTypeOf(const FrameBegin&) { return MsgType::FrameBegin; }
MsgType messageTypeOf(const TileRequest&) { return MsgType::TileRequest; }
MsgType messageTypeOf(const TileAssign&) { return MsgType::TileAssign; }
MsgType messageTypeOf(const TileResult&) { return MsgType::TileResult; }
MsgType messageTypeOf(const Heartbeat&) { return MsgType::Heartbeat; }
MsgType messageTypeOf(const Goodbye&) { return MsgType::Goodbye; }
MsgType messageTypeOf(const Ready&) { return MsgType::Ready; }
MsgType messageTypeOf(const ResyncRequest&) { return MsgType::ResyncRequest; }
MsgType messageTypeOf(const AssetRequest&) { return MsgType::AssetRequest; }
MsgType messageTypeOf(const AssetData&) { return MsgType::AssetData; }
MsgType messageTypeOf(const TileStalled&) { return MsgType::TileStalled; }
MsgType messageTypeOf(const TileFailed&) { return MsgType::TileFailed; }
MsgType messageTypeOf(const NodeHello&) { return MsgType::NodeHello; }
MsgType messageTypeOf(const NodeWelcome&) { return MsgType::NodeWelcome; }
MsgType messageTypeOf(const NodeFrame&) { return MsgType::NodeFrame; }
MsgType messageTypeOf(const NodeHave&) { return MsgType::NodeHave; }
MsgType messageTypeOf(const NodeSwap&) { return MsgType::NodeSwap; }
MsgType messageTypeOf(const NodeSwapped&) { return MsgType::NodeSwapped; }
MsgType messageTypeOf(const NodeList&) { return MsgType::NodeList; }
MsgType messageTypeOf(const TileRoutes&) { return MsgType::TileRoutes; }
MsgType messageTypeOf(const TileDone&) { return MsgType::TileDone; }

bool isNodeName(const std::string& name) {
    if (name.empty() || name.size() > 32) return false;
    for (char c : name)
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_'))
            return false;
    return true;
}

#define RTWALL_INSTANTIATE_MESSAGE(Msg)                                                    \
    template std::vector<uint8_t> encodeMessage<Msg>(Header header, const Msg& msg); \
    template Msg decodePayload<Msg>(const uint8_t* data, size_t size);
RTWALL_INSTANTIATE_MESSAGE(Hello)
RTWALL_INSTANTIATE_MESSAGE(Welcome)
RTWALL_INSTANTIATE_MESSAGE(SceneSnapshot)
RTWALL_INSTANTIATE_MESSAGE(MeshRequest)
RTWALL_INSTANTIATE_MESSAGE(MeshData)
RTWALL_INSTANTIATE_MESSAGE(Update)
RTWALL_INSTANTIATE_MESSAGE(FrameBegin)
RTWALL_INSTANTIATE_MESSAGE(TileRequest)
RTWALL_INSTANTIATE_MESSAGE(TileAssign)
RTWALL_INSTANTIATE_MESSAGE(TileResult)
RTWALL_INSTANTIATE_MESSAGE(Heartbeat)
RTWALL_INSTANTIATE_MESSAGE(Goodbye)
RTWALL_INSTANTIATE_MESSAGE(Ready)
RTWALL_INSTANTIATE_MESSAGE(ResyncRequest)
RTWALL_INSTANTIATE_MESSAGE(AssetRequest)
RTWALL_INSTANTIATE_MESSAGE(AssetData)
RTWALL_INSTANTIATE_MESSAGE(TileStalled)
RTWALL_INSTANTIATE_MESSAGE(TileFailed)
RTWALL_INSTANTIATE_MESSAGE(NodeHello)
RTWALL_INSTANTIATE_MESSAGE(NodeWelcome)
RTWALL_INSTANTIATE_MESSAGE(NodeFrame)
RTWALL_INSTANTIATE_MESSAGE(NodeHave)
RTWALL_INSTANTIATE_MESSAGE(NodeSwap)
RTWALL_INSTANTIATE_MESSAGE(NodeSwapped)
RTWALL_INSTANTIATE_MESSAGE(NodeList)
RTWALL_INSTANTIATE_MESSAGE(TileRoutes)
RTWALL_INSTANTIATE_MESSAGE(TileDone)
#undef RTWALL_INSTANTIATE_MESSAGE

// -- Meshes --------------------------------------------------------------------------------------

namespace {

void writeMesh(Writer& w, const TriangleMesh& mesh) {
    const size_t vertices = mesh.vertexCount(), triangles = mesh.triangleCount();
    w.u64(vertices);
    const float* p = mesh.positions();
    for (size_t i = 0; i < 3 * vertices; ++i) w.f32(p[i]);
    w.u64(triangles);
    const uint32_t* idx = mesh.indices();
    for (size_t i = 0; i < 3 * triangles; ++i) w.u32(idx[i]);
    w.boolean(mesh.hasNormals());
    if (const float* n = mesh.normals())
        for (size_t i = 0; i < 3 * vertices; ++i) w.f32(n[i]);
    // Version 4: vertex colours, after the normals.
    w.boolean(mesh.hasColors());
    if (const uint8_t* c = mesh.colors()) w.bytes(c, 3 * vertices);
    // Version 5: texture coordinates (u, v per vertex), after the colours.
    w.boolean(mesh.hasUVs());
    if (const float* t = mesh.uvs())
        for (size_t i = 0; i < 2 * vertices; ++i) w.f32(t[i]);
}

}  // namespace

std::vector<uint8_t> encodeMesh(const TriangleMesh& mesh) {
    return measureAndWrite([&](Writer& w) { writeMesh(w, mesh); });
}

TriangleMesh decodeMesh(const uint8_t* data, size_t size) {
    if (size > kMaxMeshBytes) fail("mesh of " + std::to_string(size) + " bytes exceeds the limit");
    Reader r(data, size);
    constexpr size_t kVertexBytes = 3 * sizeof(float), kTriangleBytes = 3 * sizeof(uint32_t);
    TriangleMesh mesh;

    const uint64_t vertices = r.u64();
    // 32-bit indices address at most 2^32 - 1 vertices (TriangleMesh's own limit).
    r.expectElements(vertices, kVertexBytes, std::numeric_limits<uint32_t>::max());
    mesh.reserve(size_t(vertices), 0);
    for (uint64_t v = 0; v < vertices; ++v) mesh.addVertex(readFloat3(r));

    const uint64_t triangles = r.u64();
    r.expectElements(triangles, kTriangleBytes, kMaxMeshBytes / kTriangleBytes);
    mesh.reserve(size_t(vertices), size_t(triangles));
    for (uint64_t t = 0; t < triangles; ++t) {
        uint32_t c[3];
        for (uint32_t& i : c) {
            i = r.u32();
            if (i >= vertices)
                fail("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(i) + " of " +
                     std::to_string(vertices));
        }
        mesh.addTriangle(c[0], c[1], c[2]);
    }

    if (r.boolean()) {
        // The encoder writes the flag only for a mesh with normals, which has vertices; anything
        // else would not re-encode to the same bytes (and hash).
        if (vertices == 0) fail("normals flag set on a mesh without vertices");
        r.expectElements(vertices, kVertexBytes, std::numeric_limits<uint32_t>::max());
        std::vector<float> normals(size_t(3 * vertices));
        for (float& n : normals) n = r.f32();
        mesh.setNormals(std::move(normals));
    }
    if (r.boolean()) {
        if (vertices == 0) fail("colours flag set on a mesh without vertices");
        r.expectElements(vertices, 3, std::numeric_limits<uint32_t>::max());
        std::vector<uint8_t> colors(size_t(3 * vertices));
        r.bytes(colors.data(), colors.size());
        mesh.setColors(std::move(colors));
    }
    if (r.boolean()) {
        if (vertices == 0) fail("texture coordinates flag set on a mesh without vertices");
        r.expectElements(vertices, 2 * sizeof(float), std::numeric_limits<uint32_t>::max());
        std::vector<float> uv(size_t(2 * vertices));
        for (size_t i = 0; i < uv.size(); ++i) {
            uv[i] = r.f32();
            if (!std::isfinite(uv[i])) fail("vertex " + std::to_string(i / 2) + " has a non-finite texture coordinate");
        }
        mesh.setUVs(std::move(uv));
    }
    r.expectEnd();
    return mesh;
}

Hash128 hashBytes(const uint8_t* data, size_t size) {
    const XXH128_hash_t h = XXH3_128bits(data, size);
    return {h.low64, h.high64};
}

// -- Scene state -----------------------------------------------------------------------------------

template <class T> std::vector<uint8_t> encodeValue(const T& value) {
    return measureAndWrite([&](Writer& w) { write(w, value); });
}
template std::vector<uint8_t> encodeValue(const Material&);
template std::vector<uint8_t> encodeValue(const Light&);
template std::vector<uint8_t> encodeValue(const CameraDesc&);
template std::vector<uint8_t> encodeValue(const InstanceDesc&);
template std::vector<uint8_t> encodeValue(const RenderSettings&);
template std::vector<uint8_t> encodeValue(const SectionPlane&);

Hash128 stateHash(const SceneSnapshot& snapshot) {
    const std::vector<uint8_t> bytes = measureAndWrite([&](Writer& w) { writeState(w, snapshot); });
    return hashBytes(bytes.data(), bytes.size());
}

EncodedSnapshot encodeSnapshot(const Header& header, const SceneSnapshot& snapshot) {
    EncodedSnapshot out;
    out.message = encodeMessage(header, snapshot);
    // The payload is the sequence number (u32) and then writeState's bytes: hashed in place.
    constexpr size_t kState = kHeaderSize + sizeof(uint32_t);
    out.stateHash = hashBytes(out.message.data() + kState, out.message.size() - kState);
    return out;
}

}  // namespace rtwall::cluster
