// rtwall mesh library: the one public header.
//
// Importers read mesh files (through OpenMesh) straight into the flat buffers that the
// engine hands to Embree as shared buffers, so an imported model exists once in memory.
#pragma once

#include <rtwall/input_error.h>
#include <rtwall/vec.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rtwall {

namespace detail {
struct MeshAccess;  // the cache reader fills the buffers directly
}

struct Bounds3 {
    Float3 lo{+INFINITY, +INFINITY, +INFINITY};
    Float3 hi{-INFINITY, -INFINITY, -INFINITY};
    bool empty() const { return lo.x > hi.x; }
    void extend(const Float3& p);
};

// One array of a mesh, in the layout Embree reads: either owned (a vector) or a read-only view
// of memory that something else keeps alive (the pages of a mapped mesh cache), so a cached mesh
// is rendered where it lies instead of being copied. Either way kPad zero elements (16 bytes)
// follow the data, because Embree reads the last element with a 16-byte SIMD load. Writing to a
// view first copies it into owned storage. Any per-vertex or per-triangle array of TriangleMesh
// is one of these, so a further optional array is one more member, with nothing else to change.
template <class T>
class MeshArray {
public:
    static constexpr size_t kPad = 16 / sizeof(T);

    MeshArray() : owned_(kPad, T{}) {}
    const T* data() const { return view_ ? view_ : owned_.data(); }
    size_t size() const { return size_; }  // without the padding
    bool empty() const { return size_ == 0; }
    const T& operator[](size_t i) const { return data()[i]; }
    bool isView() const { return view_ != nullptr; }
    size_t heapBytes() const { return owned_.capacity() * sizeof(T); }             // owned storage
    size_t viewBytes() const { return view_ ? (size_ + kPad) * sizeof(T) : 0; }  // mapped storage

    T* mutableData() {
        makeOwned();
        return owned_.data();
    }
    void reserve(size_t n) {
        makeOwned();
        owned_.reserve(n + kPad);
    }
    void push_back(T v) {
        makeOwned();
        owned_.push_back(T{});  // the padding moves one element on
        owned_[size_++] = v;
    }
    // Takes `values` as the whole array (the padding is appended here).
    void assign(std::vector<T> values) {
        size_ = values.size();
        values.resize(size_ + kPad, T{});
        owned_ = std::move(values);
        view_ = nullptr;
        keepAlive_.reset();
    }
    // Uses n elements at `at` in place; at[n .. n + kPad) must be readable too. `keepAlive` owns
    // the memory (e.g. the mapping) and is released with the last array that uses it.
    void view(const T* at, size_t n, std::shared_ptr<const void> keepAlive) {
        owned_.clear();
        owned_.shrink_to_fit();
        view_ = at;
        size_ = n;
        keepAlive_ = std::move(keepAlive);
    }
    void clear() { assign({}); }
    void shrinkToFit() {
        if (!view_) owned_.shrink_to_fit();
    }

private:
    void makeOwned() {
        if (!view_) return;
        std::vector<T> copy(view_, view_ + size_ + kPad);
        owned_ = std::move(copy);
        view_ = nullptr;
        keepAlive_.reset();
    }

    std::vector<T> owned_;  // size_ + kPad elements when owned; empty when a view
    const T* view_ = nullptr;
    size_t size_ = 0;
    std::shared_ptr<const void> keepAlive_;
};

// Indexed triangle mesh in exactly the layout Embree reads: float3 positions (12-byte stride),
// uint32 triangle indices, each followed by 16 bytes of zero padding (MeshArray). Optional
// per-vertex normals use the same layout. Optional per-vertex colours are 8-bit sRGB-encoded RGB,
// 3 bytes per vertex, as the files store them (float colours are rounded to 8 bits); the renderer
// decodes them to linear and multiplies the material colour by their interpolation. Embree never
// reads the colours. Optional per-vertex texture coordinates are two floats (u, v) per vertex,
// kept only when the file gives them (OBJ vt, PLY u/v, s/t or texture_u/texture_v, OFF ST, VTK
// point TCoords, VRML TextureCoordinate); the renderer interpolates them for the "uv" texture
// mapping. Copying a mesh that views a mapping shares the mapping (the copy views the same pages).
class TriangleMesh {
public:
    size_t vertexCount() const { return vertexCount_; }
    size_t triangleCount() const { return indices_.size() / 3; }
    bool hasNormals() const { return !normals_.empty(); }
    bool hasColors() const { return !colors_.empty(); }
    bool hasUVs() const { return !uvs_.empty(); }

