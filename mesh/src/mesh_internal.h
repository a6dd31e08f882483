// Helpers shared by the importers and the cache. Internal to rtwall_mesh.
#pragma once

#include "rtwall/mesh.h"

#include <array>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace rtwall::detail {

// A row-major 3x4 affine transform: an assembly node's placement as the importers build it.
using Affine = std::array<double, 12>;
// a after b (a * b): b's placement, then a's; the importers compose a node's world this way.
Affine composeAffine(const Affine& a, const Affine& b);

// The cache reader and the recentring step work on the buffers directly.
struct MeshAccess {
    static MeshArray<float>& positions(TriangleMesh& m) { return m.positions_; }
    static MeshArray<float>& normals(TriangleMesh& m) { return m.normals_; }
    static MeshArray<uint32_t>& indices(TriangleMesh& m) { return m.indices_; }
    static MeshArray<uint8_t>& colors(TriangleMesh& m) { return m.colors_; }
    static MeshArray<float>& uvs(TriangleMesh& m) { return m.uvs_; }
    static void setVertexCount(TriangleMesh& m, size_t n) { m.vertexCount_ = n; }
};

// The origin a mesh with these bounds is stored relative to: the centre of its bounds, rounded to
// a whole number so that the offset itself is exact, when the mesh lies further from its origin
// than its own size (and at least 1024 units); else {0,0,0}, which leaves meshes near their
// origin bit-for-bit as they were.
std::array<double, 3> chooseOrigin(const double lo[3], const double hi[3]);

// Recentres a mesh imported in float (the OpenMesh readers) by chooseOrigin's rule.
void recentre(TriangleMesh& mesh);

// True when the triangle has zero area in the float buffers.
bool zeroArea(const TriangleMesh& mesh, uint32_t a, uint32_t b, uint32_t c);

}  // namespace rtwall::detail

namespace rtwall::detail {

// The bytes of a cache file for `mesh` (cache.cpp); also how a VTK import returns its mesh from
// the child process it runs in.
std::vector<unsigned char> encodeMeshCache(const TriangleMesh& mesh, const ImportReport& report, uint64_t sourceSize,
                                           int64_t sourceMtime);

// Decodes and validates cache bytes (cache.cpp). With `keepAlive` (the owner of `data`, e.g. a
// mapping) on a little-endian host, the mesh's arrays are views of `data`; otherwise copies.
TriangleMesh decodeMeshCache(const unsigned char* data, size_t size, uint64_t sourceSize, int64_t sourceMtime,
                             const std::string& name, ImportReport* report, std::shared_ptr<const void> keepAlive);

// For importers that run in a forked child (child_io.cpp): writes all `n` bytes (false on an
// error), and makes a crash end the child by its signal, with no inherited handler and no core.
bool writeAll(int fd, const void* data, size_t n);
void dropInheritedCrashHandlers();

// Reads any supported mesh file, without a cache (import.cpp).
TriangleMesh importMesh(const std::filesystem::path& file, ImportReport* report);


// Meshes of `a` congruent to an earlier one (a rigid motion within tolerance x its bounding-box
// diagonal, normals too; never a mirror) are dropped and their instances place the earlier one
// through the motion (congruence.cpp). Returns how many meshes were dropped.
size_t shareCongruentMeshes(Assembly& a, double tolerance);

// Assembly importers (import_gltf.cpp, import_cad.cpp); loadAssembly (assembly.cpp) picks one.
Assembly importGltf(const std::filesystem::path& file);
// STEP and IGES (import_cad.cpp), in this process. OCCT's document application and static tables
// are shared, so imports take occtMutex() (`lock` false: the caller holds it, or is the child
// process forked while holding it).
std::mutex& occtMutex();
Assembly importCadHere(const std::filesystem::path& file, const AssemblyOptions& options, bool lock = true);

// Assembly caches (cache.cpp): what a cache must have been made from.
struct AssemblyKey {
    uint64_t hash = 0, size = 0;  // XXH3-64 and size of the source file's content
    double linearDeflection = 0, angularDeflection = 0;
};
std::filesystem::path assemblyCachePath(const std::filesystem::path& source, const std::filesystem::path& cacheDir);
uint64_t hashFileContent(const std::filesystem::path& file, uint64_t& size);
void writeAssemblyCache(const Assembly& assembly, const AssemblyKey& key, const std::filesystem::path& cacheFile);
// The bytes writeAssemblyCache writes; also how a STEP/IGES import returns its assembly from the
// child process it runs in.
std::vector<unsigned char> encodeAssemblyCache(const Assembly& assembly, const AssemblyKey& key);
// Writes encoded bytes as the cache file, atomically (a temporary file, then rename).
void writeAssemblyCacheBytes(const unsigned char* data, size_t size, const std::filesystem::path& cacheFile);
// Validated in full (checksum, counts, indices, every mesh as decodeMeshCache does); with
// `keepAlive` the meshes view `data`.
Assembly decodeAssemblyCache(const unsigned char* data, size_t size, const AssemblyKey& key, const std::string& name,
                             std::shared_ptr<const void> keepAlive);
std::optional<Assembly> readAssemblyCache(const std::filesystem::path& cacheFile, const AssemblyKey& key, std::string* whyNot);

// STEP and IGES as loadAssembly reads them (cad_child.cpp): importCadHere in a child process with
// a memory and a time limit, the result handed back as assembly-cache bytes for `key` (mapped,
// validated, and with `cacheFile` also written there). RTWALL_CAD_IN_PROCESS=1 imports here.
struct CadImport {
    Assembly assembly;
    std::string cacheError;  // with a cacheFile: why it was not written; empty when it was
};
CadImport importCad(const std::filesystem::path& file, const AssemblyOptions& options, const AssemblyKey& key,
                    const std::filesystem::path* cacheFile);

}  // namespace rtwall::detail
