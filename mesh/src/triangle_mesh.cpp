#include "rtwall/mesh.h"

#include "mesh_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rtwall {

void Bounds3::extend(const Float3& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
}

void TriangleMesh::reserve(size_t vertices, size_t triangles) {
    positions_.reserve(3 * vertices);
    indices_.reserve(3 * triangles);
}

uint32_t TriangleMesh::addVertex(const Float3& p) {
    // Normals are attached once all vertices exist; a vertex added later would leave the
    // normal buffer one entry short, which Embree would read past.
    if (!normals_.empty() || !colors_.empty() || !uvs_.empty())
        throw std::logic_error("TriangleMesh::addVertex after setNormals, setColors or setUVs");
    if (vertexCount_ >= std::numeric_limits<uint32_t>::max())
        throw std::length_error("TriangleMesh: more vertices than 32-bit indices can address");
    positions_.push_back(p.x);
    positions_.push_back(p.y);
    positions_.push_back(p.z);
    return static_cast<uint32_t>(vertexCount_++);
}

void TriangleMesh::setPosition(uint32_t v, const Float3& p) {
    if (v >= vertexCount_)
        throw std::out_of_range("TriangleMesh::setPosition: index " + std::to_string(v) + " >= vertex count " +
                                std::to_string(vertexCount_));
    float* at = positions_.mutableData() + 3 * size_t(v);
    at[0] = p.x;
    at[1] = p.y;
    at[2] = p.z;
}

void TriangleMesh::addTriangle(uint32_t a, uint32_t b, uint32_t c) {
    // An index past the end would make Embree read outside the vertex buffer, so this
    // invariant is checked even though callers are required to validate first.
    if (a >= vertexCount_ || b >= vertexCount_ || c >= vertexCount_)
        throw std::out_of_range("TriangleMesh::addTriangle: index " +
                                std::to_string(std::max({a, b, c})) + " >= vertex count " +
                                std::to_string(vertexCount_));
    indices_.push_back(a);
    indices_.push_back(b);
    indices_.push_back(c);
}

void TriangleMesh::setNormals(std::vector<float> normalsXYZ) {
    if (normalsXYZ.size() != 3 * vertexCount_)
        throw std::invalid_argument("TriangleMesh::setNormals: got " + std::to_string(normalsXYZ.size()) +
                                    " floats for " + std::to_string(vertexCount_) + " vertices");
    normals_.assign(std::move(normalsXYZ));
}

void TriangleMesh::shrinkToFit() {
    positions_.shrinkToFit();
    normals_.shrinkToFit();
    indices_.shrinkToFit();
    colors_.shrinkToFit();
    uvs_.shrinkToFit();
}

void TriangleMesh::setUVs(std::vector<float> uv) {
    if (!uv.empty() && uv.size() != 2 * vertexCount_)
        throw std::invalid_argument("TriangleMesh::setUVs: got " + std::to_string(uv.size()) + " floats for " +
                                    std::to_string(vertexCount_) + " vertices");
    for (size_t i = 0; i < uv.size(); ++i)
        if (!std::isfinite(uv[i]))
            throw std::invalid_argument("TriangleMesh::setUVs: vertex " + std::to_string(i / 2) +
                                        " has a NaN or infinite texture coordinate");
    uvs_.assign(std::move(uv));
}

void TriangleMesh::setColors(std::vector<uint8_t> colorsRGB) {
    if (!colorsRGB.empty() && colorsRGB.size() != 3 * vertexCount_)
        throw std::invalid_argument("TriangleMesh::setColors: got " + std::to_string(colorsRGB.size()) +
                                    " bytes for " + std::to_string(vertexCount_) + " vertices");
    colors_.assign(std::move(colorsRGB));
}

Bounds3 TriangleMesh::bounds() const {
    Bounds3 b;
    for (size_t v = 0; v < vertexCount_; ++v) b.extend(position(v));
    return b;
}

size_t TriangleMesh::residentBytes() const {
    return positions_.heapBytes() + normals_.heapBytes() + indices_.heapBytes() + (colors_.empty() ? 0 : colors_.heapBytes()) +
           (uvs_.empty() ? 0 : uvs_.heapBytes()) + mappedBytes();
}

size_t TriangleMesh::mappedBytes() const {
    return positions_.viewBytes() + normals_.viewBytes() + indices_.viewBytes() + colors_.viewBytes() + uvs_.viewBytes();
}

namespace detail {

std::array<double, 3> chooseOrigin(const double lo[3], const double hi[3]) {
    double centre[3], farthest = 0, extent = 0;
    for (int k = 0; k < 3; ++k) {
        if (!(lo[k] <= hi[k])) return {0, 0, 0};
        centre[k] = 0.5 * (lo[k] + hi[k]);
        farthest = std::max(farthest, std::fabs(centre[k]));
        extent = std::max(extent, hi[k] - lo[k]);
    }
    if (farthest < 1024.0 || farthest <= extent) return {0, 0, 0};
    return {std::round(centre[0]), std::round(centre[1]), std::round(centre[2])};
}

void recentre(TriangleMesh& mesh) {
    const Bounds3 b = mesh.bounds();
    if (b.empty()) return;
    const double lo[3] = {b.lo.x, b.lo.y, b.lo.z}, hi[3] = {b.hi.x, b.hi.y, b.hi.z};
    const std::array<double, 3> o = chooseOrigin(lo, hi);
    if (o == std::array<double, 3>{0, 0, 0}) return;
    float* p = MeshAccess::positions(mesh).mutableData();
    for (size_t v = 0; v < mesh.vertexCount(); ++v)
        for (size_t k = 0; k < 3; ++k) p[3 * v + k] = float(double(p[3 * v + k]) - o[k]);
    const std::array<double, 3> old = mesh.origin();
    mesh.setOrigin({old[0] + o[0], old[1] + o[1], old[2] + o[2]});
}

bool zeroArea(const TriangleMesh& mesh, uint32_t a, uint32_t b, uint32_t c) {
    const Float3 pa = mesh.position(a), pb = mesh.position(b), pc = mesh.position(c);
    const double ux = double(pb.x) - pa.x, uy = double(pb.y) - pa.y, uz = double(pb.z) - pa.z;
    const double vx = double(pc.x) - pa.x, vy = double(pc.y) - pa.y, vz = double(pc.z) - pa.z;
    return uy * vz - uz * vy == 0.0 && uz * vx - ux * vz == 0.0 && ux * vy - uy * vx == 0.0;
}

}  // namespace detail

}  // namespace rtwall
