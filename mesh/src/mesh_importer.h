// The importer OpenMesh's format readers write into (import.cpp runs them): it fills a
// TriangleMesh's buffers directly, triangulates polygons, checks every index it is handed and
// rebuilds what the readers pass as halfedges. Internal to rtwall_mesh; included by import.cpp
// only.
#pragma once

#include "rtwall/mesh.h"

#include "mesh_internal.h"
#include "triangulate.h"
#include "validate.h"

#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/Mesh/BaseKernel.hh>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace rtwall::detail {

// -----------------------------------------------------------------------------------------------
// Importer

class MeshImporter final : public OpenMesh::IO::BaseImporter {
public:
    using FaceHandle = OpenMesh::FaceHandle;

    // `cornerTexcoords`: the reader gives texture coordinates per face corner (OBJ: while it
    // parses a face, before add_face), not per vertex.
    MeshImporter(TriangleMesh& mesh, bool cornerTexcoords) : mesh_(mesh), cornerTexcoords_(cornerTexcoords) {}

    const std::string& error() const { return error_; }
    // Copies the polygon counts (polygonsTriangulated and its parts) into `report`.
    void reportPolygons(ImportReport& report) const {
        report.polygonsTriangulated = polygons_.polygonsTriangulated;
        report.polygonsFanned = polygons_.polygonsFanned;
        report.polygonsEarClipped = polygons_.polygonsEarClipped;
        report.polygonsDegenerate = polygons_.polygonsDegenerate;
        report.polygonsSelfIntersecting = polygons_.polygonsSelfIntersecting;
    }
    size_t degenerateTriangles() const { return degenerateTriangles_; }
    size_t seamVerticesSplit() const { return seamVerticesSplit_; }

    // OM files from format 2.0 on describe faces by halfedge loops; they are turned into
    // polygons once the whole file has been read.
    void resolveHalfedgeFaces() {
        const size_t halfedges = toVertex_.size();
        std::vector<OpenMesh::VertexHandle> corners;
        for (size_t f = 0; f < faceHalfedge_.size() && error_.empty(); ++f) {
            corners.clear();
            const int start = faceHalfedge_[f];
            int h = start;
            do {
                if (h < 0 || size_t(h) >= halfedges) {
                    fail("face " + std::to_string(f) + ": halfedge " + std::to_string(h) + " is out of range");
                    return;
                }
                if (corners.size() >= halfedges) {
                    fail("face " + std::to_string(f) + ": its halfedge loop does not close");
                    return;
                }
                corners.emplace_back(toVertex_[size_t(h)]);
                h = next_[size_t(h)];
            } while (h != start);
            addPolygon(corners, f);
        }
    }

    // Normals are kept only when every vertex got a usable one.
    void finishNormals() {
        if (normalsSet_ == 0 || normalsInvalid_ || normalsSet_ != mesh_.vertexCount()) return;
        normals_.resize(3 * mesh_.vertexCount());
        mesh_.setNormals(std::move(normals_));
    }

    // Colours likewise: only when every vertex got one (PLY red/green/blue, OFF COFF).
    void finishColors() {
        if (colorsSet_ == 0 || colorsSet_ != mesh_.vertexCount()) return;
        colors_.resize(3 * mesh_.vertexCount());
        mesh_.setColors(std::move(colors_));
    }

    // Texture coordinates: per vertex, every vertex needs one; per corner, every face needs them
    // (a face without, among faces with, is an error rather than a mesh half textured).
    void finishUVs() {
        if (!error_.empty()) return;
        if (cornerTexcoords_) {
            if (facesWithUV_ == 0) return;
            if (facesWithoutUV_ > 0) {
                fail("face " + std::to_string(firstFaceWithoutUV_) + " has no texture coordinates, but " +
                     std::to_string(facesWithUV_) + " other faces have them (give every face vt indices, or none)");
                return;
            }
        } else {
            if (uvsSet_ == 0) return;
            if (uvsSet_ != mesh_.vertexCount()) {
                fail(std::to_string(uvsSet_) + " of " + std::to_string(mesh_.vertexCount()) +
                     " vertices have texture coordinates (UV count mismatch)");
                return;
            }
        }
        uvs_.resize(2 * mesh_.vertexCount());  // vertices no face uses keep (0, 0)
        mesh_.setUVs(std::move(uvs_));
    }

