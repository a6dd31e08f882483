// libFuzzer target for the glTF importer (issue 20): the input is a whole .gltf (JSON) or .glb
// file, given to decodeGltf, which reads no external file. Only InputError is an expected outcome;
// anything else (another exception, a sanitizer report, an allocation past -malloc_limit_mb) is a
// finding. An assembly that loads must satisfy what the engine relies on: every instance names a
// mesh, a material and a part that exist, every part's parent comes before it, and every mesh
// has its indices in range and finite coordinates.
//
// tinygltf is Debian's shared library, not instrumented: coverage is that of our checks on what
// it hands over, which is where a malformed file's accessors and indices are caught.
//
// Run (new inputs go to the first directory; the committed seeds are only read):
//   build-fuzz/tests/fuzz/fuzz_import_gltf -max_total_time=60 -malloc_limit_mb=512 -timeout=10 \
//     build-fuzz/tests/fuzz/corpus/gltf tests/fuzz/corpus/gltf
#include "rtwall/mesh.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        const rtwall::Assembly a = rtwall::decodeGltf(data, size, "fuzz.gltf");
        if (a.meshNames.size() != a.meshes.size()) std::abort();
        for (size_t p = 0; p < a.parts.size(); ++p)
            if (a.parts[p].parent >= int32_t(p)) std::abort();
        for (const rtwall::AssemblyInstance& in : a.instances) {
            if (in.mesh >= a.meshes.size() || in.material >= a.materials.size() || in.part >= a.parts.size()) std::abort();
            for (double v : in.transform)
                if (!std::isfinite(v)) std::abort();
        }
        for (const auto& m : a.meshes) {
            for (size_t i = 0; i < 3 * m->triangleCount(); ++i)
                if (m->indices()[i] >= m->vertexCount()) std::abort();
            for (size_t i = 0; i < 3 * m->vertexCount(); ++i)
                if (!std::isfinite(m->positions()[i])) std::abort();
            if (const float* t = m->uvs())
                for (size_t i = 0; i < 2 * m->vertexCount(); ++i)
                    if (!std::isfinite(t[i])) std::abort();
        }
    } catch (const rtwall::InputError&) {
    }
    return 0;
}
