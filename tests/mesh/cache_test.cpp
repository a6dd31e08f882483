// Mesh caches (mesh/src/cache.cpp): round trip, and every kind of bad cache is refused and
// rebuilt, never trusted.
#include "mesh_test_util.h"
#include "mesh_test_util.h"
#include "rtwall/mesh.h"

#include <gtest/gtest.h>

// Header-only, to sign hand-made caches the way the writer does.
#define XXH_INLINE_ALL
#include <xxhash.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <thread>
#include <utility>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshes = fs::path(RTWALL_TEST_DATA_DIR) / "meshes";

using test::readBytes;
using test::writeBytes;

fs::path scratch(const std::string& name) { return test::tempFolder("rtwall_cache_tests/" + name, true); }

// The cache written beside `src`, its bytes changed by `edit`.
void editCache(const fs::path& src, const std::function<void(std::string&)>& edit) {
    std::string bytes = readBytes(meshCachePath(src));
    edit(bytes);
    writeBytes(meshCachePath(src), bytes);
}

void expectSameMesh(const TriangleMesh& a, const TriangleMesh& b) {
    ASSERT_EQ(a.vertexCount(), b.vertexCount());
    ASSERT_EQ(a.triangleCount(), b.triangleCount());
    ASSERT_EQ(a.hasNormals(), b.hasNormals());
    EXPECT_EQ(std::memcmp(a.positions(), b.positions(), (3 * a.vertexCount() + 1) * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(a.indices(), b.indices(), 3 * a.triangleCount() * sizeof(uint32_t)), 0);
    if (a.hasNormals()) {
        EXPECT_EQ(std::memcmp(a.normals(), b.normals(), (3 * a.vertexCount() + 1) * sizeof(float)), 0);
    }
    EXPECT_EQ(a.origin(), b.origin());
}

// A copy of a test mesh in a scratch folder, so its cache goes there too.
fs::path copyMesh(const fs::path& dir, const char* name) { return test::copyMeshAs(name, dir, name); }

class CacheRoundTrip : public ::testing::TestWithParam<const char*> {};

TEST_P(CacheRoundTrip, GivesIdenticalGeometry) {
    const fs::path dir = scratch(std::string("roundtrip_") + std::to_string(std::hash<std::string>{}(GetParam())));
    const fs::path src = copyMesh(dir, GetParam());
    const LoadOptions opt = test::cacheOn();
    ImportReport first, second;
    const TriangleMesh imported = loadMesh(src, opt, &first);
    EXPECT_EQ(first.cache, "written");
    ASSERT_TRUE(fs::exists(meshCachePath(src)));
    const TriangleMesh cached = loadMesh(src, opt, &second);
    EXPECT_EQ(second.cache, "hit");
    expectSameMesh(imported, cached);
    EXPECT_EQ(first.format, second.format);
    EXPECT_EQ(first.polygonsTriangulated, second.polygonsTriangulated);
    EXPECT_EQ(first.polygonsFanned, second.polygonsFanned);
    EXPECT_EQ(first.polygonsEarClipped, second.polygonsEarClipped);
    EXPECT_EQ(first.polygonsDegenerate, second.polygonsDegenerate);
    EXPECT_EQ(first.polygonsSelfIntersecting, second.polygonsSelfIntersecting);
    EXPECT_EQ(first.degenerateTriangles, second.degenerateTriangles);
    EXPECT_EQ(first.seamVerticesSplit, second.seamVerticesSplit);
    EXPECT_EQ(first.cellsSkipped, second.cellsSkipped);
    // The cache file itself: 64-byte aligned sections, so its size is a multiple of 64.
    EXPECT_EQ(fs::file_size(meshCachePath(src)) % 64, 0u);
}

INSTANTIATE_TEST_SUITE_P(Files, CacheRoundTrip,
                         ::testing::Values("box_normals.obj", "tet_binary_le.ply", "box_ascii.vtk", "box_far.vtp", "box_hex_zlib.vtu"));

// Every single flipped byte anywhere in the file is caught (checksum, magic, version, counts).
TEST(MeshCache, EveryFlippedByteIsCaught) {
    const fs::path dir = scratch("flip");
    const fs::path src = copyMesh(dir, "box_normals.obj");
    const TriangleMesh mesh = loadMesh(src);
    const fs::path cache = meshCachePath(src);
    writeMeshCache(mesh, ImportReport{}, src, cache);
    const std::string good = readBytes(cache);
    ASSERT_TRUE(readMeshCache(cache, src).has_value());
    for (size_t i = 0; i < good.size(); ++i) {
        std::string bad = good;
        bad[i] = char(bad[i] ^ 0x10);
        writeBytes(cache, bad);
        std::string why;
        EXPECT_FALSE(readMeshCache(cache, src, nullptr, &why).has_value()) << "flipped byte " << i << " was not caught";
        EXPECT_EQ(why.find('\n'), std::string::npos);
    }
}

TEST(MeshCache, TruncationAndTrailingBytesAreCaught) {
    const fs::path dir = scratch("truncate");
    const fs::path src = copyMesh(dir, "box_ascii.vtk");
    writeMeshCache(loadMesh(src), ImportReport{}, src, meshCachePath(src));
    const std::string good = readBytes(meshCachePath(src));
    for (size_t size : {size_t(0), size_t(7), size_t(127), size_t(128), size_t(191), size_t(192), good.size() / 2, good.size() - 1}) {
        writeBytes(meshCachePath(src), good.substr(0, size));
        std::string why;
        EXPECT_FALSE(readMeshCache(meshCachePath(src), src, nullptr, &why).has_value()) << size;
    }
    writeBytes(meshCachePath(src), good + std::string(64, '\0'));
    std::string why;
    EXPECT_FALSE(readMeshCache(meshCachePath(src), src, nullptr, &why).has_value());
    EXPECT_NE(why.find("trailing"), std::string::npos) << why;
}

// A source that changed after the cache was written makes the cache stale: loadMesh rebuilds it
// and returns the new geometry.
TEST(MeshCache, StaleCacheIsRebuilt) {
    const fs::path dir = scratch("stale");
    const fs::path src = copyMesh(dir, "box_quads.obj");
    const LoadOptions opt = test::cacheOn();
    ImportReport r1, r2, r3;
    EXPECT_EQ(loadMesh(src, opt, &r1).triangleCount(), 12u);
    EXPECT_EQ(r1.cache, "written");
    // Same size, different content: a new modification time is what gives it away.
    std::string text = readBytes(src);
    const size_t at = text.find("v 1");
    ASSERT_NE(at, std::string::npos);
    text[at + 2] = '5';
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    writeBytes(src, text);
    const TriangleMesh fresh = loadMesh(src, opt, &r2);
    EXPECT_NE(r2.cache.find("rebuilt"), std::string::npos) << r2.cache;
    EXPECT_NE(r2.cache.find("stale"), std::string::npos) << r2.cache;
    EXPECT_EQ(fresh.bounds().hi.x, 5.0f);
    loadMesh(src, opt, &r3);
    EXPECT_EQ(r3.cache, "hit");
}

TEST(MeshCache, CorruptCacheIsRebuiltNotTrusted) {
    const fs::path dir = scratch("corrupt");
    const fs::path src = copyMesh(dir, "box_quads.obj");
    const LoadOptions opt = test::cacheOn();
    const TriangleMesh original = loadMesh(src, opt);
    editCache(src, [](std::string& bytes) { bytes[200] = char(bytes[200] ^ 1); });  // inside the positions (from byte 192)
    ImportReport r;
    const TriangleMesh again = loadMesh(src, opt, &r);
    EXPECT_NE(r.cache.find("checksum"), std::string::npos) << r.cache;
    expectSameMesh(original, again);
}

// A cache folder shared by files of the same name from different folders keeps them apart.
TEST(MeshCache, CacheDirKeepsSameNamesApart) {
    const fs::path dir = scratch("cachedir");
    fs::create_directories(dir / "a");
    fs::create_directories(dir / "b");
    EXPECT_NE(meshCachePath(dir / "a" / "m.obj", dir / "cache"), meshCachePath(dir / "b" / "m.obj", dir / "cache"));
    const fs::path src = dir / "a" / "box.obj";
    fs::copy_file(kMeshes / "box_quads.obj", src);
    LoadOptions opt = test::cacheOn();
    opt.cacheDir = dir / "cache";
    ImportReport r;
    loadMesh(src, opt, &r);
    EXPECT_EQ(r.cache, "written");
    EXPECT_TRUE(fs::exists(meshCachePath(src, dir / "cache")));
}

// The address ranges at which this process maps `file` (from /proc/self/maps).
std::vector<std::pair<uintptr_t, uintptr_t>> mappingsOf(const fs::path& file) {
    const std::string want = fs::canonical(file).string();
    std::ifstream maps("/proc/self/maps");
    std::vector<std::pair<uintptr_t, uintptr_t>> out;
    for (std::string line; std::getline(maps, line);) {
        const size_t slash = line.find('/');
        if (slash == std::string::npos || line.substr(slash) != want) continue;
        out.emplace_back(std::stoull(line.substr(0, line.find('-')), nullptr, 16),
                         std::stoull(line.substr(line.find('-') + 1), nullptr, 16));
    }
    return out;
}

// [p, p + bytes) lies inside one of the ranges.
bool inside(const void* p, size_t bytes, const std::vector<std::pair<uintptr_t, uintptr_t>>& ranges) {
    const auto at = reinterpret_cast<uintptr_t>(p);
    for (const auto& [lo, hi] : ranges)
        if (at >= lo && at + bytes <= hi) return true;
    return false;
}

// A mesh read from its cache is the mapped file: its arrays (the pointers the engine gives
// Embree as shared buffers) lie inside the mapping, 64-byte aligned, with 16 zero bytes after
// each that Embree's SIMD loads may read; the mapping goes away with the last mesh using it.
TEST(MeshCache, CachedMeshIsTheMappedFileNotACopy) {
    const fs::path dir = scratch("inplace");
    const fs::path src = copyMesh(dir, "box_normals.obj");
    const LoadOptions opt = test::cacheOn();
    const TriangleMesh imported = loadMesh(src, opt);
    EXPECT_FALSE(imported.isMapped());
    EXPECT_EQ(imported.mappedBytes(), 0u);
    const fs::path cache = meshCachePath(src);
    {
        ImportReport r;
        const TriangleMesh cached = loadMesh(src, opt, &r);
        ASSERT_EQ(r.cache, "hit");
        ASSERT_TRUE(cached.isMapped());
        ASSERT_TRUE(cached.hasNormals());
        const auto ranges = mappingsOf(cache);
        ASSERT_FALSE(ranges.empty()) << "the cache file is not mapped";
        const size_t V = cached.vertexCount(), T = cached.triangleCount();
        EXPECT_TRUE(inside(cached.positions(), 12 * V + 16, ranges));
        EXPECT_TRUE(inside(cached.normals(), 12 * V + 16, ranges));
        EXPECT_TRUE(inside(cached.indices(), 12 * T + 16, ranges));
        for (const void* p : {static_cast<const void*>(cached.positions()), static_cast<const void*>(cached.normals()),
                              static_cast<const void*>(cached.indices())})
            EXPECT_EQ(reinterpret_cast<uintptr_t>(p) % 64, 0u);
        const unsigned char zeros[16] = {};
        EXPECT_EQ(std::memcmp(cached.positions() + 3 * V, zeros, 16), 0);
        EXPECT_EQ(std::memcmp(cached.normals() + 3 * V, zeros, 16), 0);
        EXPECT_EQ(std::memcmp(cached.indices() + 3 * T, zeros, 16), 0);
        EXPECT_EQ(cached.mappedBytes(), (24 * V + 12 * T) + 3 * 16);
        EXPECT_EQ(cached.residentBytes(), cached.mappedBytes());  // nothing on the heap
        expectSameMesh(imported, cached);

        // A copy shares the pages; writing to it copies its own arrays, and the cached mesh and
        // the file stay as they were.
        TriangleMesh edited = cached;
        EXPECT_EQ(edited.positions(), cached.positions());
        edited.setPosition(0, {9, 9, 9});
        EXPECT_FALSE(edited.isMapped() && edited.positions() == cached.positions());
        EXPECT_EQ(edited.position(0).x, 9.0f);
        EXPECT_EQ(edited.positions()[3 * V], 0.0f);
        expectSameMesh(imported, cached);
    }
    EXPECT_TRUE(mappingsOf(cache).empty()) << "the mapping outlived every mesh using it";
    ImportReport again;
    EXPECT_TRUE(loadMesh(src, opt, &again).isMapped());
    EXPECT_EQ(again.cache, "hit");
}

// A cache in the version-1 layout (too little padding for Embree to read it in place) is
// refused with its version named, rebuilt, and the rebuilt one is used.
TEST(MeshCache, OldVersionIsRebuilt) {
    const fs::path dir = scratch("oldversion");
    const fs::path src = copyMesh(dir, "tet_binary_le.ply");
    LoadOptions opt;
    opt.cache = true;
    const TriangleMesh original = loadMesh(src, opt);
    ASSERT_EQ(readBytes(meshCachePath(src))[8], 5);
    editCache(src, [](std::string& bytes) { bytes[8] = 1; });
    ImportReport r1, r2;
    const TriangleMesh rebuilt = loadMesh(src, opt, &r1);
    EXPECT_EQ(r1.cache.rfind("rebuilt: ", 0), 0u) << r1.cache;
    EXPECT_NE(r1.cache.find("cache version 1"), std::string::npos) << r1.cache;
    EXPECT_FALSE(rebuilt.isMapped());
    expectSameMesh(original, rebuilt);
    const TriangleMesh cached = loadMesh(src, opt, &r2);
    EXPECT_EQ(r2.cache, "hit");
    EXPECT_TRUE(cached.isMapped());
    expectSameMesh(original, cached);
}

// A valid checksum does not make an index or coordinate trustworthy: the values are checked in
// the mapped file before the mesh is handed out.
TEST(MeshCache, BadValuesUnderAGoodChecksumAreCaught) {
    const fs::path dir = scratch("badvalues");
    const fs::path src = copyMesh(dir, "box_quads.obj");
    const TriangleMesh mesh = loadMesh(src);
    ASSERT_FALSE(mesh.hasNormals());
    const fs::path cache = meshCachePath(src);
    writeMeshCache(mesh, ImportReport{}, src, cache);
    std::string bytes = readBytes(cache);
    const size_t V = mesh.vertexCount(), T = mesh.triangleCount();
    const size_t posBytes = (12 * V + 16 + 63) / 64 * 64, idxAt = 192 + posBytes;
    ASSERT_EQ(bytes.size(), idxAt + (12 * T + 16 + 63) / 64 * 64);
    // Re-signed as the writer would: the checksum is then right, the values are not.
    auto resign = [](std::string& b) {
        std::memset(&b[120], 0, 8);
        const uint64_t h = XXH3_64bits(b.data(), b.size());
        std::memcpy(&b[120], &h, 8);  // little-endian host (the test machines)
    };
    auto error = [](const std::string& b) -> std::string {
        try {
            (void)decodeMeshCache(reinterpret_cast<const unsigned char*>(b.data()), b.size(), 0, 0, "c");
        } catch (const InputError& e) {
            return e.what();
        }
        return "";
    };
    std::memset(&bytes[16], 0, 16);  // source stamp 0/0, as decodeMeshCache is asked for below
    std::string good = bytes;
    resign(good);
    EXPECT_EQ(error(good), "");
    std::string badIndex = bytes;
    const uint32_t outOfRange = uint32_t(V);
    std::memcpy(&badIndex[idxAt + 12 * (T - 1)], &outOfRange, 4);
    resign(badIndex);
    EXPECT_EQ(error(badIndex), "c:offset " + std::to_string(idxAt + 12 * (T - 1)) + ": vertex index " + std::to_string(V) + " out of range");
    std::string badCoordinate = bytes;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(&badCoordinate[192 + 4], &nan, 4);
    resign(badCoordinate);
    EXPECT_EQ(error(badCoordinate), "c:offset 196: non-finite coordinate");
    // And through readMeshCache, which would otherwise hand the mapping to Embree.
    std::memcpy(&badIndex[16], readBytes(cache).data() + 16, 16);
    resign(badIndex);
    writeBytes(cache, badIndex);
    std::string why;
    EXPECT_FALSE(readMeshCache(cache, src, nullptr, &why).has_value());
    EXPECT_NE(why.find("out of range"), std::string::npos) << why;
}

// The decoder on arbitrary bytes never reads past them (the fuzz target does this at scale).
TEST(MeshCache, DecoderRejectsGarbage) {
    std::string junk(4096, '\0');
    for (size_t i = 0; i < junk.size(); ++i) junk[i] = char(i * 131 + 7);
    std::memcpy(junk.data(), "RTWMESH\0", 8);
    EXPECT_THROW(decodeMeshCache(reinterpret_cast<const unsigned char*>(junk.data()), junk.size(), 0, 0, "junk"), InputError);
}

}  // namespace
}  // namespace rtwall