    // -- geometry ------------------------------------------------------------------------------

    OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
        return add_vertex(OpenMesh::Vec3d(p[0], p[1], p[2]));
    }

    OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3d& p) override {
        const OpenMesh::VertexHandle vh = add_vertex();
        if (vh.is_valid()) storePoint(size_t(vh.idx()), p);
        return vh;
    }

    // PLY adds each vertex first and sets its coordinates afterwards.
    OpenMesh::VertexHandle add_vertex() override {
        if (!error_.empty()) return OpenMesh::VertexHandle();
        if (mesh_.vertexCount() >= size_t(std::numeric_limits<int>::max())) {
            fail("more vertices than the reader can address");
            return OpenMesh::VertexHandle();
        }
        return OpenMesh::VertexHandle(int(mesh_.addVertex({0, 0, 0})));
    }

    void set_point(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& p) override {
        if (!error_.empty()) return;
        if (!validVertex(vh)) {
            fail("coordinates for vertex index " + std::to_string(vh.idx()) + ", which is out of range");
            return;
        }
        storePoint(size_t(vh.idx()), OpenMesh::Vec3d(p[0], p[1], p[2]));
    }

    // OBJ: the faces whose repeated corners OpenMesh's reader removed (validate.h).
    void restoreRepeatedCorners(const std::vector<detail::RepeatedCornerFace>* faces) { repeated_ = faces; }

    FaceHandle add_face(const VHandles& corners) override {
        const VHandles& face = withRepeatedCorners(corners);
        if (!cornerTexcoords_) return addPolygon(face, faceCount_);
        const FaceHandle fh = addPolygon(resolveCornerUVs(face), faceCount_);
        pendingCorners_.clear();
        return fh;
    }

    void set_normal(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& n) override {
        set_normal(vh, OpenMesh::Vec3d(n[0], n[1], n[2]));
    }

    void set_normal(OpenMesh::VertexHandle vh, const OpenMesh::Vec3d& n) override {
        // An out-of-range handle here comes with a face that add_face reports.
        if (!error_.empty() || !validVertex(vh)) return;
        const size_t v = size_t(vh.idx());
        if (normals_.size() < 3 * (v + 1)) {
            normals_.resize(3 * std::max(v + 1, mesh_.vertexCount()));
            hasNormal_.resize(normals_.size() / 3);
        }
        const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!std::isfinite(length) || length == 0.0) {
            normalsInvalid_ = true;
            return;
        }
        for (int k = 0; k < 3; ++k) normals_[3 * v + size_t(k)] = float(n[k] / length);
        if (!hasNormal_[v]) {
            hasNormal_[v] = true;
            ++normalsSet_;
        }
    }

    // -- OM topology ---------------------------------------------------------------------------

    OpenMesh::HalfedgeHandle add_edge(OpenMesh::VertexHandle from, OpenMesh::VertexHandle to) override {
        // Halfedge 2e runs from -> to, halfedge 2e+1 back, as in OpenMesh's kernel.
        const auto first = int(toVertex_.size());
        toVertex_.push_back(to.idx());
        toVertex_.push_back(from.idx());
        next_.push_back(-1);
        next_.push_back(-1);
        return OpenMesh::HalfedgeHandle(first);
    }

    void set_next(OpenMesh::HalfedgeHandle h, OpenMesh::HalfedgeHandle next) override {
        if (h.idx() >= 0 && size_t(h.idx()) < next_.size()) next_[size_t(h.idx())] = next.idx();
    }

    FaceHandle add_face(OpenMesh::HalfedgeHandle h) override {
        faceHalfedge_.push_back(h.idx());
        return FaceHandle(int(faceHalfedge_.size() - 1));
    }

    // The OM reader refuses an importer without a kernel. This one stays empty, so the reader
    // finds no property to restore and skips every custom-property chunk.
    OpenMesh::BaseKernel* kernel() override { return &kernel_; }

    size_t n_vertices() const override { return mesh_.vertexCount(); }
    size_t n_faces() const override { return faceCount_ + faceHalfedge_.size(); }
    size_t n_edges() const override { return toVertex_.size() / 2; }

    // -- ignored: rtwall reads no face texture coordinates, status bits or face normals -------

    void add_face_texcoords(FaceHandle, OpenMesh::VertexHandle, const std::vector<OpenMesh::Vec2f>&) override {}
    void add_face_texcoords(FaceHandle, OpenMesh::VertexHandle, const std::vector<OpenMesh::Vec3f>&) override {}
    void set_face_texindex(FaceHandle, int) override {}
    void set_halfedge(OpenMesh::VertexHandle, OpenMesh::HalfedgeHandle) override {}
    void set_color(OpenMesh::VertexHandle vh, const OpenMesh::Vec3uc& c) override { storeColor(vh, c[0], c[1], c[2]); }
    void set_color(OpenMesh::VertexHandle vh, const OpenMesh::Vec4uc& c) override { storeColor(vh, c[0], c[1], c[2]); }
    void set_color(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& c) override {
        storeColor(vh, unitToByte(c[0]), unitToByte(c[1]), unitToByte(c[2]));
    }
    void set_color(OpenMesh::VertexHandle vh, const OpenMesh::Vec4f& c) override {
        storeColor(vh, unitToByte(c[0]), unitToByte(c[1]), unitToByte(c[2]));
    }
    void set_texcoord(OpenMesh::VertexHandle vh, const OpenMesh::Vec2f& t) override {
        if (!error_.empty()) return;
        if (cornerTexcoords_)
            pendingCorners_.push_back({vh.idx(), t[0], t[1]});
        else if (validVertex(vh))
            storeUV(size_t(vh.idx()), t[0], t[1]);
    }
    // The OBJ reader sends a 3D "vt u v w" as (u, v) first, then again with w: w is dropped.
    void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
    void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec2f&) override {}
    void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec3f&) override {}
    void set_status(OpenMesh::VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_status(OpenMesh::HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_status(OpenMesh::EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_status(FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_face(OpenMesh::HalfedgeHandle, FaceHandle) override {}
    void request_face_texcoords2D() override {}
    void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3uc&) override {}
    void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4uc&) override {}
    void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3f&) override {}
    void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4f&) override {}
    void set_normal(FaceHandle, const OpenMesh::Vec3f&) override {}
    void set_normal(FaceHandle, const OpenMesh::Vec3d&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec3uc&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec4uc&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec3f&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec4f&) override {}
    void add_texture_information(int, std::string) override {}

