// What the engine relies on in an imported assembly, aborted on (a fuzzer finding) when broken:
// every instance names a mesh, a material and a part that exist with a finite transform, every
// part's parent comes before it, and every mesh has its indices in range and finite coordinates
// and texture coordinates. Shared by the glTF and STEP/IGES fuzz targets.
#pragma once

#include "rtwall/mesh.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>

namespace rtwall::fuzz {

inline void checkAssembly(const Assembly& a) {
    if (a.meshNames.size() != a.meshes.size()) std::abort();
    for (size_t p = 0; p < a.parts.size(); ++p)
        if (a.parts[p].parent >= int32_t(p)) std::abort();
    for (const AssemblyInstance& in : a.instances) {
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
}

}  // namespace rtwall::fuzz
