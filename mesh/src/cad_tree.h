// The product structure of a STEP or IGES file, as the readers give it to the one walk that
// turns it into an Assembly (import_cad.cpp): products (assemblies and parts) and, per assembly,
// its components (a product placed with a location). The XDE reader (OCCT's document) and the
// direct STEP reader (import_step_direct.cpp, linear in the occurrences) both fill it, so names,
// colours, materials and the part tree come out of the same code whichever read the file.
// Only OCCT units include this (it names OCCT types).
#pragma once

#include "rtwall/mesh.h"

#include <TopoDS_Shape.hxx>
#include <gp_Trsf.hxx>

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

class STEPControl_Reader;

namespace rtwall::detail {

using CadColour = std::optional<std::array<float, 3>>;  // linear RGB (Quantity_Color's)

struct CadComponent {
    uint32_t product = 0;  // index into CadTree::products
    gp_Trsf location;      // the product's coordinates to the assembly's
    std::string name;      // empty: the product's name
    CadColour colour;
};

struct CadProduct {
    std::string name;
    std::string key;  // names an unnamed product ("0:1:1:3" in XDE, "#42" in the STEP file)
    CadColour colour;
    bool assembly = false;
    std::vector<CadComponent> components;  // assemblies
    TopoDS_Shape shape;                    // parts, without location
};

struct CadTree {
    std::vector<CadProduct> products;
    std::vector<uint32_t> roots;  // the free products, in the file's order
};

// Reads a STEP file's product structure directly from the entities `reader` loaded, in one pass
// over them and one transfer per distinct part, so that the cost grows with the file, not with
// occurrences x uses (OCCT's assembly transfer looks up every use of a product per occurrence).
// Returns false, with `why`, and transfers nothing when the file uses what only XDE reads
// (component colours and overrides, mapped-item assemblies, external references, placements by
// Cartesian operators, assemblies with shapes of their own); the caller then uses XDE.
// `progress` sees the fraction of distinct parts transferred; false cancels (Cancelled).
// `occurrences` receives how many NEXT_ASSEMBLY_USAGE_OCCURRENCEs the file holds (counted in the
// same pass, whatever is refused): XDE's time grows as their square.
bool readStepDirect(STEPControl_Reader& reader, const ProgressFn& progress, CadTree& tree, std::string& why, size_t& occurrences);

}  // namespace rtwall::detail
