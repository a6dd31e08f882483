// libFuzzer target for the glTF importer (issue 20): the input is a whole .gltf (JSON) or .glb
// file, given to decodeGltf, which reads no external file. Only InputError is an expected outcome;
// anything else (another exception, a sanitizer report, an allocation past -malloc_limit_mb) is a
// finding. An assembly that loads must satisfy what the engine relies on: every instance names a
// mesh, a material and a part that exist, every part's parent comes before it, and every mesh
// has its indices in range and finite coordinates; also after the congruent-shape search.
//
// tinygltf is Debian's shared library, not instrumented: coverage is that of our checks on what
// it hands over, which is where a malformed file's accessors and indices are caught.
//
// Run (new inputs go to the first directory; the committed seeds are only read):
//   build-fuzz/tests/fuzz/fuzz_import_gltf -max_total_time=60 -malloc_limit_mb=512 -timeout=10 \
//     build-fuzz/tests/fuzz/corpus/gltf tests/fuzz/corpus/gltf
#include "assembly_checks.h"
#include "mesh_internal.h"

#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        rtwall::Assembly a = rtwall::decodeGltf(data, size, "fuzz.gltf");
        rtwall::fuzz::checkAssembly(a);
        // The congruent-shape search (issue 29) on whatever loads: the assembly it leaves must
        // satisfy the same checks.
        rtwall::detail::shareCongruentMeshes(a, 1e-5);
        rtwall::fuzz::checkAssembly(a);
    } catch (const rtwall::InputError&) {
    }
    return 0;
}
