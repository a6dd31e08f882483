// rtwall engine: the one public header.
//
// A scene description (plain data, loaded from a TOML scene file or built in code) is turned
// into an Embree scene once; renderTile() then renders any rectangle of the image from it.
// renderTile() is the one tile-render function: the single-machine path, the render clients,
// the tests and the benchmarks all call it. It is stateless apart from per-thread scratch
// buffers and deterministic: a pixel's bytes depend only on the scene, the camera, the
// settings and the pixel, never on the tile size, the tile order, the thread count or the
// kernel (packet or single-ray).
#pragma once

#include <rtwall/camera.h>
#include <rtwall/image.h>
#include <rtwall/mesh.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rtwall {

using Color = Float3;  // linear RGB

// Row-major 3x4 affine transform (object to world), kept in double precision on the CPU side.
struct Transform {
    std::array<double, 12> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

    static Transform translate(double x, double y, double z);
    static Transform scale(double x, double y, double z);
    static Transform rotateDegrees(double axisX, double axisY, double axisZ, double degrees);
    Transform operator*(const Transform& b) const;  // apply b first, then *this
    Float3 applyPoint(const Float3& p) const;
    bool operator==(const Transform&) const = default;
};

// Material kinds. Each is one class behind the MaterialModel interface (engine/src/material.h);
// adding one means a class, a factory line in materials.cpp and a name here.
enum class MaterialType { Lambert, Phong, Mirror, Glass, Metal, Emissive, Volume };

// A colour pattern (modulates `color`) or a mask (alpha), looked up at the hit's object-space
// position: meshes carry no texture coordinates, so (u, v) come from a projection: planar, or
// spherical / cylindrical around the object-space origin with y as the axis (docs/shading.md).
enum class TextureKind { None, Checker, Marble, Wood, Image };
// Uv: the mesh's own texture coordinates (interpolated at the hit). Auto (the default): Uv where
// the hit mesh has texture coordinates, PlanarXZ where it has none. Object is for bump_mapping
// only: the noise of the object-space position (what PlanarXZ etc. mean for a bump).
enum class TextureMapping { PlanarXZ, PlanarXY, PlanarYZ, Spherical, Cylindrical, Uv, Auto, Object };

enum class AlphaMode { Mask, Hashed };
enum class AlphaChannel { Red, Alpha };

struct TextureDesc {
    TextureKind kind = TextureKind::None;
    std::string file;                           // image: a PNG or JPEG, path as the renderer opens it
    Color color2{0.1f, 0.1f, 0.1f};             // checker: second colour; marble/wood: vein/ring colour
    float scale = 1.0f;                         // planar: object units per repeat (uv = position / scale);
                                                // spherical: fraction of the turn (u) and of pole-to-pole (v)
                                                // per repeat; cylindrical: of the turn (u), object units along y (v)
    TextureMapping mapping = TextureMapping::Auto;
    bool operator==(const TextureDesc&) const = default;
};

// A transfer function control point: scalar value -> colour and extinction (per object unit).
struct TransferPoint {
    float value = 0.0f;
    Color color{1, 1, 1};
    float density = 0.0f;
    bool operator==(const TransferPoint&) const = default;
};

