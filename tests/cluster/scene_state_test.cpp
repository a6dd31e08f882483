// Tests for cluster/src/scene_state.cpp and the member guards (fields.h): one mapping between a
// scene description and what travels (issue 17). Every member of every struct that travels is set
// to a value other than its default (checked member by member, so a member added without being
// set here fails), and SceneDesc -> snapshot -> bytes -> snapshot -> SceneDesc gives every one
// back; each member on its own changes a value's wire bytes (what diffScenes compares); a change
// does the same to a scene description and to a snapshot; merged updates keep the last change to
// each object.
#include "fields.h"
#include "scene_state.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

namespace rtwall::cluster {
namespace {

// -- Members by position -------------------------------------------------------------------------

// A tuple of references to an aggregate's members. The structured binding needs exactly
// fieldCount<T>() names: these tests compiling is the proof that fieldCount counts right.
template <class T> auto tieFields(T& t) {
    constexpr size_t n = fieldCount<std::remove_const_t<T>>();
    static_assert(n >= 1 && n <= 22, "tieFields: add a case");
    if constexpr (n == 1) { auto& [a] = t; return std::tie(a); }
    else if constexpr (n == 2) { auto& [a, b] = t; return std::tie(a, b); }
    else if constexpr (n == 3) { auto& [a, b, c] = t; return std::tie(a, b, c); }
    else if constexpr (n == 4) { auto& [a, b, c, d] = t; return std::tie(a, b, c, d); }
    else if constexpr (n == 5) { auto& [a, b, c, d, e] = t; return std::tie(a, b, c, d, e); }
    else if constexpr (n == 6) { auto& [a, b, c, d, e, f] = t; return std::tie(a, b, c, d, e, f); }
    else if constexpr (n == 7) { auto& [a, b, c, d, e, f, g] = t; return std::tie(a, b, c, d, e, f, g); }
    else if constexpr (n == 8) { auto& [a, b, c, d, e, f, g, h] = t; return std::tie(a, b, c, d, e, f, g, h); }
    else if constexpr (n == 9) { auto& [a, b, c, d, e, f, g, h, i] = t; return std::tie(a, b, c, d, e, f, g, h, i); }
    else if constexpr (n == 10) { auto& [a, b, c, d, e, f, g, h, i, j] = t; return std::tie(a, b, c, d, e, f, g, h, i, j); }
    else if constexpr (n == 11) { auto& [a, b, c, d, e, f, g, h, i, j, k] = t; return std::tie(a, b, c, d, e, f, g, h, i, j, k); }
    else if constexpr (n == 12) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l);
    } else if constexpr (n == 13) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m);
    } else if constexpr (n == 14) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o);
    } else if constexpr (n == 15) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p);
    } else if constexpr (n == 16) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q);
    } else if constexpr (n == 17) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r);
    } else if constexpr (n == 18) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s);
    } else if constexpr (n == 19) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s, u] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s, u);
    } else if constexpr (n == 20) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s, u, v] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s, u, v);
    } else if constexpr (n == 21) {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s, u, v, w] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s, u, v, w);
    } else {
        auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s, u, v, w, x] = t;
        return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q, r, s, u, v, w, x);
    }
}

template <class T> struct IsVector : std::false_type {};
template <class T> struct IsVector<std::vector<T>> : std::true_type {};
template <class T> struct IsOptional : std::false_type {};
template <class T> struct IsOptional<std::optional<T>> : std::true_type {};
template <class T> struct IsArray : std::false_type {};
template <class T, size_t N> struct IsArray<std::array<T, N>> : std::true_type {};
template <class T> struct IsSharedPtr : std::false_type {};
template <class T> struct IsSharedPtr<std::shared_ptr<T>> : std::true_type {};

