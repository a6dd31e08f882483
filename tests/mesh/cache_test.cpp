// Mesh caches (mesh/src/cache.cpp): round trip, and every kind of bad cache is refused and
// rebuilt, never trusted.
#include "rtwall/mesh.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshes = fs::path(RTWALL_TEST_DATA_DIR) / "meshes";

fs::path scratch(const std::string& name) {
    const fs::path dir = fs::path(::testing::TempDir()) / "rtwall_cache_tests" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string readBytes(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

void writeBytes(const fs::path& file, const std::string& bytes) {
    std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
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
fs::path copyMesh(const fs::path& dir, const char* name) {
    fs::copy_file(kMeshes / name, dir / name);
    return dir / name;
}

class CacheRoundTrip : public ::testing::TestWithParam<const char*> {};

TEST_P(CacheRoundTrip, GivesIdenticalGeometry) {
    const fs::path dir = scratch(std::string("roundtrip_") + std::to_string(std::hash<std::string>{}(GetParam())));
    const fs::path src = copyMesh(dir, GetParam());
    LoadOptions opt;
    opt.cache = true;
    ImportReport first, second;
    const TriangleMesh imported = loadMesh(src, opt, &first);
    EXPECT_EQ(first.cache, "written");
    ASSERT_TRUE(fs::exists(meshCachePath(src)));
    const TriangleMesh cached = loadMesh(src, opt, &second);
    EXPECT_EQ(second.cache, "hit");
    expectSameMesh(imported, cached);
    EXPECT_EQ(first.format, second.format);
    EXPECT_EQ(first.polygonsTriangulated, second.polygonsTriangulated);
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
    for (size_t size : {size_t(0), size_t(7), size_t(127), size_t(128), good.size() / 2, good.size() - 1}) {
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
    LoadOptions opt;
    opt.cache = true;
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
    LoadOptions opt;
    opt.cache = true;
    const TriangleMesh original = loadMesh(src, opt);
    std::string bytes = readBytes(meshCachePath(src));
    bytes[200] = char(bytes[200] ^ 1);  // inside the positions
    writeBytes(meshCachePath(src), bytes);
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
    LoadOptions opt;
    opt.cache = true;
    opt.cacheDir = dir / "cache";
    ImportReport r;
    loadMesh(src, opt, &r);
    EXPECT_EQ(r.cache, "written");
    EXPECT_TRUE(fs::exists(meshCachePath(src, dir / "cache")));
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