struct Material {
    std::string name;
    MaterialType type = MaterialType::Lambert;
    Color color{0.8f, 0.8f, 0.8f};     // diffuse albedo (lambert, phong); reflectance (mirror, metal); tint (glass)
    Color specular{0.0f, 0.0f, 0.0f};  // phong: specular reflectance
    float shininess = 32.0f;           // phong: Blinn-Phong exponent
    float ior = 1.5f;                  // glass: index of refraction
    float roughness = 0.0f;            // metal: 0 = mirror, 1 = very rough (Phong lobe of exponent 2/r^2 - 2)
    Color absorption{0, 0, 0};         // glass: Beer-Lambert absorption coefficient per world unit of path inside
    Color emission{0, 0, 0};           // emissive: radiance leaving the surface (any material may add it)
    bool twoSided = false;             // emission leaves both sides (default: the front only, where the
                                       // triangle's winding faces, as area lights emit to one side)
    TextureDesc texture;               // modulates `color`
    float bump = 0.0f;                 // bump mapping: amplitude of the noise height field (0 = off)
    float bumpScale = 0.1f;            // bump mapping: feature size in object units (in (u, v) units with Uv)
    TextureMapping bumpMapping = TextureMapping::Auto;  // Object: noise of the object-space position;
                                                        // Uv: noise of (u, v), tangent frame dP/du, dP/dv;
                                                        // Auto: Uv where the mesh has texture coordinates
    TextureDesc alpha;                 // alpha mask: red channel / pattern below `alphaCutoff` is a hole
    float alphaCutoff = 0.5f;
    // What the mask reads and how: the surface's alpha is opacity x the mask (its red channel, or
    // the image's alpha channel with AlphaChannel::Alpha; 1 without a mask). Mask: a hole where
    // the alpha is below alphaCutoff. Hashed (glTF's BLEND): every ray keeps a hit with
    // probability alpha, decided by a hash of the ray and the triangle, so images stay
    // deterministic and converge to alpha blending as samples accumulate.
    AlphaMode alphaMode = AlphaMode::Mask;
    AlphaChannel alphaChannel = AlphaChannel::Red;
    float opacity = 1.0f;
    std::string volumeFile;            // volume: VTK image data (.vti, or legacy .vtk structured points)
    std::vector<TransferPoint> transfer;  // volume: transfer function, sorted by value
    float volumeStep = 0.5f;           // volume: ray-march step in voxels (speed/accuracy control)
    bool operator==(const Material&) const = default;
};
enum class LightType { Point, Directional, Area };

struct Light {
    LightType type = LightType::Point;
    Float3 position{0, 10, 0};   // point
    Float3 direction{0, -1, 0};  // directional: the direction the light travels
    Color color{1, 1, 1};
    float intensity = 1.0f;  // point: radiant intensity (falls off as 1/r^2); directional: irradiance;
                             // area: radiance
    Float3 edge1{1, 0, 0};   // area: a parallelogram at `position` spanned by edge1 and edge2; it emits
    Float3 edge2{0, 0, 1};   //   to the side of cross(edge1, edge2) only
    bool twoSided = false;   // area: emits to both sides
    bool operator==(const Light&) const = default;
};

// The camera turned `degrees` about the vertical axis through its look-at point (a demo's and a
// benchmark's orbit): position moves, look-at, up and field of view stay.
CameraDesc orbitCamera(const CameraDesc& camera, double degrees);

struct MeshDesc {
    std::string name;
    std::string source;  // file path or "shape:<kind>", for messages and hashing
    std::shared_ptr<const TriangleMesh> mesh;
};

// How an instance is shown (design reviews: hide, isolate and highlight parts, docs/design-review.md, "Parts").
// Hidden: not in the scene at all (no pixels, no shadow, no reflection, not picked).
// Highlighted: its surface colour is multiplied by kHighlightTint and it glows with
// kHighlightGlow, so it stands out lit or in shadow, whatever its material.
enum class Visibility : uint8_t { Shown = 0, Hidden = 1, Highlighted = 2 };
inline constexpr Float3 kHighlightTint{1.0f, 0.55f, 0.12f};
inline constexpr Float3 kHighlightGlow{0.30f, 0.14f, 0.02f};

struct InstanceDesc {
    uint32_t mesh = 0;      // index into SceneDesc::meshes
    uint32_t material = 0;  // index into SceneDesc::materials
    Transform transform;
    int32_t part = -1;      // index into SceneDesc::parts (assembly files), -1: none; kept by
                            // the master only, render clients need no names
    Visibility visibility = Visibility::Shown;
    // Kept in the small top level of moving instances from the start (issue 29; the scene
    // file's `movable = true`): moving it never rebuilds the static rest. Images are the same.
    bool movable = false;
    bool operator==(const InstanceDesc&) const = default;
};

// A node of an imported assembly's tree (glTF node, STEP assembly or part): what `rtwall info`
// lists and what picking names.
struct PartDesc {
    std::string name;
    int32_t parent = -1;  // index into SceneDesc::parts; -1 for a root
    bool operator==(const PartDesc&) const = default;
};

enum class KernelType { Packet, Single };
enum class ShadingMode { Full, EyeLight };
// What a pixel shows: the shaded image or a false-colour view of how it was made.
enum class ViewMode { Shaded, Depth, Rays, TileTime, Client };