// The structs that are walked member by member (the others are compared whole).
template <class T>
constexpr bool kWalked = std::is_same_v<T, SceneDesc> || std::is_same_v<T, SceneSnapshot> || std::is_same_v<T, MeshDesc> ||
                         std::is_same_v<T, MeshRef> || std::is_same_v<T, AssetRef> || std::is_same_v<T, Material> ||
                         std::is_same_v<T, TextureDesc> || std::is_same_v<T, TransferPoint> || std::is_same_v<T, Light> ||
                         std::is_same_v<T, CameraDesc> || std::is_same_v<T, ProjectionWindow> ||
                         std::is_same_v<T, InstanceDesc> || std::is_same_v<T, Transform> ||
                         std::is_same_v<T, RenderSettings> || std::is_same_v<T, BvhSettings> || std::is_same_v<T, Float3> ||
                         std::is_same_v<T, SectionPlane>;

std::string memberPath(const std::string& path, size_t i) { return path + "." + std::to_string(i); }

// Every member of `v` (and of its members, and of every element) differs from the default's.
template <class T> void expectAllSet(const T& v, const T& defaults, const std::string& path) {
    if constexpr (IsVector<T>::value) {
        ASSERT_FALSE(v.empty()) << path << " is empty";
        for (size_t i = 0; i < v.size(); ++i)
            expectAllSet(v[i], typename T::value_type{}, path + "[" + std::to_string(i) + "]");
    } else if constexpr (IsOptional<T>::value) {
        ASSERT_TRUE(v.has_value()) << path << " is empty";
        expectAllSet(*v, typename T::value_type{}, path);
    } else if constexpr (IsArray<T>::value) {
        for (size_t i = 0; i < v.size(); ++i) expectAllSet(v[i], defaults[i], path + "[" + std::to_string(i) + "]");
    } else if constexpr (IsSharedPtr<T>::value) {
        EXPECT_TRUE(v != nullptr) << path << " is null";
    } else if constexpr (std::is_same_v<T, decltype(SceneDesc::files)>) {
        EXPECT_FALSE(v.empty()) << path << " is empty";
    } else if constexpr (kWalked<T>) {
        const auto a = tieFields(v), b = tieFields(defaults);
        [&]<size_t... I>(std::index_sequence<I...>) {
            (expectAllSet(std::get<I>(a), std::get<I>(b), memberPath(path, I)), ...);
        }(std::make_index_sequence<std::tuple_size_v<decltype(a)>>{});
    } else {
        EXPECT_TRUE(v != defaults) << path << " has its default value: set it in the sample";
    }
}

// The same member by member, for a message that names the member.
template <class T> void expectEqualMembers(const T& x, const T& y, const std::string& path) {
    if constexpr (IsVector<T>::value) {
        ASSERT_EQ(x.size(), y.size()) << path;
        for (size_t i = 0; i < x.size(); ++i) expectEqualMembers(x[i], y[i], path + "[" + std::to_string(i) + "]");
    } else if constexpr (kWalked<T>) {
        const auto a = tieFields(x), b = tieFields(y);
        [&]<size_t... I>(std::index_sequence<I...>) {
            (expectEqualMembers(std::get<I>(a), std::get<I>(b), memberPath(path, I)), ...);
        }(std::make_index_sequence<std::tuple_size_v<decltype(a)>>{});
    } else {
        EXPECT_TRUE(x == y) << path << " differs";
    }
}

// -- Samples: every member other than its default, and valid for the decoders --------------------

Float3 f3(float x, float y, float z) { return {x, y, z}; }

TextureDesc sampleTexture(int k) {
    TextureDesc t;
    t.kind = TextureKind::Image;
    t.file = "tex/image-" + std::to_string(k) + ".png";
    t.color2 = f3(0.3f, 0.6f, 0.9f - 0.01f * float(k));
    t.scale = 2.5f + float(k);
    t.mapping = k % 2 ? TextureMapping::Spherical : TextureMapping::Uv;
    return t;
}