    const float* positions() const { return positions_.data(); }  // 3 floats per vertex
    const float* normals() const { return normals_.empty() ? nullptr : normals_.data(); }
    const uint32_t* indices() const { return indices_.data(); }  // 3 per triangle
    const uint8_t* colors() const { return colors_.empty() ? nullptr : colors_.data(); }  // 3 per vertex (RGB)
    const float* uvs() const { return uvs_.empty() ? nullptr : uvs_.data(); }  // 2 per vertex (u, v)

    Float3 position(size_t v) const { return {positions_[3 * v], positions_[3 * v + 1], positions_[3 * v + 2]}; }
    Float3 normal(size_t v) const { return {normals_[3 * v], normals_[3 * v + 1], normals_[3 * v + 2]}; }

    void reserve(size_t vertices, size_t triangles);
    uint32_t addVertex(const Float3& p);
    void setPosition(uint32_t v, const Float3& p);         // v must be < vertexCount()
    void addTriangle(uint32_t a, uint32_t b, uint32_t c);  // indices must already be valid
    void setNormals(std::vector<float> normalsXYZ);       // 3 per vertex (padding is added here)
    void setColors(std::vector<uint8_t> colorsRGB);       // 3 per vertex, or empty for none
    void setUVs(std::vector<float> uv);                   // 2 per vertex, all finite, or empty for none
    void shrinkToFit();                                   // drops spare capacity left by reserve

    Bounds3 bounds() const;        // of the float buffers, i.e. relative to origin()
    size_t residentBytes() const;  // bytes of the buffers: owned heap capacity plus mapped arrays
    size_t mappedBytes() const;    // the part of residentBytes() that is a view of a mapped file
    // True when the arrays are views of a mapping, not heap copies: a mesh loaded from its cache
    // (the cache file's pages) or read by VTK (the pages its reader process wrote).
    bool isMapped() const { return positions_.isView(); }

    // Where the buffers' origin lies in the file's coordinates, in double precision. CAD files
    // often place a model 1e5..1e6 units from their origin, where a float keeps only centimetres;
    // importers then store positions relative to the bounds' centre, and scenes put this offset
    // into the (double) instance transform. {0,0,0} for meshes near their origin.
    const std::array<double, 3>& origin() const { return origin_; }
    void setOrigin(const std::array<double, 3>& origin) { origin_ = origin; }

private:
    friend struct detail::MeshAccess;
    MeshArray<float> positions_;   // 3 per vertex
    MeshArray<float> normals_;     // empty, or 3 per vertex
    MeshArray<uint32_t> indices_;  // 3 per triangle
    MeshArray<uint8_t> colors_;    // empty, or 3 per vertex (RGB)
    MeshArray<float> uvs_;         // empty, or 2 per vertex (u, v)
    size_t vertexCount_ = 0;
    std::array<double, 3> origin_{0, 0, 0};
};