struct RenderSettings {
    int width = 800;                      // image size in pixels
    int height = 600;
    int tileSize = 32;                    // square tiles, in pixels
    KernelType kernel = KernelType::Packet;
    ShadingMode shading = ShadingMode::Full;  // eyelight: primary rays only, for fast previews
    int maxDepth = 8;                     // primary ray = depth 1; reflection/refraction add one each
    int supersample = 1;                  // n x n regular sub-pixel grid
    bool shadows = true;                  // hard shadows from every light
    Color background{0.05f, 0.05f, 0.08f};
    Color ambient{0.0f, 0.0f, 0.0f};      // constant ambient light, times diffuse albedo
    int threads = 0;                      // 0 = one per hardware thread
    float pruneThreshold = 0.002f;        // drop rays whose throughput to the pixel is below this (0 = never)
    bool gi = false;                      // path tracing: indirect light by cosine-sampled bounces
    int samples = 1;                      // random samples per pixel sample and frame (GI, glossy, area lights)
    ViewMode view = ViewMode::Shaded;
    bool operator==(const RenderSettings&) const = default;
};

struct InjectedTileFault;  // a test hook: rtwall/engine_testing.h

// How this process traces, as opposed to what the image shows (RenderSettings): these never
// travel to a render client (each has its own) and never change a shaded pixel's bytes; only
// the client false-colour view shows clientId.
struct TraceOptions {
    // Rays per Embree packet (the packet kernel, and the primary-ray blocks of both kernels): 0 =
    // this CPU's widest (packetWidth()), or 4, 8 or 16 forced. Every width gives the same bytes.
    int packetWidth = 0;
    uint32_t clientId = 0;                     // the id the master gave this render client: the client view's colour
    std::shared_ptr<const InjectedTileFault> fault;  // null outside tests (rtwall/engine_testing.h)
};

// How each mesh's BVH is built ([bvh] in scene files): memory against build and render speed.
struct BvhSettings {
    enum class Quality { Low, Medium, High };
    Quality quality = Quality::Medium;  // Embree build quality (high: spatial splits, slower builds)
    bool compact = false;               // RTC_SCENE_FLAG_COMPACT: smaller BVH, slower traversal
    bool robust = false;                // RTC_SCENE_FLAG_ROBUST: exact traversal (thin, far triangles)
    // What Embree is given: Auto hands it quads (RTC_GEOMETRY_TYPE_QUAD) for the consecutive
    // triangle pairs (2k, 2k+1) that share an edge, the rest as triangles (a smaller BVH with
    // half the leaves); Triangles hands it every triangle as it is.
    enum class Primitives { Auto, Triangles };
    Primitives primitives = Primitives::Auto;
    bool operator==(const BvhSettings&) const = default;
};

// A section plane ([[section]] in scene files, issue 20): geometry on the side its normal points
// away from is cut off for every ray (camera, shadow, reflection, refraction, GI), and where the
// plane cuts through a closed part the cut shows a cap: an opaque Lambert surface of `capColor`
// facing the cut-away side. Coordinates are the scene's (relative to SceneDesc::origin, like
// lights). Up to kMaxSections; a point is kept when it lies on the kept side of every enabled one.
struct SectionPlane {
    bool enabled = false;
    Float3 point{0, 0, 0};            // a point on the plane
    Float3 normal{1, 0, 0};           // towards the kept side; non-zero (the engine normalises it)
    Color capColor{0.8f, 0.1f, 0.1f}; // linear RGB of the cap
    bool caps = true;                 // false: the cut stays open (insides are seen)
    bool operator==(const SectionPlane&) const = default;
};
// The denoiser of stochastic frames (issue 28; the filter is rtwall/denoise.h in engine/frame,
// run on the display side after assembly): what the scene file's [denoise] table and
// `--denoise` set. Off: frames of a still view are averaged as ever (Accumulator), bit for bit.
struct DenoiseSettings {
    enum class Mode { Off, Temporal, Svgf };
    // Temporal: each pixel's history re-projected from the frames before and averaged with the
    // new frame. Svgf: that, then an edge-avoiding a-trous wavelet filter of the illumination.
    Mode mode = Mode::Off;
    int levels = 5;                 // a-trous iterations (svgf), 1..10: the filter reaches 2^levels pixels
    int history = 32;               // the most frames a moving view's pixel averages (alpha >= 1/history); still views: all
    float sigmaDepth = 1.0f;        // edge stops: depth (times the local depth gradient), ...
    float sigmaNormal = 128.0f;     // ... normal (the cosine's exponent) ...
    float sigmaLuminance = 4.0f;    // ... and luminance (times the noise's standard deviation)
    bool operator==(const DenoiseSettings&) const = default;
};
// "off", "temporal", "svgf"; anything else is an InputError naming them.
DenoiseSettings::Mode denoiseModeFromName(const std::string& name);
const char* denoiseModeName(DenoiseSettings::Mode mode);