Material sampleMaterial(int k) {
    Material m;
    m.name = "material-" + std::to_string(k);
    m.type = k % 2 ? MaterialType::Glass : MaterialType::Volume;
    m.color = f3(0.25f, 0.5f, 0.75f - 0.0625f * float(k));
    m.specular = f3(0.125f, 0.375f, 1.0f);
    m.shininess = 77.5f + float(k);
    m.ior = 1.33f + 0.125f * float(k);
    m.roughness = 0.25f;
    m.absorption = f3(0.5f, 1.0f, 2.0f);
    m.emission = f3(3.0f, 4.0f, 5.0f + float(k));
    m.twoSided = true;
    m.texture = sampleTexture(2 * k);
    m.bump = 0.75f;
    m.bumpScale = 0.25f;
    m.bumpMapping = TextureMapping::Object;
    m.alpha = sampleTexture(2 * k + 1);
    m.alphaCutoff = 0.375f;
    m.alphaMode = AlphaMode::Hashed;
    m.alphaChannel = AlphaChannel::Alpha;
    m.opacity = 0.625f;
    m.volumeFile = "vol/smoke-" + std::to_string(k) + ".vti";
    m.transfer = {TransferPoint{0.25f, f3(0.5f, 0.25f, 0.125f), 1.5f}, TransferPoint{0.75f, f3(2.0f, 0.5f, 0.0625f), 3.0f}};
    m.volumeStep = 1.5f;
    return m;
}

Light sampleLight(int k) {
    Light l;
    l.type = k % 2 ? LightType::Directional : LightType::Area;
    l.position = f3(1.5f, -2.25f, 3.0f + float(k));
    l.direction = f3(0.5f, -0.75f, 0.25f);
    l.color = f3(0.9f, 0.8f, 0.7f);
    l.intensity = 123.5f + float(k);
    l.edge1 = f3(2.0f, 0.5f, 0.25f);
    l.edge2 = f3(0.25f, 0.5f, 2.0f + float(k));
    l.twoSided = true;
    return l;
}

CameraDesc sampleCamera(int k) {
    CameraDesc c;
    c.name = "wall-" + std::to_string(k);
    c.position = f3(-4.5f, 2.0f, 9.25f + float(k));
    c.lookAt = f3(0.5f, 0.25f, -1.0f);
    c.up = f3(0.125f, 0.5f, 1.0f);
    c.fovY = 61.5f + float(k);
    c.window = ProjectionWindow{f3(-1.25f, -0.75f, 0.5f), f3(2.5f, 0.125f, -0.125f), f3(0.0625f, 1.5f, 0.03125f)};
    return c;
}

SectionPlane sampleSection(int k) {
    SectionPlane p;
    p.enabled = true;
    p.point = f3(0.5f, -1.25f, 2.0f + float(k));
    p.normal = f3(0.25f, 1.0f, -0.5f);
    p.capColor = f3(0.125f, 0.25f, 0.5f);
    p.caps = false;
    return p;
}

Transform sampleTransform(int k) {
    Transform t;
    for (size_t i = 0; i < t.m.size(); ++i) t.m[i] = 0.1 * double(i + 2) + 1e-9 * k + 0.5;
    return t;
}

RenderSettings sampleSettings() {
    RenderSettings s;
    s.width = 1920;
    s.height = 1080;
    s.tileSize = 48;
    s.kernel = KernelType::Single;
    s.shading = ShadingMode::EyeLight;
    s.maxDepth = 12;
    s.supersample = 3;
    s.shadows = false;
    s.background = f3(0.1f, 0.2f, 0.3f);
    s.ambient = f3(0.05f, 0.06f, 0.07f);
    s.threads = 7;
    s.pruneThreshold = 0.01f;
    s.gi = true;
    s.samples = 4;
    s.view = ViewMode::Client;
    return s;
}

FileBytes bytesOf(const std::string& text) { return std::make_shared<const std::vector<uint8_t>>(text.begin(), text.end()); }

AssetRef refOf(const std::string& path, const FileBytes& bytes) {
    return AssetRef{path, hashBytes(bytes->data(), bytes->size()), bytes->size()};
}

