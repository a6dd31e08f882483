#include "rtwall/mesh.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace rtwall {

void Bounds3::extend(const Float3& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
}

void TriangleMesh::reserve(size_t vertices, size_t triangles) {
    positions_.reserve(3 * vertices + 1);
    indices_.reserve(3 * triangles);
}

uint32_t TriangleMesh::addVertex(const Float3& p) {
    // Normals are attached once all vertices exist; a vertex added later would leave the
    // normal buffer one entry short, which Embree would read past.
    if (!normals_.empty()) throw std::logic_error("TriangleMesh::addVertex after setNormals");
    if (vertexCount_ >= std::numeric_limits<uint32_t>::max())
        throw std::length_error("TriangleMesh: more vertices than 32-bit indices can address");
    // The padding float becomes x, and a new padding float goes on the end.
    positions_.back() = p.x;
    positions_.push_back(p.y);
    positions_.push_back(p.z);
    positions_.push_back(0.0f);
    return static_cast<uint32_t>(vertexCount_++);
}

void TriangleMesh::setPosition(uint32_t v, const Float3& p) {
    if (v >= vertexCount_)
        throw std::out_of_range("TriangleMesh::setPosition: index " + std::to_string(v) + " >= vertex count " +
                                std::to_string(vertexCount_));
    positions_[3 * size_t(v)] = p.x;
    positions_[3 * size_t(v) + 1] = p.y;
    positions_[3 * size_t(v) + 2] = p.z;
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
    if (normalsXYZ.empty()) {
        normals_.clear();
        return;
    }
    normalsXYZ.push_back(0.0f);
    normals_ = std::move(normalsXYZ);
}

Bounds3 TriangleMesh::bounds() const {
    Bounds3 b;
    for (size_t v = 0; v < vertexCount_; ++v) b.extend(position(v));
    return b;
}

size_t TriangleMesh::residentBytes() const {
    return positions_.capacity() * sizeof(float) + normals_.capacity() * sizeof(float) +
           indices_.capacity() * sizeof(uint32_t);
}

}  // namespace rtwall
