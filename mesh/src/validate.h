// Pre-pass over a mesh file's bytes before OpenMesh parses them. Internal to rtwall_mesh.
//
// OpenMesh's readers trust their input: header counts drive loops and allocations without
// looking at the file size, failed number parses leave streams in states the readers do not
// check, and a few malformed headers make them loop forever. Each validator here checks what
// the matching reader will rely on, so that every file that gets past it is one the reader
// handles correctly, and every file that does not is reported with its line or byte offset.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rtwall::detail {

enum class MeshFormat { Obj, Off, Ply, Stl, Om };

// An OBJ face that visits a vertex more than once, as a keyhole polygon visits its bridge corners.
// OpenMesh's OBJ reader keeps only the first visit of each vertex, which cuts the hole open, so
// the importer puts the corners back from here.
struct RepeatedCornerFace {
    size_t face;                    // among the faces the reader passes on (three distinct corners or more)
    std::vector<uint32_t> corners;  // every corner, zero-based, in the file's order
};

struct Prepass {
    bool binaryStl = false;        // the STL reader cannot tell binary from ASCII on a stream
    size_t vertices = 0;           // upper bound, for reserving the mesh buffers
    size_t triangles = 0;          // upper bound after triangulation
    size_t droppedDegenerate = 0;  // faces the reader drops because corners coincide (OBJ, STL)
    std::vector<RepeatedCornerFace> repeatedCorners;  // OBJ, in face order
    std::vector<std::string> warnings;                // "<name>:line N: ..." each
};

// Throws InputError naming `name` and, where known, the line or byte offset. May rewrite bytes
// of `data` in place into forms OpenMesh reads reliably: comments and OBJ material references
// become blanks and the PLY header is normalised, keeping sizes, offsets and line numbers; PLY
// face lists other than the vertex indices are removed, which shortens binary PLY data.
Prepass validateMesh(MeshFormat format, std::string& data, const std::string& name);

}  // namespace rtwall::detail
