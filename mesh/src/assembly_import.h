// What the assembly importers (glTF, STEP/IGES) share. Internal to rtwall_mesh.
#pragma once

#include "rtwall/mesh.h"

#include <cstdint>

namespace rtwall::detail {

// The grey material of the parts a file gives none: added to `out` on first use, its index kept
// in `index` (-1 until then).
uint32_t defaultAssemblyMaterial(Assembly& out, int& index);

}  // namespace rtwall::detail
