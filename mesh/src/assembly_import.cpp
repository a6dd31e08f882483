// What the assembly importers (glTF, STEP/IGES) share: placements composed the same way, and the
// one default material. Its own unit so that an importer builds without the other (the glTF fuzz
// target compiles only the glTF side).
#include "assembly_import.h"
#include "mesh_internal.h"

namespace rtwall {

detail::Affine detail::composeAffine(const Affine& a, const Affine& b) {
    Affine r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j)
            r[4 * i + j] = a[4 * i] * b[j] + a[4 * i + 1] * b[4 + j] + a[4 * i + 2] * b[8 + j] + (j == 3 ? a[4 * i + 3] : 0.0);
    return r;
}

uint32_t detail::defaultAssemblyMaterial(Assembly& out, int& index) {
    if (index < 0) {
        AssemblyMaterial m;
        m.name = "default";
        m.baseColor = {0.7f, 0.7f, 0.72f, 1.0f};
        index = int(out.materials.size());
        out.materials.push_back(m);
    }
    return uint32_t(index);
}

}  // namespace rtwall
