// The STEP assembly the engine tests read: written through OpenCASCADE's XDE writer by
// `rtwall gen step` (tools/gen/step_assembly.cpp); tests that include this link rtwall_gen.
#pragma once

#include "test_util.h"

#include "generators.h"

#include <filesystem>

namespace rtwall::test {

// Three modules of seven part instances: 21 instances of 3 parts, written once per process.
inline const std::filesystem::path& stepAssembly() {
    static const std::filesystem::path file = [] {
        const std::filesystem::path dir = processScratchDir("step-generated");
        gen::genStep({.out = dir, .instances = 21});
        return dir / "assembly.step";
    }();
    return file;
}

}  // namespace rtwall::test