inline constexpr int kMaxSections = 6;
using SectionPlanes = std::array<SectionPlane, kMaxSections>;

struct SceneDesc {
    std::filesystem::path sourceFile;  // empty when built in code
    // Where this description's coordinate origin lies in the scene file's world, in double
    // precision. Scenes far from the world origin are rebased on load: instance transforms,
    // cameras and lights are stored relative to it, so the single-precision data Embree and the
    // kernel see stays small and exact. {0,0,0} for scenes near the origin.
    std::array<double, 3> origin{0, 0, 0};
    BvhSettings bvh;
    std::vector<MeshDesc> meshes;
    std::vector<Material> materials;
    std::vector<InstanceDesc> instances;
    std::vector<PartDesc> parts;  // assembly files: the node tree, parents first; empty otherwise
    std::vector<Light> lights;
    std::vector<CameraDesc> cameras;
    RenderSettings settings;
    DenoiseSettings denoise;  // the display side's: never sent to a render client
    SectionPlanes sections;  // slot i is plane i; disabled slots cut nothing
    // Contents of texture image and volume files by the path a material names: a path found
    // here is decoded from these bytes, not opened (a render client gets them from the master).
    std::map<std::string, std::shared_ptr<const std::vector<uint8_t>>> files;

    const CameraDesc* findCamera(const std::string& name) const;  // nullptr if absent
    // The part's names from its root down, joined by '/' ("engine/piston 2"); empty for -1.
    std::string partPath(int32_t part) const;
    Bounds3 worldBounds() const;
};

// Parts by name (hide, isolate, highlight). A pattern is matched against a part's path
// (SceneDesc::partPath, "engine/piston 2") when it contains a '/', else against its name; '*'
// stands for any run of characters (also '/'), everything else is literal. An instance is
// matched when its part or any ancestor of it is; an instance without a part (a scene file's own
// [[instance]]) is matched by its mesh's name.
bool globMatch(const std::string& pattern, const std::string& text);
std::vector<uint32_t> instancesMatching(const SceneDesc& scene, const std::string& pattern);

// What is hidden, isolated and highlighted, as patterns (scene file [parts], `--hide`, the wall's
// keys). Each instance's visibility: with any isolate pattern, the instances no isolate pattern
// matches are hidden; those a hide pattern matches are hidden; of the rest, those a highlight
// pattern matches are highlighted.
struct PartView {
    std::vector<std::string> hide, isolate, highlight;
    bool empty() const { return hide.empty() && isolate.empty() && highlight.empty(); }
    bool operator==(const PartView&) const = default;
};
// One visibility per instance. Throws InputError naming the first pattern that matches nothing.
std::vector<Visibility> visibilityOf(const SceneDesc& scene, const PartView& view);
// Hidden where either is, else highlighted where either is.
Visibility combineVisibility(Visibility a, Visibility b);
// Each instance's visibility combined with what `view` gives it (throws as visibilityOf, before
// changing anything): a scene file's [parts], then `--hide` etc. on top.
void applyPartView(SceneDesc& scene, const PartView& view);

// "shaded", "depth", "rays", "tile_time", "client"; anything else is an InputError.
ViewMode viewModeFromName(const std::string& name);

// Loads a TOML scene file (format: configs/README.md). Throws InputError naming the file, the
// line and the key on any problem, including unknown keys and wrong types.
SceneDesc loadSceneFile(const std::filesystem::path& file);

