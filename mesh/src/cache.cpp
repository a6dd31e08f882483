// Mesh caches: an imported mesh as one binary file that loads without parsing.
//
// Layout (every integer and float little-endian, whatever the host):
//   0   char[8]  magic "RTWMESH\0"
//   8   u32      format version (kCacheVersion; bumped whenever the layout or an importer's
//                output changes, so an old cache is rebuilt rather than misread)
//   12  u32      header size (192)
//   16  u64      source file size in bytes
//   24  i64      source modification time, nanoseconds since the epoch
//   32  u64      vertex count V
//   40  u64      triangle count T
//   48  u32      flags: bit 0 = vertex normals, bit 1 = vertex colours, bit 2 = texture coordinates
//   52  u32      zero
//   56  f64[3]   mesh origin (TriangleMesh::origin)
//   80  u64[4]   import report: polygons triangulated, degenerate triangles, strips, cells skipped
//   112 char[8]  import format name, zero-padded
//   120 u64      XXH3-64 of the whole file with these 8 bytes taken as zero
//   128 u64[5]   import report (version 5): polygons fanned, ear-clipped, degenerate and
//                self-intersecting, OBJ seam vertices split
//   168 u8[24]   zero
//   192 f32[3V]   positions, then zeros: at least 16 bytes (Embree's SIMD loads read past the
//                 last element), up to a multiple of 64
//       f32[3V]   normals, if flagged, padded likewise
//       u32[3T]   triangle indices, padded likewise
//       u8[3V]    vertex colours (sRGB-encoded RGB), if flagged, then at least 16 zero bytes, up
//                 to a multiple of 64 (version 3)
//       f32[2V]   texture coordinates (u, v per vertex), if flagged, then at least 16 zero bytes,
//                 up to a multiple of 64 (version 4)
// The file size must be exactly what the counts give. Sections start on 64-byte boundaries, so
// in a mapping (page-aligned) every array is 64-byte aligned, and the arrays are used in place:
// a mesh read from its cache is a view of the mapped file (MeshArray), the buffers Embree reads.
// Version 1 had only 4 bytes of padding after the positions and none after the indices, so its
// arrays could not be handed to Embree in place; version 2 had no colours, version 3 no texture
// coordinates, version 4 fanned concave polygons (a 128-byte header without their counts). All
// are rebuilt.
#include "cache_io.h"
#include "mesh_internal.h"

#include <xxhash.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <type_traits>

namespace rtwall {

namespace {

namespace fs = std::filesystem;
using detail::MeshAccess;
using namespace detail::cacheio;

constexpr char kMagic[8] = {'R', 'T', 'W', 'M', 'E', 'S', 'H', 0};
constexpr uint32_t kCacheVersion = 5;
constexpr size_t kHeaderSize = 192;
constexpr size_t kChecksumAt = 120;

// Bytes of a section of n 4-byte values: the values, 16 bytes of zeros, rounded up to 64.
constexpr size_t sectionBytes(size_t n) { return align64(4 * n + 16); }

struct SourceStamp {
    uint64_t size = 0;
    int64_t mtimeNs = 0;
};

bool stampOf(const fs::path& source, SourceStamp& out) {
    struct stat st {};
    if (::stat(source.c_str(), &st) != 0) return false;
    out.size = uint64_t(st.st_size);
    out.mtimeNs = int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
    return true;
}

uint64_t checksum(const unsigned char* data, size_t size) { return checksumAt(data, size, kChecksumAt); }

}  // namespace

fs::path meshCachePath(const fs::path& source, const fs::path& cacheDir) {
    if (cacheDir.empty()) return fs::path(source.string() + ".rtwcache");
    // Caches of files from different folders share the directory: the absolute path's hash
    // keeps them apart.
    std::error_code ec;
    const std::string key = fs::absolute(source, ec).lexically_normal().string();
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(XXH3_64bits(key.data(), key.size())));
    return cacheDir / (source.filename().string() + "." + hex + ".rtwcache");
}