private:
    // Errors are recorded, not thrown: an exception must not unwind through the reader, which
    // may be holding OpenMesh's global log streams switched off. After the first error every
    // callback is ignored.
    void fail(std::string what) {
        if (error_.empty()) error_ = std::move(what);
    }

    // Float colours are fractions of full intensity; NaN becomes 0.
    static uint8_t unitToByte(float f) { return f > 0.0f ? uint8_t(std::lround(std::min(f, 1.0f) * 255.0f)) : 0; }

    void storeColor(OpenMesh::VertexHandle vh, uint8_t r, uint8_t g, uint8_t b) {
        if (!error_.empty() || !validVertex(vh)) return;
        const size_t v = size_t(vh.idx());
        if (colors_.size() < 3 * (v + 1)) {
            colors_.resize(3 * std::max(v + 1, mesh_.vertexCount()));
            hasColor_.resize(colors_.size() / 3);
        }
        colors_[3 * v] = r;
        colors_[3 * v + 1] = g;
        colors_[3 * v + 2] = b;
        if (!hasColor_[v]) {
            hasColor_[v] = true;
            ++colorsSet_;
        }
    }

    void storeUV(size_t v, float u, float w) {
        if (!std::isfinite(u) || !std::isfinite(w)) {
            fail("vertex " + std::to_string(v) + " has a NaN or infinite texture coordinate");
            return;
        }
        if (uvs_.size() < 2 * (v + 1)) {
            uvs_.resize(2 * std::max(v + 1, mesh_.vertexCount()));
            hasUV_.resize(uvs_.size() / 2);
        }
        uvs_[2 * v] = u;
        uvs_[2 * v + 1] = w;
        if (!hasUV_[v]) {
            hasUV_[v] = true;
            ++uvsSet_;
        }
    }

    // The face as the file gives it, where the reader removed repeated corners: a keyhole
    // polygon visits its bridge corners twice, and without the second visits its hole is cut
    // open. The pre-pass's corners must be the reader's once repeats are removed, or the two
    // disagree about the file and it is refused.
    const VHandles& withRepeatedCorners(const VHandles& corners) {
        if (!error_.empty() || !repeated_ || nextRepeated_ >= repeated_->size() || (*repeated_)[nextRepeated_].face != faceCount_)
            return corners;
        const std::vector<uint32_t>& full = (*repeated_)[nextRepeated_++].corners;
        // The first visit of each vertex, found by sorting (vertex, corner) pairs.
        visits_.clear();
        for (size_t k = 0; k < full.size(); ++k) visits_.emplace_back(full[k], uint32_t(k));
        std::sort(visits_.begin(), visits_.end());
        firstVisit_.assign(full.size(), 0);
        for (size_t k = 0; k < visits_.size(); ++k)
            if (k == 0 || visits_[k].first != visits_[k - 1].first) firstVisit_[visits_[k].second] = 1;
        restored_.clear();
        size_t kept = 0;
        bool same = true;
        for (size_t k = 0; k < full.size(); ++k) {
            restored_.emplace_back(int(full[k]));
            if (!firstVisit_[k]) continue;
            same = same && kept < corners.size() && corners[kept].idx() == int(full[k]);
            ++kept;
        }
        if (!same || kept != corners.size()) {
            fail("face " + std::to_string(faceCount_) + ": OpenMesh read other corners than the file lists");
            return corners;
        }
        return restored_;
    }

    // OBJ corners: each corner's (u, v) goes to its vertex; a vertex that already has another
    // (u, v) (a texture seam) is split: the corner gets a copy of the vertex (position, normal,
    // colour) with its own (u, v), found again by the chain of copies when another corner has
    // the same pair. Returns the face's corners with the copies in place.
    const VHandles& resolveCornerUVs(const VHandles& corners) {
        resolved_ = corners;
        if (!error_.empty()) return resolved_;
        const size_t face = faceCount_;
        if (pendingCorners_.empty()) {
            if (facesWithoutUV_++ == 0) firstFaceWithoutUV_ = face;
            return resolved_;
        }
        ++facesWithUV_;
        for (size_t k = 0; k < resolved_.size(); ++k) {
            auto& corner = resolved_[k];
            if (!validVertex(corner)) return resolved_;  // addPolygon reports it
            // Corner k's own (u, v) where every corner has one: a vertex visited twice (a keyhole's
            // bridge corner) may have a different one on each visit.
            const auto it = k < pendingCorners_.size() && pendingCorners_[k].vertex == corner.idx()
                                ? pendingCorners_.begin() + long(k)
                                : std::find_if(pendingCorners_.begin(), pendingCorners_.end(),
                                               [&](const PendingCorner& p) { return p.vertex == corner.idx(); });
            if (it == pendingCorners_.end()) {
                fail("face " + std::to_string(face) + ": vertex " + std::to_string(corner.idx() + 1) +
                     " has no texture coordinate, but other corners of the face have one");
                return resolved_;
            }
            if (!std::isfinite(it->u) || !std::isfinite(it->v)) {
                fail("face " + std::to_string(face) + ": a NaN or infinite texture coordinate");
                return resolved_;
            }
            size_t v = size_t(corner.idx());
            if (v >= hasUV_.size() || !hasUV_[v]) {
                storeUV(v, it->u, it->v);
                continue;
            }
            while (!(uvs_[2 * v] == it->u && uvs_[2 * v + 1] == it->v)) {
                if (v < seamNext_.size() && seamNext_[v] != kNoCopy) {
                    v = seamNext_[v];
                    continue;
                }
                v = splitVertex(v);
                if (!error_.empty()) return resolved_;
                storeUV(v, it->u, it->v);
                break;
            }
            corner = OpenMesh::VertexHandle(int(v));
        }
        return resolved_;
    }

    // A copy of vertex `v` at the end of the chain of its copies.
    size_t splitVertex(size_t v) {
        if (mesh_.vertexCount() >= size_t(std::numeric_limits<int>::max())) {
            fail("more vertices than the reader can address");
            return v;
        }
        const size_t copy = mesh_.addVertex(mesh_.position(v));
        ++seamVerticesSplit_;
        if (seamNext_.size() <= copy) seamNext_.resize(copy + 1, kNoCopy);
        seamNext_[v] = uint32_t(copy);
        // The copy takes the vertex's normal and colour where it has them.
        auto copyAttribute = [&](auto& values, std::vector<bool>& has, size_t& set) {
            if (v >= has.size() || !has[v]) return;
            values.resize(std::max(values.size(), 3 * (copy + 1)));
            has.resize(values.size() / 3);
            for (size_t k = 0; k < 3; ++k) values[3 * copy + k] = values[3 * v + k];
            has[copy] = true;
            ++set;
        };
        copyAttribute(normals_, hasNormal_, normalsSet_);
        copyAttribute(colors_, hasColor_, colorsSet_);
        return copy;
    }

    bool validVertex(OpenMesh::VertexHandle vh) const { return vh.idx() >= 0 && size_t(vh.idx()) < mesh_.vertexCount(); }

    void storePoint(size_t v, const OpenMesh::Vec3d& p) {
        // Doubles beyond float range would become infinities in the float buffer.
        for (int k = 0; k < 3; ++k) {
            if (!std::isfinite(p[k]) || std::fabs(p[k]) > double(std::numeric_limits<float>::max())) {
                fail("vertex " + std::to_string(v) + " has a NaN or infinite coordinate");
                return;
            }
        }
        mesh_.setPosition(uint32_t(v), {float(p[0]), float(p[1]), float(p[2])});
    }

    FaceHandle addPolygon(const VHandles& corners, size_t face) {
        if (!error_.empty()) return FaceHandle();
        if (corners.size() < 3) {
            fail("face " + std::to_string(face) + " has fewer than 3 corners");
            return FaceHandle();
        }
        for (const auto vh : corners) {
            if (!validVertex(vh)) {
                fail("face " + std::to_string(face) + ": vertex index " + std::to_string(vh.idx()) +
                     " is out of range (the file has " + std::to_string(mesh_.vertexCount()) + " vertices)");
                return FaceHandle();
            }
        }
        polygon_.clear();
        for (const auto vh : corners) polygon_.push_back(uint32_t(vh.idx()));
        const detail::PolygonKind kind = triangulator_.triangulate(mesh_.positions(), polygon_.data(), polygon_.size());
        detail::countPolygon(polygons_, kind);
        const std::vector<uint32_t>& t = triangulator_.triangles();
        for (size_t k = 0; k + 2 < t.size(); k += 3) {
            if (detail::zeroArea(mesh_, t[k], t[k + 1], t[k + 2])) ++degenerateTriangles_;
            mesh_.addTriangle(t[k], t[k + 1], t[k + 2]);
        }
        ++faceCount_;
        return FaceHandle(int(faceCount_ - 1));
    }

    TriangleMesh& mesh_;
    std::string error_;
    size_t faceCount_ = 0;
    ImportReport polygons_;  // the polygon counts only
    size_t degenerateTriangles_ = 0;
    detail::PolygonTriangulator triangulator_;
    std::vector<uint32_t> polygon_;

    std::vector<float> normals_;
    std::vector<bool> hasNormal_;
    size_t normalsSet_ = 0;
    bool normalsInvalid_ = false;

    std::vector<uint8_t> colors_;
    std::vector<bool> hasColor_;
    size_t colorsSet_ = 0;

    struct PendingCorner {
        int vertex;
        float u, v;
    };
    static constexpr uint32_t kNoCopy = 0xFFFFFFFFu;
    bool cornerTexcoords_ = false;
    std::vector<float> uvs_;
    std::vector<bool> hasUV_;
    size_t uvsSet_ = 0;
    std::vector<PendingCorner> pendingCorners_;  // the face being read (OBJ)
    VHandles resolved_;
    const std::vector<detail::RepeatedCornerFace>* repeated_ = nullptr;
    size_t nextRepeated_ = 0;
    VHandles restored_;
    std::vector<std::pair<uint32_t, uint32_t>> visits_;
    std::vector<uint8_t> firstVisit_;
    std::vector<uint32_t> seamNext_;  // per vertex: its next copy with another (u, v), or kNoCopy
    size_t seamVerticesSplit_ = 0;
    size_t facesWithUV_ = 0, facesWithoutUV_ = 0, firstFaceWithoutUV_ = 0;

    std::vector<int> toVertex_;      // per halfedge
    std::vector<int> next_;          // per halfedge
    std::vector<int> faceHalfedge_;  // per face
    OpenMesh::BaseKernel kernel_;
};

}  // namespace rtwall::detail
