#include "generators.h"

namespace rtwall::gen {

const std::map<std::string, Generator>& generators() {
    static const std::map<std::string, Generator> all = {
        {"powerplant",
         {"CAD-like plant far from the origin: VTK/PLY/OBJ sections, instanced pumps (--triangles, --copies)", genPowerplant}},
        {"sunflowers",
         {"field of instanced sunflowers in groups of groups, plus large trees (--instances plants, --triangles per plant, "
          "--trees, --tree-triangles)",
          genSunflowers}},
        {"office",
         {"the office demo: shadows, mirror, glass, textures, alpha-masked leaves, a volume",
          [](const GenOptions& g) { writeShadingDemo("office", g.out); }}},
        {"headlight",
         {"the headlight demo: parabolic reflector, bulb, structured lens glass, deep paths",
          [](const GenOptions& g) { writeShadingDemo("headlight", g.out); }}},
        {"step",
         {"STEP assembly through OpenCASCADE: 3 coloured, named parts in a 7-part module on a grid, assembly.step "
          "(--instances part instances, 7000)",
          genStep}},
        {"step-curved",
         {"STEP assembly of curved parts (filleted plate, pins with a rounded head, ball knobs, rings: 11-part "
          "module), where the tessellation deflections show: assembly.step (--instances, 11000)",
          genStepCurved}},
        {"iges", {"the same assembly as IGES through OpenCASCADE: assembly.igs (--instances)", genIges}},
    };
    return all;
}

}  // namespace rtwall::gen