namespace detail {

std::vector<unsigned char> encodeMeshCache(const TriangleMesh& mesh, const ImportReport& report, uint64_t sourceSize,
                                           int64_t sourceMtime) {
    const size_t V = mesh.vertexCount(), T = mesh.triangleCount();
    const size_t posBytes = sectionBytes(3 * V);
    const size_t nrmBytes = mesh.hasNormals() ? sectionBytes(3 * V) : 0;
    const size_t idxBytes = sectionBytes(3 * T);
    const size_t colBytes = mesh.hasColors() ? align64(3 * V + 16) : 0;
    const size_t uvBytes = mesh.hasUVs() ? sectionBytes(2 * V) : 0;
    const size_t total = kHeaderSize + posBytes + nrmBytes + idxBytes + colBytes + uvBytes;

    std::vector<unsigned char> bytes(total, 0);
    unsigned char* h = bytes.data();
    std::memcpy(h, kMagic, 8);
    putLE<uint32_t>(h + 8, kCacheVersion);
    putLE<uint32_t>(h + 12, uint32_t(kHeaderSize));
    putLE<uint64_t>(h + 16, sourceSize);
    putLE<int64_t>(h + 24, sourceMtime);
    putLE<uint64_t>(h + 32, V);
    putLE<uint64_t>(h + 40, T);
    putLE<uint32_t>(h + 48, (mesh.hasNormals() ? 1u : 0u) | (mesh.hasColors() ? 2u : 0u) | (mesh.hasUVs() ? 4u : 0u));
    for (int k = 0; k < 3; ++k) putLE<double>(h + 56 + 8 * k, mesh.origin()[size_t(k)]);
    putLE<uint64_t>(h + 80, report.polygonsTriangulated);
    putLE<uint64_t>(h + 88, report.degenerateTriangles);
    putLE<uint64_t>(h + 96, report.stripsTriangulated);
    putLE<uint64_t>(h + 104, report.cellsSkipped);
    std::memcpy(h + 112, report.format.data(), std::min<size_t>(report.format.size(), 8));
    putLE<uint64_t>(h + 128, report.polygonsFanned);
    putLE<uint64_t>(h + 136, report.polygonsEarClipped);
    putLE<uint64_t>(h + 144, report.polygonsDegenerate);
    putLE<uint64_t>(h + 152, report.polygonsSelfIntersecting);
    putLE<uint64_t>(h + 160, report.seamVerticesSplit);
    size_t at = kHeaderSize;
    copyArrayLE(h + at, mesh.positions(), 3 * V);
    at += posBytes;
    if (mesh.hasNormals()) {
        copyArrayLE(h + at, mesh.normals(), 3 * V);
        at += nrmBytes;
    }
    copyArrayLE(h + at, mesh.indices(), 3 * T);
    at += idxBytes;
    if (mesh.hasColors()) {
        std::memcpy(h + at, mesh.colors(), 3 * V);
        at += colBytes;
    }
    if (mesh.hasUVs()) copyArrayLE(h + at, mesh.uvs(), 2 * V);
    putLE<uint64_t>(h + kChecksumAt, checksum(h, total));
    return bytes;
}

}  // namespace detail

void writeMeshCache(const TriangleMesh& mesh, const ImportReport& report, const fs::path& source,
                    const fs::path& cacheFile, const ProgressFn& progress) {
    SourceStamp stamp;
    if (!stampOf(source, stamp)) throw InputError(source.string() + ": cannot stat the source of a cache");
    const std::vector<unsigned char> bytes = detail::encodeMeshCache(mesh, report, stamp.size, stamp.mtimeNs);
    const unsigned char* h = bytes.data();
    const size_t total = bytes.size();

    const fs::path tmp = cacheFile.string() + ".tmp." + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw InputError(cacheFile.string() + ": cannot write the cache: " + std::strerror(errno));
        constexpr size_t kChunk = size_t(16) << 20;
        for (size_t done = 0; done < total; done += kChunk) {
            out.write(reinterpret_cast<const char*>(h + done), std::streamsize(std::min(kChunk, total - done)));
            if (progress && !progress(double(done) / double(total))) {
                out.close();
                fs::remove(tmp);
                throw Cancelled();
            }
        }
        out.flush();
        if (!out) {
            out.close();
            std::error_code ec;
            fs::remove(tmp, ec);
            throw InputError(cacheFile.string() + ": cannot write the cache (disk full?)");
        }
    }
    std::error_code ec;
    fs::rename(tmp, cacheFile, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw InputError(cacheFile.string() + ": cannot write the cache: " + ec.message());
    }
    if (progress) progress(1.0);
}