// What a scene load did, for benchmarks and progress reports.
struct SceneLoadStats {
    double importSeconds = 0;   // parsing mesh files (including writing caches)
    double cacheSeconds = 0;    // reading valid caches
    size_t cacheHits = 0, cacheWritten = 0, filesImported = 0;
};
struct SceneLoadOptions {
    ProgressFn progress;            // scene files: fraction of mesh bytes loaded; returning false cancels (Cancelled)
    std::optional<bool> cache;      // scene files: overrides the scene file's [load] cache
    SceneLoadStats* stats = nullptr;
    int64_t builtinTriangles = 3'000'000;  // builtin:NAME: about this many triangles
    // STEP/IGES files: the tessellation (AssemblyOptions); `cache` (off when unset) uses and writes
    // their assembly cache, `progress` follows the import (parse, transfer, tessellation).
    double linearDeflection = 0.1;   // file units (millimetres for most CAD files)
    double angularDeflection = 0.5;  // radians
    // A mesh or assembly file opened as the scene: shapes (assembly meshes, or the bodies of a mesh
    // file) that are the same up to a rigid motion are stored once (AssemblyOptions::shareCongruent,
    // shareCongruentBodies). Scene files say it in [import].
    bool shareCongruent = true;
};
SceneDesc loadSceneFile(const std::filesystem::path& file, const SceneLoadOptions& options);

// Writes a regular grid of scalars (`values`: nx * ny * nz, x fastest, at least 2 per axis) as
// ASCII VTK image data (.vti), which volume materials read; for generators and tests.
void writeVolumeVti(const std::filesystem::path& file, int nx, int ny, int nz, const std::vector<float>& values);

// A scene made of one mesh file, with a camera that frames its bounds and a default light. An
// assembly file (isAssemblyFile: glTF, STEP, IGES) becomes its meshes, each stored once, placed by
// its instances, with its materials and its part tree; a mesh file whose bodies repeat, its
// distinct bodies placed by instances (shareCongruentBodies).
SceneDesc sceneFromMeshFile(const std::filesystem::path& file);
SceneDesc sceneFromMeshFile(const std::filesystem::path& file, const SceneLoadOptions& options);
SceneDesc sceneFromAssembly(const Assembly& assembly, const std::filesystem::path& file);
// How an assembly's metallic-roughness material becomes an rtwall material (docs/assemblies.md, "Materials").
Material materialFromAssembly(const AssemblyMaterial& material);

// Scenes built in code, shared by tests, benchmarks and examples. "knots": twelve distinct
// torus knots on a floor with about `triangles` triangles in all (the kernel benchmark).
SceneDesc builtinScene(const std::string& name, int64_t triangles);

// What a scene name given to rtwall names: "builtin:NAME" a scene built in code, a name ending
// in .toml (any case) a scene file, anything else a mesh file (OBJ, PLY, VTK, ... any case).
enum class SceneSourceKind { Builtin, SceneFile, MeshFile };
SceneSourceKind sceneSourceKind(const std::string& nameOrPath);

// The one way every command loads a scene by name: builtinScene, loadSceneFile or
// sceneFromMeshFile, as sceneSourceKind says.
SceneDesc loadScene(const std::string& nameOrPath, const SceneLoadOptions& options = {});

// How an area light is seen by rays (engine/src/light_faces.cpp, configs/README.md [[light]]):
// not at all (next-event estimation alone finds it), through emitters that cover its whole
// parallelogram (Covered: light samples and hits on them are weighted by multiple importance
// sampling), or through emitters that cover part of it (Partial: light samples count in full,
// and so do hits on the emitters where no light sample could have found them).
enum class LightFace : uint8_t { None, Partial, Covered };

// A loaded scene ready to render: Embree device, one BVH per mesh, instances on top.
class Scene {
public:
    explicit Scene(const SceneDesc& desc);
    // With a BVH build progress report (fraction of triangles built); returning false stops the
    // build, which then throws Cancelled.
    Scene(const SceneDesc& desc, const ProgressFn& buildProgress);
    ~Scene();

