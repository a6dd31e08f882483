// libFuzzer targets for the mesh importers and the mesh cache reader. One source, built once per
// target with FUZZ_MESH_FORMAT set (tests/fuzz/CMakeLists.txt):
//   fuzz_import_vtk, fuzz_import_vtp, fuzz_import_vtu   the input is a whole .vtk/.vtp/.vtu file
//   fuzz_import_wrl                                      the input is a whole VRML 2.0 .wrl file
//   fuzz_import_openmesh  the first byte picks obj/off/ply/stl/om (its value modulo 5), the rest is the file
//   fuzz_mesh_cache       the input is a cache file, given to decodeMeshCache with the source stamp it
//                         claims, so the fuzzer gets past the staleness check, and with its checksum
//                         set right, so it gets past that too: without, almost every mutation stops
//                         at the checksum and the validation behind it (counts, sizes, non-finite
//                         values, index range) is never reached (a 10-minute run stayed at 286
//                         edges). The mismatch itself is covered by cache_test's flipped byte.
// loadMesh reads files, so the input is written to a per-process scratch file first. Only
// InputError is an expected outcome; anything else (another exception, a sanitizer report, an
// out-of-memory past -malloc_limit_mb) is a finding. A mesh that loads must satisfy the
// invariants Embree relies on (indices in range, finite coordinates).
//
// VTK parses in a child process (import_vtk.cpp), so a crash inside VTK is contained and is no
// finding here (ASan still prints its report from the child), and the coverage of VTK's own code
// does not reach the fuzzer. To hunt bugs inside VTK, run with RTWALL_VTK_IN_PROCESS=1.
//
// Leak detection is off (-detect_leaks=0): the libraries leak a few constant bytes per file on
// valid seeds already (VTK 9.1's vtkGeometryFilterHelper and XML array iterators, OpenMesh's
// mostream connect/disconnect in CaptureOpenMeshLog), which would stop every run at once.
//
// Run (new inputs go to the first directory; the committed seeds are only read):
//   build-fuzz/tests/fuzz/fuzz_import_vtk -max_total_time=60 -malloc_limit_mb=512 -timeout=10 -detect_leaks=0 \
//     build-fuzz/tests/fuzz/corpus/vtk tests/fuzz/corpus/vtk
#include "rtwall/mesh.h"

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <xxhash.h>

#ifndef FUZZ_MESH_FORMAT
#error "define FUZZ_MESH_FORMAT"
#endif

namespace {

void checkMesh(const rtwall::TriangleMesh& m) {
    for (size_t i = 0; i < 3 * m.triangleCount(); ++i)
        if (m.indices()[i] >= m.vertexCount()) std::abort();
    for (size_t i = 0; i < 3 * m.vertexCount(); ++i)
        if (!std::isfinite(m.positions()[i])) std::abort();
    // Colours, when present, cover every vertex (AddressSanitizer catches a short buffer).
    if (const uint8_t* c = m.colors()) {
        unsigned sum = 0;
        for (size_t i = 0; i < 3 * m.vertexCount(); ++i) sum += c[i];
        if (sum > 255u * 3u * m.vertexCount()) std::abort();
    }
    // Texture coordinates, when present, cover every vertex and are finite.
    if (const float* t = m.uvs())
        for (size_t i = 0; i < 2 * m.vertexCount(); ++i)
            if (!std::isfinite(t[i])) std::abort();
}

std::filesystem::path scratch(const char* ext) {
    static const std::filesystem::path dir = [] {
        auto d = std::filesystem::temp_directory_path() / ("rtwall_fuzz_" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir / (std::string("input.") + ext);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string format = FUZZ_MESH_FORMAT;
    try {
        if (format == "cache") {
            uint64_t srcSize = 0;
            int64_t srcMtime = 0;
            if (size >= 32) {
                std::memcpy(&srcSize, data + 16, 8);  // little-endian hosts only, as the fuzz build is
                std::memcpy(&srcMtime, data + 24, 8);
            }
            if (size < 128) {
                checkMesh(rtwall::decodeMeshCache(data, size, srcSize, srcMtime, "fuzz"));
                return 0;
            }
            // cache.cpp's checksum: XXH3-64 of the whole file with bytes 120..127 taken as zero.
            std::vector<unsigned char> file(data, data + size);
            std::memset(file.data() + 120, 0, 8);
            const uint64_t sum = XXH3_64bits(file.data(), file.size());
            std::memcpy(file.data() + 120, &sum, 8);  // little-endian hosts only, as above
            checkMesh(rtwall::decodeMeshCache(file.data(), file.size(), srcSize, srcMtime, "fuzz"));
            return 0;
        }
        const char* ext = format.c_str();
        if (format == "openmesh") {
            if (size == 0) return 0;
            static const char* exts[] = {"obj", "off", "ply", "stl", "om"};
            ext = exts[data[0] % 5];
            ++data;
            --size;
        }
        const std::filesystem::path file = scratch(ext);
        FILE* f = std::fopen(file.c_str(), "wb");
        if (!f) std::abort();
        if (size && std::fwrite(data, 1, size, f) != size) std::abort();
        std::fclose(f);
        checkMesh(rtwall::loadMesh(file));
    } catch (const rtwall::InputError&) {
    }
    return 0;
}