namespace detail {

TriangleMesh decodeMeshCache(const unsigned char* data, size_t size, uint64_t sourceSize, int64_t sourceMtime,
                             const std::string& name, ImportReport* report, std::shared_ptr<const void> keepAlive) {
    auto bad = [&](size_t offset, const std::string& what) -> InputError {
        return InputError(name + ":offset " + std::to_string(offset) + ": " + what);
    };
    if (size < kHeaderSize) throw bad(size, "truncated: " + std::to_string(size) + " bytes, shorter than the header");
    if (std::memcmp(data, kMagic, 8) != 0) throw bad(0, "not an rtwall mesh cache");
    const uint32_t version = getLE<uint32_t>(data + 8);
    if (version != kCacheVersion)
        throw bad(8, "cache version " + std::to_string(version) + ", this rtwall reads version " + std::to_string(kCacheVersion));
    if (getLE<uint32_t>(data + 12) != kHeaderSize) throw bad(12, "unexpected header size");
    if (getLE<uint64_t>(data + 16) != sourceSize || getLE<int64_t>(data + 24) != sourceMtime)
        throw bad(16, "stale: the source file changed since the cache was written");
    const uint64_t V = getLE<uint64_t>(data + 32), T = getLE<uint64_t>(data + 40);
    const uint32_t flags = getLE<uint32_t>(data + 48);
    if (flags > 7 || getLE<uint32_t>(data + 52) != 0) throw bad(48, "unknown flags");
    for (size_t at = 168; at < kHeaderSize; ++at)
        if (data[at] != 0) throw bad(at, "reserved header bytes are not zero");
    // Counts must fit the file before anything is computed from them.
    if (V == 0 || T == 0 || V >= std::numeric_limits<uint32_t>::max() || V > size / 12 || T > size / 12)
        throw bad(32, "vertex or triangle count does not fit the file");
    const bool normals = flags & 1, colors = flags & 2, uvs = flags & 4;
    const size_t posBytes = sectionBytes(3 * V), nrmBytes = normals ? posBytes : 0, idxBytes = sectionBytes(3 * T);
    const size_t colBytes = colors ? align64(3 * V + 16) : 0;
    const size_t uvBytes = uvs ? sectionBytes(2 * V) : 0;
    const size_t expected = kHeaderSize + posBytes + nrmBytes + idxBytes + colBytes + uvBytes;
    if (size != expected)
        throw bad(std::min(size, expected), (size < expected ? "truncated: " : "trailing bytes: ") + std::to_string(size) +
                                                " bytes, the counts give " + std::to_string(expected));
    if (getLE<uint64_t>(data + kChecksumAt) != checksum(data, size)) throw bad(kChecksumAt, "checksum mismatch: the cache is corrupt");

    // Validated where the bytes lie, before any array is used: the checksum only says the file
    // is the one that was written, not that whoever wrote it was right.
    const size_t nrmAt = kHeaderSize + posBytes, idxAt = nrmAt + nrmBytes;
    for (size_t i = 0; i < 3 * V; ++i)
        if (!std::isfinite(getLE<float>(data + kHeaderSize + 4 * i))) throw bad(kHeaderSize + 4 * i, "non-finite coordinate");
    if (normals)
        for (size_t i = 0; i < 3 * V; ++i)
            if (!std::isfinite(getLE<float>(data + nrmAt + 4 * i))) throw bad(nrmAt + 4 * i, "non-finite normal");
    // The last line before Embree: an index past the vertices would be an out-of-bounds read.
    for (size_t i = 0; i < 3 * T; ++i)
        if (const uint32_t v = getLE<uint32_t>(data + idxAt + 4 * i); v >= V)
            throw bad(idxAt + 4 * i, "vertex index " + std::to_string(v) + " out of range");
    const size_t colAt = idxAt + idxBytes, uvAt = colAt + colBytes;
    if (uvs)
        for (size_t i = 0; i < 2 * V; ++i)
            if (!std::isfinite(getLE<float>(data + uvAt + 4 * i))) throw bad(uvAt + 4 * i, "non-finite texture coordinate");
    std::array<double, 3> origin{};
    for (int k = 0; k < 3; ++k) {
        origin[size_t(k)] = getLE<double>(data + 56 + 8 * k);
        if (!std::isfinite(origin[size_t(k)])) throw bad(56, "non-finite origin");
    }

    TriangleMesh mesh;
    MeshArray<float>& pos = MeshAccess::positions(mesh);
    MeshArray<float>& nrm = MeshAccess::normals(mesh);
    MeshArray<uint32_t>& idx = MeshAccess::indices(mesh);
    // In place needs the host's byte order and 4-byte alignment (a mapping is page-aligned).
    const bool inPlace = keepAlive && std::endian::native == std::endian::little &&
                         reinterpret_cast<uintptr_t>(data) % alignof(float) == 0;
    if (inPlace) {
        pos.view(reinterpret_cast<const float*>(data + kHeaderSize), 3 * V, keepAlive);
        if (normals) nrm.view(reinterpret_cast<const float*>(data + nrmAt), 3 * V, keepAlive);
        idx.view(reinterpret_cast<const uint32_t*>(data + idxAt), 3 * T, keepAlive);
        if (colors) MeshAccess::colors(mesh).view(data + colAt, 3 * V, keepAlive);
        if (uvs) MeshAccess::uvs(mesh).view(reinterpret_cast<const float*>(data + uvAt), 2 * V, keepAlive);
    } else {
        auto copy = [](const unsigned char* src, size_t n, auto tag) {
            using Elem = decltype(tag);
            std::vector<Elem> v(n);
            for (size_t i = 0; i < n; ++i) v[i] = getLE<Elem>(src + 4 * i);
            return v;
        };
        pos.assign(copy(data + kHeaderSize, 3 * V, float{}));
        if (normals) nrm.assign(copy(data + nrmAt, 3 * V, float{}));
        idx.assign(copy(data + idxAt, 3 * T, uint32_t{}));
        if (colors) MeshAccess::colors(mesh).assign(std::vector<uint8_t>(data + colAt, data + colAt + 3 * V));
        if (uvs) MeshAccess::uvs(mesh).assign(copy(data + uvAt, 2 * V, float{}));
    }
    MeshAccess::setVertexCount(mesh, V);
    mesh.setOrigin(origin);
    if (report) {
        report->polygonsTriangulated = getLE<uint64_t>(data + 80);
        report->degenerateTriangles = getLE<uint64_t>(data + 88);
        report->stripsTriangulated = getLE<uint64_t>(data + 96);
        report->cellsSkipped = getLE<uint64_t>(data + 104);
        report->polygonsFanned = getLE<uint64_t>(data + 128);
        report->polygonsEarClipped = getLE<uint64_t>(data + 136);
        report->polygonsDegenerate = getLE<uint64_t>(data + 144);
        report->polygonsSelfIntersecting = getLE<uint64_t>(data + 152);
        report->seamVerticesSplit = getLE<uint64_t>(data + 160);
        const char* f = reinterpret_cast<const char*>(data + 112);
        report->format.clear();
        for (int k = 0; k < 8 && f[k] >= 'a' && f[k] <= 'z'; ++k) report->format += f[k];
    }
    return mesh;
}

}  // namespace detail