    // Bytes Embree holds for BVHs and instances (its memory monitor), and the geometry buffers
    // of the unique meshes (shared with Embree, counted once).
    size_t embreeBytes() const;
    size_t embreeTopLevelBytes() const;  // the part for instances and the top-level BVH
    size_t geometryBytes() const;
    // What the mesh BVHs were built from ([bvh] primitives), over desc().meshes: triangle pairs
    // (2k, 2k+1), the pairs that share an edge, the quads Embree got (those read in place from the
    // meshes' own index arrays among them), the triangles it got as triangles, and the bytes of
    // the quad/triangle index buffers made for it (part of geometryBytes()).
    struct PrimitiveStats {
        size_t triangles = 0, pairs = 0, pairsSharingEdge = 0, quads = 0, quadsInPlace = 0, separateTriangles = 0;
        size_t quadIndexBytes = 0, meshesAsQuads = 0, meshesAsTriangles = 0;
    };
    PrimitiveStats primitiveStats() const;
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    const SceneDesc& desc() const;

    // Differential updates: they change what the next commit() publishes, without rebuilding
    // any mesh's BVH (a transform only refits the top level). Not safe while tiles render.
    void setInstanceTransform(uint32_t instance, const Transform& transform);  // throws std::out_of_range
    // Hides, shows or highlights an instance: a hidden one leaves the top level (the next commit
    // rebuilds it over the instances, never a mesh's BVH). Throws std::out_of_range.
    void setInstanceVisibility(uint32_t instance, Visibility visibility);
    void setMaterial(uint32_t material, const Material& value);
    // The contents of a file that materials set from now on may name (as SceneDesc::files): a
    // render client gets them from the master by hash.
    void addFile(const std::string& path, std::shared_ptr<const std::vector<uint8_t>> bytes);
    void setLight(uint32_t light, const Light& value);
    // O(1): no BVH or instance is touched, the kernel clips rays against the planes. Throws
    // std::out_of_range for a slot >= kMaxSections, std::invalid_argument for a plane that is not
    // finite or has a zero normal.
    void setSection(uint32_t index, const SectionPlane& plane);
    // Publishes the changes. Moved instances live in a small top level of their own, rebuilt by
    // each commit (microseconds); the static rest is rebuilt in the background when an instance
    // starts moving, and a later commit publishes it (never waiting for it). Images are the same
    // whichever level holds an instance.
    void commit();
    // Waits for a background rebuild of the static top level and publishes it (benchmarks, tests).
    void waitForRebuild();
    struct TopLevelState {
        size_t moving = 0;      // instances in the moving top level
        size_t stale = 0;       // static copies that rays skip until a rebuild publishes
        bool rebuilding = false;  // a rebuild in flight or done but not published
    };
    TopLevelState topLevelState() const;

    // What the scene recognised as the visible faces of its area lights, as of the last change:
    // per light (None for point and directional lights), and the area light an instance is the
    // visible face of (-1: none). Both throw std::out_of_range for an index that does not exist.
    LightFace lightFace(uint32_t light) const;
    int32_t areaLightOf(uint32_t instance) const;

    struct Impl;
    const Impl& impl() const { return *impl_; }

private:
    std::unique_ptr<Impl> impl_;
};

// A tile that could not be rendered. renderTile and renderTileLinear throw it for anything that
// goes wrong inside a tile (renderFrame and renderFrameLinear rethrow the first); what() is
// "frame F, tile x0,y0,x1,y1: reason". The caller knows where the scene and the camera came
// from and can add the command that renders just this tile (replayCommand).
class TileError : public std::runtime_error {
public:
    TileError(uint32_t frame, const TileRect& rect, const std::string& reason);
    uint32_t frame() const { return frame_; }
    const TileRect& rect() const { return rect_; }
    const std::string& reason() const { return reason_; }

private:
    uint32_t frame_;
    TileRect rect_;
    std::string reason_;
};

// Where renderTile writes: pixel (rect.x0 + i, rect.y0 + j) goes to data + j*stride + 3*i (sRGB8).
struct TileView {
    uint8_t* data = nullptr;
    size_t stride = 0;
};

// Depth with every tile (issue 27): a pixel's depth is the distance from the camera's origin to
// the surface its primary ray hits first, along that ray, in scene units (the nearest of its
// sub-pixel samples). Distance along the ray rather than eye-space z because it means the same
// for every camera, symmetric or off-axis, with no image plane to agree on: the warp puts the
// point back at origin() + normalize(direction(x + 0.5, y + 0.5)) * depth. (Not the ray-depth
// false-colour view, ViewMode::Depth, which counts bounces.)
// Pixels whose rays hit nothing show the background and get kBackgroundDepth (rtwall/camera.h).