SceneDesc sampleScene() {
    SceneDesc d;
    d.sourceFile = "scenes/zoo.toml";
    d.origin = {1e6 + 0.25, -2e5, 3.0e5 + 1.0 / 1024};
    d.bvh = {BvhSettings::Quality::High, true, true, BvhSettings::Primitives::Triangles};
    d.meshes.push_back({"box", "meshes/box.ply", std::make_shared<const TriangleMesh>(makeBox())});
    d.meshes.push_back({"quad", "shape:quad", std::make_shared<const TriangleMesh>(makeQuad())});
    d.materials = {sampleMaterial(0), sampleMaterial(1)};
    d.instances = {InstanceDesc{1, 1, sampleTransform(0), 1, Visibility::Highlighted, true},
                   InstanceDesc{1, 1, sampleTransform(1), 0, Visibility::Hidden, true}};
    d.parts = {PartDesc{"module", -1}, PartDesc{"module/bolt", 0}};
    d.lights = {sampleLight(0), sampleLight(1)};
    d.cameras = {sampleCamera(0), sampleCamera(1)};
    d.settings = sampleSettings();
    for (int i = 0; i < kMaxSections; ++i) d.sections[i] = sampleSection(i);
    d.denoise = {DenoiseSettings::Mode::Svgf, 3, 12, 2.0f, 64.0f, 8.0f};  // the display side's: does not travel
    for (const Material& m : d.materials)
        for (const std::string& path : {m.texture.file, m.alpha.file, m.volumeFile}) d.files[path] = bytesOf("bytes of " + path);
    return d;
}

// What the master sends for `scene`: its meshes and files by hash.
struct Sent {
    std::vector<MeshRef> meshes;
    std::vector<AssetRef> assets;
    std::map<Hash128, std::shared_ptr<const TriangleMesh>> meshBytes;
    std::map<Hash128, FileBytes> fileBytes;
};
Sent sentFor(const SceneDesc& d) {
    Sent s;
    for (const MeshDesc& m : d.meshes) {
        s.meshes.push_back(meshRefOf(m));
        s.meshBytes[s.meshes.back().hash] = m.mesh;
    }
    for (const auto& [path, bytes] : d.files) {
        s.assets.push_back(refOf(path, bytes));
        s.fileBytes[s.assets.back().hash] = bytes;
    }
    return s;
}

// The sample scene's snapshot with update sequence `seq`.
SceneSnapshot sampleSnapshot(uint64_t seq) {
    const SceneDesc d = sampleScene();
    const Sent sent = sentFor(d);
    return snapshotOf(d, sent.meshes, sent.assets, seq);
}

// -- Tests ---------------------------------------------------------------------------------------

TEST(SceneState, MemberCountsAreExact) {
    // The guards count these; tieFields above binds exactly this many names, or does not compile.
    EXPECT_EQ(fieldCount<Material>(), 22u);
    EXPECT_EQ(fieldCount<TextureDesc>(), 5u);
    EXPECT_EQ(fieldCount<TransferPoint>(), 3u);
    EXPECT_EQ(fieldCount<Light>(), 8u);
    EXPECT_EQ(fieldCount<CameraDesc>(), 6u);  // std::optional<ProjectionWindow> counts as one
    EXPECT_EQ(fieldCount<ProjectionWindow>(), 3u);
    EXPECT_EQ(fieldCount<InstanceDesc>(), 6u);
    EXPECT_EQ(fieldCount<Transform>(), 1u);  // the std::array, not its 12 doubles
    EXPECT_EQ(fieldCount<BvhSettings>(), 4u);
    EXPECT_EQ(fieldCount<SectionPlane>(), 5u);
    EXPECT_EQ(fieldCount<SceneDesc>(), 13u);
    EXPECT_EQ(fieldCount<SceneSnapshot>(), 10u);
    EXPECT_EQ(std::tuple_size_v<decltype(tieFields(std::declval<RenderSettings&>()))>, fieldCount<RenderSettings>());
}

TEST(SceneState, TheSamplesSetEveryMember) {
    const SceneDesc d = sampleScene();
    expectAllSet(d, SceneDesc{}, "SceneDesc");
    const Sent sent = sentFor(d);
    expectAllSet(snapshotOf(d, sent.meshes, sent.assets, 42), SceneSnapshot{}, "SceneSnapshot");
}

