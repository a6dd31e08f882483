// rtwall mesh library: the one public header.
//
// Importers read mesh files (through OpenMesh) straight into the flat buffers that the
// engine hands to Embree as shared buffers, so an imported model exists once in memory.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace rtwall {

// A user-facing input problem (bad file, bad config, bad argument). what() is one line:
// "<file>:<line or offset>: <what is wrong>", or "<file>: <what is wrong>" where no place is known.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct Float3 {
    float x = 0, y = 0, z = 0;
};

struct Bounds3 {
    Float3 lo{+INFINITY, +INFINITY, +INFINITY};
    Float3 hi{-INFINITY, -INFINITY, -INFINITY};
    bool empty() const { return lo.x > hi.x; }
    void extend(const Float3& p);
};

// Indexed triangle mesh in exactly the layout Embree reads: float3 positions (12-byte stride)
// with 4 bytes of tail padding, because Embree loads the last vertex with a 16-byte read;
// uint32 triangle indices. Optional per-vertex normals use the same layout.
class TriangleMesh {
public:
    size_t vertexCount() const { return vertexCount_; }
    size_t triangleCount() const { return indices_.size() / 3; }
    bool hasNormals() const { return !normals_.empty(); }

    const float* positions() const { return positions_.data(); }  // 3 floats per vertex
    const float* normals() const { return normals_.empty() ? nullptr : normals_.data(); }
    const uint32_t* indices() const { return indices_.data(); }  // 3 per triangle

    Float3 position(size_t v) const { return {positions_[3 * v], positions_[3 * v + 1], positions_[3 * v + 2]}; }
    Float3 normal(size_t v) const { return {normals_[3 * v], normals_[3 * v + 1], normals_[3 * v + 2]}; }

    void reserve(size_t vertices, size_t triangles);
    uint32_t addVertex(const Float3& p);
    void setPosition(uint32_t v, const Float3& p);         // v must be < vertexCount()
    void addTriangle(uint32_t a, uint32_t b, uint32_t c);  // indices must already be valid
    void setNormals(std::vector<float> normalsXYZ);       // 3 per vertex (padding is added here)

    Bounds3 bounds() const;
    size_t residentBytes() const;  // heap bytes of the buffers

private:
    std::vector<float> positions_{0.0f};  // always ends with one padding float
    std::vector<float> normals_;          // empty, or 3 per vertex + one padding float
    std::vector<uint32_t> indices_;
    size_t vertexCount_ = 0;
};

struct ImportReport {
    std::string format;               // "obj", "off", "ply", "stl", "om"
    size_t polygonsTriangulated = 0;  // faces with more than three corners, fan-triangulated
    size_t degenerateTriangles = 0;   // zero-area triangles (kept, never hit, counted), plus faces
                                      // the OBJ and STL readers drop because corners repeat
};

// Reads OBJ, OFF, PLY (ASCII/binary), STL (ASCII/binary) and OM. The format is chosen from
// the extension and checked against the content. Throws InputError on any malformed input,
// naming the file and the place; never crashes, never hangs, never allocates much more than
// the file's size before the data has been validated. Polygons are fan-triangulated. Vertex
// normals are kept, normalised, only when the file gives every vertex one. STL corners at the
// same position become one shared vertex, as in OpenMesh's reader, so an STL mesh is indexed
// like the others. Safe to call from several threads (the OpenMesh part runs one at a time).
TriangleMesh loadMesh(const std::filesystem::path& file, ImportReport* report = nullptr);

// Procedural shapes for scenes, tests and benchmarks, wound counter-clockwise seen from
// outside. Sizes out of range throw std::invalid_argument.
TriangleMesh makeSphere(int rings, int segments);                 // unit sphere at the origin, with normals;
                                                                  // rings >= 2, segments >= 3
TriangleMesh makeBox();                                           // [-1,1]^3, 12 triangles
TriangleMesh makeQuad();                                          // [-1,1]^2 in the xz-plane, normal +y
// A tube of tubeRadius, with normals, around a (p,q) torus knot that lies within the unit ball.
TriangleMesh makeTorusKnot(int p, int q, int segments, int sides, float tubeRadius);

}  // namespace rtwall