// Where renderTile writes depth: pixel (rect.x0 + i, rect.y0 + j) goes to data[j*stride + i].
struct DepthView {
    float* data = nullptr;  // null: no depth (the colour path is exactly as without)
    size_t stride = 0;      // floats per row
};

// Feature buffers with a tile (issue 28): what an edge-avoiding denoiser needs of each pixel's
// first hit, the mean over the pixel's sub-pixel samples (each weighted as its colour is):
// - albedo: the reflectance the hit's material shows there (colour or texture times vertex
//   colour and highlight tint), linear RGB; a miss gives (1, 1, 1), so that the background's
//   "illumination" is its colour;
// - normal: the shading normal before bump mapping (interpolated vertex normals, else the
//   geometric one), world space, facing the ray: the geometry whose edges the filter keeps, not
//   a plaster's bumps, which vary from pixel to pixel like a texture; a miss gives (0, 0, 0);
// - id: of the pixel's first sample, the hit instance + 1 (0: a miss; a section plane's cap:
//   kCapFeatureId - plane).
// Depth goes with DepthView. Pixel (rect.x0 + i, rect.y0 + j) goes to albedo/normal
// [(j*stride + i)*3 ...] and id[j*stride + i]. Null pointers: that feature is not computed; all
// null, the colour path is exactly as without.
struct FeatureView {
    float* albedo = nullptr;
    float* normal = nullptr;
    uint32_t* id = nullptr;
    size_t stride = 0;  // pixels per row
    bool any() const { return albedo || normal || id; }
};
inline constexpr uint32_t kCapFeatureId = 0xFFFFFFFFu;

// Per-tile statistics for benchmarks and false-colour views.
struct TileStats {
    uint64_t rays = 0;        // closest-hit rays traced
    uint64_t shadowRays = 0;  // occlusion rays traced
};

// The one tile-render function. Random numbers (GI, glossy reflection, area lights, volume
// jitter) are a hash of the pixel's image coordinates, the frame and the sample, so a pixel's
// bytes never depend on which tile or client rendered it.
TileStats renderTile(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                     const RenderSettings& settings, TileView out, const TraceOptions& trace = {});
// The same, and each pixel's depth (kBackgroundDepth above) into `depth`. The colour bytes are
// those of the call without depth.
TileStats renderTile(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                     const RenderSettings& settings, TileView out, DepthView depth, const TraceOptions& trace = {});

// The same, in linear RGB floats (3 per pixel, `stride` floats per row), before quantisation:
// for tests of the estimators. False-colour views are not applied.
TileStats renderTileLinear(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                           const RenderSettings& settings, float* out, size_t stride, const TraceOptions& trace = {});
TileStats renderTileLinear(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                           const RenderSettings& settings, float* out, size_t stride, DepthView depth,
                           const TraceOptions& trace = {});
// The same with the denoiser's features (FeatureView); the colour and depth are those of the
// calls without.
TileStats renderTileLinear(const Scene& scene, const Camera& camera, const TileRect& rect, uint32_t frame,
                           const RenderSettings& settings, float* out, size_t stride, DepthView depth,
                           FeatureView features, const TraceOptions& trace = {});

// Everything that decides one tile's pixels, as `rtwall render` can be told it.
struct TileReplay {
    std::string scene;                      // as loadScene() was given it: builtin:NAME, a scene file or a mesh file
    int64_t builtinTriangles = 3'000'000;   // a builtin scene's SceneLoadOptions::builtinTriangles
    std::array<double, 3> origin{0, 0, 0};  // the loaded SceneDesc::origin: the camera goes in the file's coordinates
    CameraDesc camera;
    RenderSettings settings;
    TraceOptions trace;                     // the injected fault is not replayed
    uint32_t frame = 0;
    TileRect rect;
};

// The `rtwall render` command line that renders exactly these pixels of that tile again, alone:
// every setting that can change a pixel is spelled out (the scene file's [render] table may have
// been overridden), the camera by position, look-at point, up, field of view and projection
// window in the scene file's world coordinates, the frame's own random numbers (--frame), the
// kernel and the packet width. What it cannot carry: changes made to the scene after it was
// loaded (materials, lights, instance transforms moved on a running wall).
std::string replayCommand(const TileReplay& tile);