// SceneDesc -> snapshot -> bytes -> snapshot -> SceneDesc: every member comes back, but for what
// does not travel: the scene file's path, the cameras (a frame carries its views), an assembly's
// part names (the instances' part indices do travel) and the denoiser's settings (the display
// side's). (What is each
// process's own, the packet width and a client's id, is TraceOptions, never on the wire.)
TEST(SceneState, EveryMemberTravelsAndComesBack) {
    const SceneDesc d = sampleScene();
    const Sent sent = sentFor(d);
    const SceneSnapshot snap = snapshotOf(d, sent.meshes, sent.assets, 42);

    Header h;
    h.session = 7;
    const std::vector<uint8_t> bytes = encodeMessage(h, snap);
    const SceneSnapshot& sentSnap = snap;
    const SceneSnapshot decoded = decodePayload<SceneSnapshot>(bytes.data() + kHeaderSize, bytes.size() - kHeaderSize);
    expectEqualMembers(decoded, sentSnap, "SceneSnapshot");
    EXPECT_TRUE(decoded == sentSnap);

    const std::optional<SceneDesc> back = sceneOf(decoded, sent.meshBytes, sent.fileBytes);
    ASSERT_TRUE(back);
    SceneDesc expected = d;
    expected.sourceFile.clear();
    expected.parts.clear();
    expected.cameras.clear();
    expected.denoise = {};
    expectEqualMembers(*back, expected, "SceneDesc");
}

TEST(SceneState, EveryChangeTravelsAndComesBack) {
    Update u;
    u.seq = 9;
    u.baseSeq = 4;
    u.changes = {TransformChange{1, sampleTransform(4)},
                 MaterialChange{1, sampleMaterial(5), {refOf("tex/new.png", bytesOf("new"))}}, LightChange{1, sampleLight(6)},
                 SettingsChange{sampleSettings()}, SectionChange{5, sampleSection(3)},
                 VisibilityChange{1, Visibility::Hidden}};
    expectAllSet(std::get<SectionChange>(u.changes[4]).value, SectionPlane{}, "SectionChange");
    expectAllSet(std::get<MaterialChange>(u.changes[1]).value, Material{}, "MaterialChange");
    expectAllSet(std::get<LightChange>(u.changes[2]).value, Light{}, "LightChange");
    expectAllSet(std::get<SettingsChange>(u.changes[3]).settings, RenderSettings{}, "SettingsChange");
    const std::vector<uint8_t> bytes = encodeMessage(Header{}, u);
    EXPECT_TRUE(decodePayload<Update>(bytes.data() + kHeaderSize, bytes.size() - kHeaderSize) == u);
}

// Each member on its own changes a value's wire bytes: what diffScenes compares, so an edit of
// any member of a material, light, camera, instance or the settings is an update.
template <class T> void expectEveryMemberOnTheWire(const T& sample, const char* name) {
    const T defaults{};
    const auto from = tieFields(sample);
    [&]<size_t... I>(std::index_sequence<I...>) {
        auto one = [&]<size_t K>(std::integral_constant<size_t, K>) {
            T changed = defaults;
            auto& member = std::get<K>(tieFields(changed));
            member = std::get<K>(from);
            EXPECT_FALSE(sameOnWire(defaults, changed)) << name << " member " << K << " does not reach the wire";
        };
        (one(std::integral_constant<size_t, I>{}), ...);
    }(std::make_index_sequence<fieldCount<T>()>{});
}

TEST(SceneState, EveryMemberChangesTheWireBytes) {
    expectEveryMemberOnTheWire(sampleMaterial(0), "Material");
    expectEveryMemberOnTheWire(sampleLight(0), "Light");
    expectEveryMemberOnTheWire(sampleCamera(0), "CameraDesc");
    expectEveryMemberOnTheWire(InstanceDesc{1, 2, sampleTransform(0), 3, Visibility::Hidden, true}, "InstanceDesc");
    expectEveryMemberOnTheWire(sampleSettings(), "RenderSettings");
    expectEveryMemberOnTheWire(sampleSection(0), "SectionPlane");
    EXPECT_TRUE(sameOnWire(sampleMaterial(1), sampleMaterial(1)));
}