struct ImportReport {
    std::string format;               // "obj", "off", "ply", "stl", "om", "vtk", "vtp", "vtu", "wrl"
    size_t polygonsTriangulated = 0;  // faces with more than three corners: the sum of the next four
    size_t polygonsFanned = 0;        // strictly convex in their plane: a fan from the first corner
    size_t polygonsEarClipped = 0;    // concave or keyhole (a hole bridged to the outline), or with
                                      // repeated corners or collinear runs: ear-clipped in their plane
    size_t polygonsDegenerate = 0;    // no area at all (every corner on one line or point): fanned
                                      // into zero-area triangles, which degenerateTriangles counts
    size_t polygonsSelfIntersecting = 0;  // ear clipping ran out of ears because the boundary crosses
                                          // itself: what was left is fanned
    size_t degenerateTriangles = 0;   // zero-area triangles (kept, never hit, counted), plus faces
                                      // the OBJ and STL readers drop because corners repeat
    size_t stripsTriangulated = 0;    // VTK triangle strips turned into triangles
    size_t cellsSkipped = 0;          // VTK vertices and lines (nothing to render), counted
    std::string cache;                // loadMesh with a cache: "hit", "written", or "rebuilt: <why>"
    size_t seamVerticesSplit = 0;     // OBJ: vertices copied because their corners have different vt
    // Input accepted with a doubt, one line each naming the file and the place (e.g. a PLY header
    // line that is no PLY keyword). loadMesh also prints each to stderr, prefixed "warning: ".
    std::vector<std::string> warnings;
};

// Optional progress report for long steps: called with the fraction done in [0, 1]; returning
// false asks the step to stop, which it does by throwing Cancelled.
using ProgressFn = std::function<bool(double fraction)>;

class Cancelled : public std::runtime_error {
public:
    Cancelled() : std::runtime_error("cancelled") {}
};

struct LoadOptions {
    bool cache = false;              // use FILE's cache when it is current, else import and write one
    std::filesystem::path cacheDir;  // where caches live; empty: beside the file, as FILE.rtwcache
    ProgressFn progress;             // progress of writing a cache (large meshes); false cancels
};

// Reads OBJ, OFF, PLY (ASCII/binary), STL (ASCII/binary) and OM. The format is chosen from
// the extension and checked against the content. Throws InputError on any malformed input,
// naming the file and the place; never crashes, never hangs, never allocates much more than
// the file's size before the data has been validated. Polygons, in every format, become
// triangles by one routine: a fan where they are strictly convex, ear clipping in their plane
// where they are not (concave and keyhole polygons, repeated corners, collinear runs; OBJ faces
// keep the corners OpenMesh's reader would drop as repeats). ImportReport counts each kind. Vertex
// normals are kept, normalised, only when the file gives every vertex one. STL corners at the
// same position become one shared vertex, as in OpenMesh's reader, so an STL mesh is indexed
// like the others. Safe to call from several threads (the OpenMesh part runs one at a time).
//
// VTK formats go through VTK: legacy .vtk (polydata and unstructured grids, ASCII or binary),
// XML .vtp and .vtu (raw, base64 or compressed; an unstructured grid becomes its outer surface).
// The reader is chosen by content for VTK files (a legacy file named .vtp is read as legacy)
// and by extension otherwise. Meshes far from their file's origin are recentred (origin()).
// VRML 2.0 .wrl goes through VTK's VRML importer: every shape's polygons, in world coordinates
// (Transform nodes applied in double precision), with normals where every shape has them.
//
// Per-vertex colours are kept when the file gives every vertex one: PLY red/green/blue, OFF
// COFF, OBJ "v x y z r g b", VTK RGB(A) point scalars, VRML Color nodes and Material colours.
// Texture coordinates likewise, only when every vertex (OBJ: every face corner) has one. OBJ gives
// them per face corner: a vertex whose corners name different vt (a seam) is split into one
// vertex per distinct (u, v), each a copy of the position, normal and colour, and the split
// corners' triangles use the copies (ImportReport::seamVerticesSplit counts them). A NaN or
// infinite texture coordinate, or UVs on some vertices or corners only, is an InputError naming
// the file and the vertex or face.
TriangleMesh loadMesh(const std::filesystem::path& file, ImportReport* report = nullptr);
TriangleMesh loadMesh(const std::filesystem::path& file, const LoadOptions& options, ImportReport* report = nullptr);

// Mesh caches: a binary file that holds a mesh exactly as imported, mmap-able (every section
// 64-byte aligned), little-endian, versioned, with an XXH3-64 checksum over everything, and the
// size and modification time of the source it was made from. A cache that is stale, truncated,
// corrupt or from another version is never used. The cache's file name for a source file:
std::filesystem::path meshCachePath(const std::filesystem::path& source, const std::filesystem::path& cacheDir = {});
// Writes atomically (a temporary file, then rename).
void writeMeshCache(const TriangleMesh& mesh, const ImportReport& report, const std::filesystem::path& source,
                    const std::filesystem::path& cacheFile, const ProgressFn& progress = {});