// Progressive refinement of a still view: the mean of the frames added since the last reset,
// in linear light (each sRGB8 frame is converted back exactly and summed in double). The
// cluster and one machine add the same bytes, so they give the same refined image.
class Accumulator {
public:
    void reset() { frames_ = 0; }
    void add(const Image& frame);  // a frame of another size resets first
    // A frame in linear RGB (3 floats a pixel, as renderTileLinear writes them), without the
    // 8-bit quantisation's bias. Each value is rounded to IEEE half precision (11 significant
    // bits) first: the precision the cluster sends accumulated tiles in, so that one machine and
    // the cluster sum the same values. Frames added with add() and addLinear() must not be mixed.
    void addLinear(const float* rgb, int width, int height);
    Image resolve() const;
    int frames() const { return frames_; }

private:
    int width_ = 0, height_ = 0, frames_ = 0;
    std::vector<double> sum_;
};

// IEEE 754 half precision (round to nearest even): the precision accumulated frames travel in.
uint16_t halfFromFloat(float v);
float floatFromHalf(uint16_t bits);
// The same for `count` values (F16C instructions where the CPU has them: identical results).
void halfFromFloat(const float* in, size_t count, uint16_t* out);
void floatFromHalf(const uint16_t* in, size_t count, float* out);

// The 8-bit sRGB quantisation renderTile applies, for `count` linear values.
void linearToSrgb8(const float* linear, size_t count, uint8_t* out);
// Its inverse for `count` 8-bit values: the linear value each code stands for (what
// Accumulator::add sums), exactly.
void srgb8ToLinear(const uint8_t* srgb, size_t count, float* out);

// True when a frame's pixels depend on the frame number, i.e. when averaging frames refines
// the image: path tracing, area lights, rough metal or a volume (per-frame random sampling) in
// the shaded view with full shading. Such frames also jitter their sub-pixel positions and draw
// their own pruning coins, so their mean converges to the box-filtered, unpruned image. A
// deterministic scene renders the same bytes every frame.
bool rendersStochastically(const SceneDesc& scene);

std::vector<TileRect> makeTiles(int width, int height, int tileSize);

// Renders a whole frame on settings.threads threads (tiles handed out on demand).
Image renderFrame(const Scene& scene, const Camera& camera, const RenderSettings& settings, uint32_t frame = 0,
                  TileStats* stats = nullptr, const TraceOptions& trace = {});
// A whole frame with its depth (width x height distances, rows top to bottom).
struct RenderedFrame {
    Image image;
    std::vector<float> depth;
};
RenderedFrame renderFrameWithDepth(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                                   uint32_t frame = 0, const TraceOptions& trace = {});
// The same frame in linear RGB floats (3 per pixel, rows of settings.width pixels), as
// renderTileLinear writes them: what Accumulator::addLinear averages.
std::vector<float> renderFrameLinear(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                                     uint32_t frame = 0, TileStats* stats = nullptr, const TraceOptions& trace = {});

// A whole frame in linear RGB with its depth and the denoiser's features (FeatureView), each
// width x height (times 3 for colour, albedo and normal), rows top to bottom.
struct FeatureFrame {
    std::vector<float> linear, depth, albedo, normal;
    std::vector<uint32_t> id;
};
FeatureFrame renderFrameFeatures(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                                 uint32_t frame = 0, TileStats* stats = nullptr, const TraceOptions& trace = {});

// Picking: the instance that the primary ray through image position (px, py) (pixels from the
// top-left corner) hits first, where, and how far along the ray (in units of the ray
// direction camera.direction(px, py)); nothing when the ray escapes.
struct PickResult {
    uint32_t instance = 0;  // index into SceneDesc::instances
    float t = 0;
    Float3 point;           // world space
};
std::optional<PickResult> pick(const Scene& scene, const Camera& camera, float px, float py);

// Number of rays per Embree packet the packet kernel uses on this CPU (4, 8 or 16) where
// TraceOptions::packetWidth is 0: 16 with AVX-512, 8 with AVX, else 4.
int packetWidth();

}  // namespace rtwall