// One implementation of what a change writes, for a scene description and for a
// snapshot: after the same changes, the description's snapshot is the changed snapshot.
TEST(SceneState, AChangeDoesTheSameToADescriptionAndToASnapshot) {
    SceneDesc d = sampleScene();
    const Sent sent = sentFor(d);
    SceneSnapshot snap = snapshotOf(d, sent.meshes, sent.assets, 3);
    const AssetRef fresh = refOf("tex/new.png", bytesOf("new"));
    Material m = sampleMaterial(7);
    m.texture.file = fresh.path;
    const std::vector<Change> changes = {
        TransformChange{1, sampleTransform(9)},
        // A file the state holds already and one it does not: only the new one joins the snapshot.
        MaterialChange{0, m, {fresh, sent.assets.front()}}, LightChange{1, sampleLight(4)},
        SettingsChange{RenderSettings{}}, TransformChange{0, sampleTransform(11)}, SectionChange{3, sampleSection(2)}};
    for (const Change& c : changes) {
        applyChange(d, c);
        applyChange(snap, c);
    }
    std::vector<AssetRef> assets = sent.assets;
    assets.push_back(fresh);
    EXPECT_TRUE(snapshotOf(d, sent.meshes, assets, 3) == snap);
    EXPECT_TRUE(d.materials[0] == m);
    EXPECT_TRUE(d.instances[0].transform == sampleTransform(11));
    EXPECT_TRUE(d.sections[3] == sampleSection(2));

    // An object that does not exist: an error, and nothing changed.
    const SceneDesc before = d;
    const SceneSnapshot snapBefore = snap;
    for (const Change& bad : std::vector<Change>{TransformChange{2, {}}, MaterialChange{2, {}, {fresh}}, LightChange{2, {}},
                                                 LightChange{0xFFFFFFFFu, {}}, SectionChange{uint32_t(kMaxSections), {}}}) {
        EXPECT_THROW(applyChange(d, bad), DecodeError);
        EXPECT_THROW(applyChange(snap, bad), DecodeError);
    }
    expectEqualMembers(d, before, "SceneDesc");
    EXPECT_TRUE(snap == snapBefore);
}

TEST(SceneState, SceneOfWaitsForEveryMeshAndFile) {
    const SceneDesc d = sampleScene();
    Sent sent = sentFor(d);
    const SceneSnapshot snap = snapshotOf(d, sent.meshes, sent.assets, 1);
    ASSERT_TRUE(sceneOf(snap, sent.meshBytes, sent.fileBytes));
    auto meshes = sent.meshBytes;
    meshes.erase(sent.meshes[1].hash);
    EXPECT_FALSE(sceneOf(snap, meshes, sent.fileBytes));
    auto files = sent.fileBytes;
    files.erase(sent.assets[2].hash);
    EXPECT_FALSE(sceneOf(snap, sent.meshBytes, files));
}

TEST(SceneState, MergedUpdatesKeepTheLastChangeToEachObject) {
    auto update = [](uint32_t seq, Change c) {
        Update u;
        u.seq = seq;
        u.baseSeq = seq - 1;
        u.changes.push_back(std::move(c));
        return u;
    };
    const std::vector<Update> updates = {
        update(5, SettingsChange{RenderSettings{}}), update(6, TransformChange{3, sampleTransform(1)}),
        update(7, SettingsChange{RenderSettings{}}), update(8, TransformChange{3, sampleTransform(2)}),
        update(9, TransformChange{4, sampleTransform(3)}), update(10, MaterialChange{3, sampleMaterial(1), {}}),
        update(11, LightChange{3, sampleLight(1)}),  update(12, SettingsChange{sampleSettings()})};
    MergedUpdate merged;
    EXPECT_TRUE(merged.empty());
    for (const Update& u : updates) merged.add(Update(u));
    const Update& m = merged.update();
    EXPECT_EQ(m.baseSeq, 4u);
    EXPECT_EQ(m.seq, 12u);
    // The last change to each object in the place of its first; a transform, a material and a
    // light of the same index are three objects.
    const std::vector<Change> expected = {SettingsChange{sampleSettings()}, TransformChange{3, sampleTransform(2)},
                                          TransformChange{4, sampleTransform(3)}, MaterialChange{3, sampleMaterial(1), {}},
                                          LightChange{3, sampleLight(1)}};
    EXPECT_TRUE(m.changes == expected);

    // Applying the merged update gives the state that applying them one by one gives.
    SceneDesc d = sampleScene();
    d.instances.resize(5, d.instances.front());
    d.materials.resize(4, d.materials.front());
    d.lights.resize(4, d.lights.front());
    const Sent sent = sentFor(d);
    SceneSnapshot one = snapshotOf(d, sent.meshes, sent.assets, 4), all = one;
    for (const Update& u : updates)
        for (const Change& c : u.changes) applyChange(one, c);
    for (const Change& c : m.changes) applyChange(all, c);
    EXPECT_TRUE(one == all);

    const Update taken = merged.take();
    EXPECT_EQ(taken.seq, 12u);
    EXPECT_TRUE(taken.changes == expected);
    EXPECT_TRUE(merged.empty());
    EXPECT_TRUE(merged.update().changes.empty());
    merged.add(update(13, TransformChange{0, sampleTransform(4)}));
    EXPECT_EQ(merged.update().baseSeq, 12u);
    EXPECT_EQ(merged.update().changes.size(), 1u);
}