TriangleMesh decodeMeshCache(const unsigned char* data, size_t size, uint64_t sourceSize, int64_t sourceMtime,
                             const std::string& name, ImportReport* report) {
    return detail::decodeMeshCache(data, size, sourceSize, sourceMtime, name, report, nullptr);
}

std::optional<TriangleMesh> readMeshCache(const fs::path& cacheFile, const fs::path& source, ImportReport* report,
                                          std::string* whyNot) {
    auto no = [&](const std::string& why) -> std::optional<TriangleMesh> {
        if (whyNot) *whyNot = why;
        return std::nullopt;
    };
    SourceStamp stamp;
    if (!stampOf(source, stamp)) return no("the source file cannot be read");
    // Shared: the mesh's arrays view the mapping and keep it alive; a rejected cache unmaps here.
    const auto map = std::make_shared<const Mapping>(cacheFile);
    if (!map->ok()) return no("no cache");
    if (!map->data()) return no("the cache is empty or cannot be mapped");
    try {
        TriangleMesh mesh = detail::decodeMeshCache(map->data(), map->size(), stamp.size, stamp.mtimeNs,
                                                    cacheFile.string(), report, map);
        map->accessRandomly();
        return mesh;
    } catch (const InputError& e) {
        return no(e.what());
    } catch (const std::bad_alloc&) {
        return no("out of memory reading the cache");
    }
}

TriangleMesh loadMesh(const fs::path& file, ImportReport* report) { return detail::importMesh(file, report); }

TriangleMesh loadMesh(const fs::path& file, const LoadOptions& options, ImportReport* report) {
    ImportReport local;
    ImportReport& r = report ? *report : local;
    if (!options.cache) return detail::importMesh(file, &r);
    const fs::path cacheFile = meshCachePath(file, options.cacheDir);
    std::string why;
    if (std::optional<TriangleMesh> cached = readMeshCache(cacheFile, file, &r, &why)) {
        r.cache = "hit";
        return std::move(*cached);
    }
    TriangleMesh mesh = detail::importMesh(file, &r);
    try {
        if (!options.cacheDir.empty()) fs::create_directories(options.cacheDir);
        writeMeshCache(mesh, r, file, cacheFile, options.progress);
        r.cache = why == "no cache" ? "written" : "rebuilt: " + why;
    } catch (const Cancelled&) {
        throw;
    } catch (const std::exception& e) {
        // A read-only folder must not stop a scene from loading.
        r.cache = std::string("not written: ") + e.what();
    }
    return mesh;
}

}  // namespace rtwall