// The mesh in a cache file if the cache is valid and matches `source` as it is now; otherwise
// nothing, with the reason in *whyNot. Never throws for a bad cache file. The whole file is
// validated (checksum, counts, finite coordinates, index range) before the mesh is returned; on
// a little-endian host the mesh's arrays are then views of the mapped file (isMapped()), which
// the mesh keeps mapped for as long as it or a copy of it lives. The cache is replaced by
// rename, never rewritten in place, so a mapped cache's pages cannot change under a renderer.
std::optional<TriangleMesh> readMeshCache(const std::filesystem::path& cacheFile, const std::filesystem::path& source,
                                          ImportReport* report = nullptr, std::string* whyNot = nullptr);
// The decoder behind readMeshCache, on bytes in memory (for the fuzz target). `sourceSize` and
// `sourceMtime` are what the cache must have been made from. Throws InputError naming `name`.
// The mesh returned owns copies of the arrays.
TriangleMesh decodeMeshCache(const unsigned char* data, size_t size, uint64_t sourceSize, int64_t sourceMtime,
                             const std::string& name, ImportReport* report = nullptr);

// Assemblies: files that place meshes by a node tree rather than hold one mesh. glTF 2.0
// (.gltf, .glb) and STEP (.step, .stp) / IGES (.iges, .igs) are read as assemblies: every mesh
// is stored once and placed by as many instances as the file uses it (the engine's scene loader
// turns them into instances that share one BVH).

// A material as the file describes it, in glTF's metallic-roughness terms (STEP colours fill
// baseColor; the rest keeps its defaults). The engine maps it onto its own material kinds.
struct AssemblyMaterial {
    std::string name;
    std::array<float, 4> baseColor{1, 1, 1, 1};  // linear RGBA
    float metallic = 0.0f;                        // 0 dielectric .. 1 metal
    float roughness = 0.5f;                       // 0 smooth .. 1 rough
    std::array<float, 3> emissive{0, 0, 0};       // linear RGB radiance
    float transmission = 0.0f;                    // KHR_materials_transmission: 0 opaque .. 1 clear
    float ior = 1.5f;                             // KHR_materials_ior
    std::string baseColorTexture;                 // key into Assembly::files (a PNG or JPEG); empty: none
    // glTF's alphaMode: Opaque ignores alpha; Mask cuts holes where alpha (baseColor[3] times the
    // texture's alpha) is below alphaCutoff; Blend is partly transparent.
    enum class Alpha { Opaque, Mask, Blend } alphaMode = Alpha::Opaque;
    float alphaCutoff = 0.5f;
    bool doubleSided = false;  // glTF: both sides are the surface (emission leaves both)
};

// A node of the assembly tree: a glTF node, a STEP assembly, part or part occurrence.
struct AssemblyPart {
    std::string name;     // the file's name for it, or "<kind> <index>" where it has none
    int32_t parent = -1;  // index into Assembly::parts; -1 for a root
};

struct AssemblyInstance {
    uint32_t mesh = 0;      // index into Assembly::meshes
    uint32_t material = 0;  // index into Assembly::materials
    uint32_t part = 0;      // the node it belongs to (index into Assembly::parts)
    std::array<double, 12> transform{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};  // row-major 3x4, mesh to world,
                                                                           // the mesh's origin() included
};

struct Assembly {
    std::string format;  // "gltf", "glb", "step", "iges"
    std::vector<std::shared_ptr<const TriangleMesh>> meshes;  // each stored once
    std::vector<std::string> meshNames;                       // one per mesh
    std::vector<AssemblyMaterial> materials;
    std::vector<AssemblyPart> parts;  // parents come before their children
    std::vector<AssemblyInstance> instances;
    // Texture images by the key a material names ("<file>#image<N>"): the bytes as the file holds them.
    std::map<std::string, std::shared_ptr<const std::vector<uint8_t>>> files;
    std::vector<std::string> warnings;  // one line each, naming the file
    std::string cache;                  // with AssemblyOptions::cache: "hit", "written", "rebuilt: <why>"
                                        // or "not written: <why>"; empty without
    size_t congruentMeshes = 0;         // meshes found congruent to another and stored once
                                        // (AssemblyOptions::shareCongruent)
    std::string reader;                 // STEP/IGES, imported (not cached): "direct" (STEP's own
                                        // structure reader), "xde" (IGES) or "xde: <why not direct>"
};

