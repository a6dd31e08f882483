// libFuzzer target for the STEP and IGES importer (issue 20): the input is a whole file, read as
// STEP when it starts as a STEP file does ("ISO-10303-21"), else as IGES, through loadAssembly,
// which imports in a child process (cad_child.cpp). Only InputError is an expected outcome;
// anything else (another exception, a sanitizer report in this process, a hang past -timeout)
// is a finding. An assembly that loads must satisfy what the engine relies on: every instance
// names a mesh, a material and a part that exist, parents come before their children, every
// transform is finite, every mesh has its indices in range and finite coordinates.
//
// OpenCASCADE is Debian's build, not instrumented. In the child process, its crashes are
// contained (the parent reports a malformed file: that is the behaviour under test) and coverage
// does not reach the fuzzer, which then mutates blindly from the seeds; the parent's validation
// of the child's result is instrumented. To hunt bugs inside OCCT with coverage of rtwall's part
// of the import, run with RTWALL_CAD_IN_PROCESS=1 (a crash there is OCCT's).
//
// Seeds (tests/fuzz/corpus/step) are written by OCCT itself: `rtwall gen step`, `gen step-curved`
// and `gen iges` at a few instances each.
//
// Run (new inputs go to the first directory; the committed seeds are only read):
//   build-fuzz/tests/fuzz/fuzz_step -max_total_time=60 -timeout=60 -rss_limit_mb=4096 \
//     build-fuzz/tests/fuzz/corpus/step tests/fuzz/corpus/step
#include "assembly_checks.h"
#include "rtwall/mesh.h"

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::filesystem::path dir = [] {
        auto d = std::filesystem::temp_directory_path() / ("rtwall_fuzz_step_" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    const bool step = size >= 12 && std::memcmp(data, "ISO-10303-21", 12) == 0;
    const std::filesystem::path file = dir / (step ? "input.step" : "input.igs");
    FILE* f = std::fopen(file.c_str(), "wb");
    if (!f) std::abort();
    if (size && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
    try {
        const rtwall::Assembly a = rtwall::loadAssembly(file);
        if (a.instances.empty()) std::abort();  // a STEP/IGES file that loads places something
        rtwall::fuzz::checkAssembly(a);
    } catch (const rtwall::InputError&) {
    }
    return 0;
}
