// VTK-based importers (legacy .vtk, XML .vtp and .vtu, VRML 2.0 .wrl). Internal to rtwall_mesh: VTK stays
// private to this library and nothing of it appears in rtwall/mesh.h.
#pragma once

#include "rtwall/mesh.h"

#include <string>
#include <string_view>
#include <vector>

namespace rtwall::detail {

enum class VtkKind { None, Legacy, XmlPolyData, XmlUnstructuredGrid, Vrml };

// What the bytes of a file say it is, whatever its extension.
VtkKind sniffVtk(std::string_view head);

// Reads a VTK file whose bytes are `data` (already read from disk, so that size checks and the
// reader see the same bytes). Polygons and triangle strips become triangles, unstructured grids
// are reduced to their outer surface, vertices and lines are skipped and counted. Coordinates are
// read in double precision and recentred (see TriangleMesh::origin) before they are rounded to
// float. Throws InputError naming the file and the place.
TriangleMesh loadVtk(VtkKind kind, const std::string& data, const std::string& name, ImportReport& report);

// Checks the counts a VTK header declares against the size of the file, before VTK allocates
// anything for them. Exposed for the tests.
void checkVtkCounts(VtkKind kind, std::string_view data, const std::string& name);

// Header text, shared by the count checks (import_vtk_counts.cpp) and the readers.
namespace vtkheader {
[[noreturn]] void fail(const std::string& name, const std::string& what);
bool startsWith(std::string_view s, std::string_view p);
// The line from `pos`, at most 256 characters, without its line end.
std::string_view lineAt(std::string_view data, size_t pos);
// Splits a header line into whitespace-separated tokens.
std::vector<std::string_view> tokens(std::string_view line);
}  // namespace vtkheader

}  // namespace rtwall::detail