struct AssemblyOptions {
    // STEP/IGES tessellation (BRepMesh_IncrementalMesh): the largest distance between a surface and
    // its triangles, in the file's units, and the largest angle between neighbouring triangles.
    double linearDeflection = 0.1;
    double angularDeflection = 0.5;  // radians
    // STEP/IGES: use the file's cache when it is current, else write one. The cache (FILE.rtwasm,
    // or in cacheDir) holds the tessellated parts as mesh caches, mapped in place on a hit, and
    // the assembly around them; it is keyed by the file's content (XXH3-64, size) and the two
    // deflections, checksummed and validated in full before use, replaced by rename.
    bool cache = false;
    std::filesystem::path cacheDir;  // empty: beside the file
    ProgressFn progress;             // STEP/IGES: fraction of the import (parse, transfer, tessellation); false cancels (Cancelled)
    // Meshes that are the same shape up to a rigid motion (the same vertices, texture
    // coordinates and colours, in any numbering; every vertex within congruenceTolerance x the
    // shape's bounding-box diagonal, every normal within 1e-3; the same triangles or a planar
    // retriangulation) are stored once, whatever the file says; a chiral shape's mirror image is
    // not merged. Applied to every format, cached or not.
    bool shareCongruent = true;
    double congruenceTolerance = 1e-5;
    // STEP: read the product structure through OCCT's XDE document even where rtwall's direct
    // reader could (the same assembly; XDE's transfer grows as occurrences x uses of a product).
    bool stepThroughXde = false;
};

// True for the extensions read as assemblies (any case).
bool isAssemblyFile(const std::filesystem::path& file);
// Reads an assembly. Throws InputError (one line naming the file and what is wrong) on any
// malformed input: bad JSON or GLB framing, an accessor or buffer view outside its buffer, an
// index out of range, a missing external buffer or image, a node tree with a cycle; never
// allocates much more than the file and the buffers it names hold.
Assembly loadAssembly(const std::filesystem::path& file, const AssemblyOptions& options = {});
// A mesh file that holds many bodies (triangles joined through shared vertices; a plant exported
// as one OBJ, PLY or STL): bodies that are the same shape up to a rigid motion (the test of
// AssemblyOptions::shareCongruent, at `tolerance`) are stored once and placed by instances; the
// bodies without a copy stay together in one mesh, placed first. With no two bodies congruent,
// one body, or a soup of unconnected triangles (under 4 triangles a body), the assembly is the
// mesh as given, one instance (congruentMeshes 0). Parts: one, `name`; format "mesh".
Assembly shareCongruentBodies(std::shared_ptr<const TriangleMesh> mesh, const std::string& name, double tolerance = 1e-5);
// glTF from memory (the fuzz target): JSON or GLB by content; external files are not read
// (a URI other than a data: URI is an InputError naming `name`).
Assembly decodeGltf(const unsigned char* data, size_t size, const std::string& name);

// Procedural shapes for scenes, tests and benchmarks, wound counter-clockwise seen from
// outside. Sizes out of range throw std::invalid_argument.
TriangleMesh makeSphere(int rings, int segments);                 // unit sphere at the origin, with normals;
                                                                  // rings >= 2, segments >= 3
TriangleMesh makeBox();                                           // [-1,1]^3, 12 triangles
TriangleMesh makeQuad();                                          // [-1,1]^2 in the xz-plane, normal +y
// A tube of tubeRadius, with normals, around a (p,q) torus knot that lies within the unit ball.
TriangleMesh makeTorusKnot(int p, int q, int segments, int sides, float tubeRadius);

}  // namespace rtwall
