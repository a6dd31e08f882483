// What the mesh tests share: geometry checks, the test meshes and scratch copies of them, test
// names made of file names, a load's error message.
#pragma once

#include "rtwall/mesh.h"
#include "rtwall/vec.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <type_traits>

namespace rtwall::test {

inline Float3 corner(const TriangleMesh& m, size_t t, int k) { return m.position(m.indices()[3 * t + size_t(k)]); }

// Signed volume by the divergence theorem: exact for a closed mesh, and positive only if every
// triangle is wound counter-clockwise seen from outside. Summed in double over float terms.
inline double signedVolume(const TriangleMesh& m) {
    double v = 0;
    for (size_t t = 0; t < m.triangleCount(); ++t)
        v += double(dot(corner(m, t, 0), cross(corner(m, t, 1), corner(m, t, 2)))) / 6.0;
    return v;
}

inline Float3 geometricNormal(const TriangleMesh& m, size_t t) {
    return cross(corner(m, t, 1) - corner(m, t, 0), corner(m, t, 2) - corner(m, t, 0));
}

// What an import of a known file reports and holds.
inline void expectImported(const TriangleMesh& mesh, const ImportReport& report, const std::string& format, size_t vertices,
                           size_t triangles, size_t polygonsTriangulated) {
    EXPECT_EQ(report.format, format);
    EXPECT_EQ(mesh.vertexCount(), vertices);
    EXPECT_EQ(mesh.triangleCount(), triangles);
    EXPECT_EQ(report.polygonsTriangulated, polygonsTriangulated);
}

// The mesh's bounds are [lo, hi] exactly.
inline void expectBounds(const TriangleMesh& mesh, Float3 lo, Float3 hi) {
    const Bounds3 b = mesh.bounds();
    EXPECT_EQ(b.lo.x, lo.x);
    EXPECT_EQ(b.lo.y, lo.y);
    EXPECT_EQ(b.lo.z, lo.z);
    EXPECT_EQ(b.hi.x, hi.x);
    EXPECT_EQ(b.hi.y, hi.y);
    EXPECT_EQ(b.hi.z, hi.z);
}

inline const std::filesystem::path& meshDir() {
    static const std::filesystem::path dir = std::filesystem::path(RTWALL_TEST_DATA_DIR) / "meshes";
    return dir;
}

inline std::string readBytes(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void writeBytes(const std::filesystem::path& file, const std::string& bytes) {
    std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

// A folder of this name under the test temp directory; `fresh`: emptied first.
inline std::filesystem::path tempFolder(const std::string& name, bool fresh = false) {
    const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / name;
    if (fresh) std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

// Test mesh `file` copied into `folder` as `name` (a name that hides the format, or a copy the
// cache may sit beside).
inline std::filesystem::path copyMeshAs(const std::string& file, const std::filesystem::path& folder, const std::string& name) {
    std::filesystem::copy_file(meshDir() / file, folder / name, std::filesystem::copy_options::overwrite_existing);
    return folder / name;
}

// A test name made of a file name: letters and digits stay, everything else becomes '_'.
inline std::string fileTestName(std::string name) {
    for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return name;
}

// INSTANTIATE_TEST_SUITE_P's name generator for cases that are files: a file name, or a struct
// whose `file` is one.
struct FileCaseName {
    template <class T> std::string operator()(const ::testing::TestParamInfo<T>& p) const {
        if constexpr (std::is_convertible_v<T, const char*>)
            return fileTestName(p.param);
        else
            return fileTestName(p.param.file);
    }
};

// loadMesh's error message for `file`, or "(no InputError)".
inline std::string loadError(const std::filesystem::path& file) {
    try {
        loadMesh(file);
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no InputError)";
}

// Load options with the mesh cache on.
inline LoadOptions cacheOn() {
    LoadOptions o;
    o.cache = true;
    return o;
}

// Loads `src` twice with the cache on: the first load writes the cache, the second is a hit.
// Returns the imported mesh and the cached one.
inline std::pair<TriangleMesh, TriangleMesh> loadThroughCache(const std::filesystem::path& src) {
    const LoadOptions lo = cacheOn();
    ImportReport r1, r2;
    TriangleMesh first = loadMesh(src, lo, &r1);
    EXPECT_EQ(r1.cache, "written");
    TriangleMesh second = loadMesh(src, lo, &r2);
    EXPECT_EQ(r2.cache, "hit");
    return {std::move(first), std::move(second)};
}

// `cache` with `bytes` written over it is refused by its checksum.
inline void expectChecksumRefuses(const std::filesystem::path& cache, const std::filesystem::path& src, const std::string& bytes) {
    writeBytes(cache, bytes);
    std::string why;
    EXPECT_FALSE(readMeshCache(cache, src, nullptr, &why));
    EXPECT_NE(why.find("checksum"), std::string::npos) << why;
}

}  // namespace rtwall::test