// Material 0 gets a new texture (the change brings its file), material 1 then uses it too (the
// state holds it: its change brings nothing) and material 0 goes back to the old one. Merged,
// the last change to material 0 must still bring the file, or whoever applies the merged update
// (a joining client, the master's frame state) lacks a file that material 1 names.
TEST(SceneState, MergedUpdatesKeepEveryFileTheChangesBrought) {
    const SceneDesc d = sampleScene();
    const Sent sent = sentFor(d);
    const AssetRef fresh = refOf("tex/new.png", bytesOf("new"));
    Material textured = d.materials[0];
    textured.texture.file = fresh.path;
    Material alsoTextured = d.materials[1];
    alsoTextured.texture.file = fresh.path;
    MergedUpdate merged;
    uint32_t seq = 4;
    for (Change c : std::vector<Change>{MaterialChange{0, textured, {fresh}}, MaterialChange{1, alsoTextured, {}},
                                        MaterialChange{0, d.materials[0], {}}}) {
        Update u;
        u.baseSeq = seq;
        u.seq = ++seq;
        u.changes.push_back(std::move(c));
        merged.add(std::move(u));
    }
    SceneSnapshot one = snapshotOf(d, sent.meshes, sent.assets, 4), all = one;
    applyChange(one, MaterialChange{0, textured, {fresh}});
    applyChange(one, MaterialChange{1, alsoTextured, {}});
    applyChange(one, MaterialChange{0, d.materials[0], {}});
    for (const Change& c : merged.update().changes) applyChange(all, c);
    EXPECT_TRUE(one == all);
    ASSERT_EQ(merged.update().changes.size(), 2u);
    EXPECT_TRUE(std::get<MaterialChange>(merged.update().changes[0]).files == std::vector<AssetRef>{fresh});
}

TEST(SceneState, ASnapshotIsHashedFromTheBytesSent) {
    const SceneSnapshot snap = sampleSnapshot(17);
    Header h;
    h.session = 99;
    h.sceneVersion = 17;
    const EncodedSnapshot e = encodeSnapshot(h, snap);
    EXPECT_EQ(e.message, encodeMessage(h, snap));
    EXPECT_EQ(e.stateHash, stateHash(snap));
    SceneSnapshot other = snap;
    other.updateSeq = 18;
    EXPECT_EQ(encodeSnapshot(h, other).stateHash, e.stateHash) << "the sequence number is not part of the state";
    other.instances[0].transform.m[5] += 1e-9;
    EXPECT_NE(encodeSnapshot(h, other).stateHash, e.stateHash);
}

}  // namespace
}  // namespace rtwall::cluster

namespace rtwall::cluster {
namespace {

// An edited [denoise] is an edit of its own (the display side applies it; nothing is sent).
TEST(SceneState, ADenoiseEditIsTheDisplaysOwn) {
    const SceneDesc before = sampleScene();
    SceneDesc after = before;
    EXPECT_TRUE(diffScenes(before, after).empty());
    after.denoise.mode = DenoiseSettings::Mode::Temporal;
    after.denoise.levels = 4;
    const SceneEdit e = diffScenes(before, after);
    ASSERT_TRUE(e.denoise);
    EXPECT_EQ(*e.denoise, after.denoise);
    EXPECT_FALSE(e.empty());
    EXPECT_FALSE(e.settings) << "the render settings the clients get are unchanged";
}

}  // namespace
}  // namespace rtwall::cluster
