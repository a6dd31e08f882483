// loadMesh: OpenMesh's format readers feeding rtwall::TriangleMesh directly.
//
// The readers talk to a BaseImporter; ours writes straight into the TriangleMesh buffers, so no
// OpenMesh mesh (and no second copy of the geometry) is ever built. Every file first passes
// validateMesh (validate.cpp), which is what makes the readers safe to run on it; the importer
// still checks every index it is handed, because that is the last line between a file and an
// out-of-bounds read in Embree.
#include "rtwall/mesh.h"

#include "import_vtk.h"
#include "mesh_internal.h"
#include "triangulate.h"
#include "validate.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/IO/reader/OBJReader.hh>
#include <OpenMesh/Core/IO/reader/OFFReader.hh>
#include <OpenMesh/Core/IO/reader/OMReader.hh>
#include <OpenMesh/Core/IO/reader/PLYReader.hh>
#include <OpenMesh/Core/IO/reader/STLReader.hh>
#include <OpenMesh/Core/Mesh/BaseKernel.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <mutex>
#include <new>
#include <optional>
#include <sstream>
#include <streambuf>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;
namespace OmIo = OpenMesh::IO;
using detail::MeshFormat;

// -----------------------------------------------------------------------------------------------
// Importer

class MeshImporter final : public OmIo::BaseImporter {
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

// -----------------------------------------------------------------------------------------------
// OpenMesh plumbing

// A read-only, seekable stream over the validated buffer: the readers seek (OBJ reads twice,
// PLY re-reads its header) and the buffer is not copied.
class BufferStreamBuf final : public std::streambuf {
public:
    explicit BufferStreamBuf(std::string& data) { setg(data.data(), data.data(), data.data() + data.size()); }

protected:
    pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
        if (!(which & std::ios_base::in)) return pos_type(off_type(-1));
        const off_type size = egptr() - eback();
        off_type target = off;
        if (dir == std::ios_base::cur) target += gptr() - eback();
        if (dir == std::ios_base::end) target += size;
        if (target < 0 || target > size) return pos_type(off_type(-1));
        setg(eback(), eback() + target, egptr());
        return pos_type(target);
    }
    pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
        return seekoff(off_type(pos), std::ios_base::beg, which);
    }
};

// OpenMesh reports through its global omerr/omlog streams. While a file is read they go to a
// string instead of the terminal, so the user sees our one-line error and not the reader's.
//
// omerr's connect() allocates a target that disconnect() forgets without freeing, so connecting
// a buffer per import (and reconnecting std::cerr after it) leaked two targets a file. Instead
// one sink is connected once for the process: it writes to the import's buffer while a capture
// is open and to std::cerr (where omerr went before) otherwise. Captures run under
// openMeshMutex().
class OpenMeshErrSink {
public:
    static OpenMeshErrSink& instance() {
        static OpenMeshErrSink* sink = [] {
            auto* s = new OpenMeshErrSink;  // lives as long as omerr, which keeps a reference
            s->toCerr_ = omerr().disconnect(std::cerr);
            omerr().connect(*s);
            return s;
        }();
        return *sink;
    }
    void capture(std::ostringstream* text) { text_ = text; }
    friend OpenMeshErrSink& operator<<(OpenMeshErrSink& s, const std::string& line) {
        if (s.text_) *s.text_ << line;
        else if (s.toCerr_) std::cerr << line;
        return s;
    }

private:
    std::ostringstream* text_ = nullptr;
    bool toCerr_ = false;
};

class CaptureOpenMeshLog {
public:
    CaptureOpenMeshLog() {
        OpenMeshErrSink::instance().capture(&text_);
        errEnabled_ = omerr().is_enabled();
        omerr().enable();
        logEnabled_ = omlog().is_enabled();
        outEnabled_ = omout().is_enabled();
        omlog().disable();
        omout().disable();
    }
    ~CaptureOpenMeshLog() {
        omerr().flush();
        OpenMeshErrSink::instance().capture(nullptr);
        // Set both ways: a reader that switched it off and then threw leaves it off.
        if (errEnabled_)
            omerr().enable();
        else
            omerr().disable();
        if (logEnabled_) omlog().enable();
        if (outEnabled_) omout().enable();
    }
    CaptureOpenMeshLog(const CaptureOpenMeshLog&) = delete;
    CaptureOpenMeshLog& operator=(const CaptureOpenMeshLog&) = delete;

    // The first line the reader wrote, for an error message. Readers echo bytes of the file,
    // so anything unprintable is replaced.
    std::string firstLine() {
        omerr().flush();
        std::string line;
        std::istringstream in(text_.str());
        while (std::getline(in, line) && line.find_first_not_of(" \t\r") == std::string::npos) {
        }
        for (char& c : line)
            if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
        return line.substr(0, 200);
    }

private:
    std::ostringstream text_;
    bool errEnabled_ = true, logEnabled_ = true, outEnabled_ = true;
};

// The readers are process-wide singletons with per-file state, and the log streams are global.
std::mutex& openMeshMutex() {
    static std::mutex mutex;
    return mutex;
}

// Names each reader's singleton, so that a static OpenMesh build links and registers them all,
// and confirms they are there: without them IOManager would fail every file the same way.
void requireReaders() {
    static const bool registered = [] {
        OmIo::OBJReader();
        OmIo::OFFReader();
        OmIo::PLYReader();
        OmIo::STLReader();
        OmIo::OMReader();
        // can_read() would sniff a file named dummy.<ext>; the filter list names every
        // registered reader's extensions without touching the disk.
        const std::string& filters = OmIo::IOManager().qt_read_filters();
        for (const char* ext : {"*.obj ", "*.off ", "*.ply ", "*.stl ", "*.om "})
            if (filters.find(ext) == std::string::npos) return false;
        return true;
    }();
    if (!registered) throw std::logic_error("rtwall: OpenMesh's mesh readers are not registered");
}

// -----------------------------------------------------------------------------------------------
// Files

struct FormatInfo {
    MeshFormat format;
    const char* name;
};

FormatInfo formatFromExtension(const fs::path& file, const std::string& name) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".obj") return {MeshFormat::Obj, "obj"};
    if (ext == ".off") return {MeshFormat::Off, "off"};
    if (ext == ".ply") return {MeshFormat::Ply, "ply"};
    if (ext == ".stl") return {MeshFormat::Stl, "stl"};
    if (ext == ".om") return {MeshFormat::Om, "om"};
    throw InputError(name + ": unknown mesh format " + (ext.empty() ? std::string("(no extension)") : "'" + ext + "'") +
                     "; expected .obj, .off, .ply, .stl, .om, .vtk, .vtp, .vtu or .wrl");
}

bool isVtkExtension(const fs::path& file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".vtk" || ext == ".vtp" || ext == ".vtu" || ext == ".wrl";
}

void requireRegularFile(const fs::path& file, const std::string& name) {
    std::error_code ec;
    const fs::file_status st = fs::status(file, ec);
    if (ec && ec != std::errc::no_such_file_or_directory) throw InputError(name + ": cannot access: " + ec.message());
    if (!fs::exists(st)) throw InputError(name + ": no such file");
    if (fs::is_directory(st)) throw InputError(name + ": is a directory, not a mesh file");
    // Devices and pipes have no size to check against and may never end.
    if (!fs::is_regular_file(st)) throw InputError(name + ": not a regular file");
}

std::string readFile(const fs::path& file, const std::string& name) {
    std::error_code ec;
    const uintmax_t size = fs::file_size(file, ec);
    if (ec) throw InputError(name + ": cannot read: " + ec.message());
    if (size == 0) throw InputError(name + ": file is empty");

    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(name + ": cannot open: " + std::error_code(errno, std::generic_category()).message());
    std::string data;
    try {
        data.resize(size_t(size));
    } catch (const std::exception&) {
        throw InputError(name + ": file too large to load (" + std::to_string(size) + " bytes)");
    }
    in.read(data.data(), std::streamsize(size));
    if (size_t(in.gcount()) != size)
        throw InputError(name + ": read only " + std::to_string(in.gcount()) + " of " + std::to_string(size) + " bytes");
    return data;
}

std::string readPrefix(const fs::path& file, size_t bytes) {
    std::ifstream in(file, std::ios::binary);
    std::string prefix(bytes, '\0');
    in.read(prefix.data(), std::streamsize(bytes));
    prefix.resize(size_t(std::max<std::streamsize>(in.gcount(), 0)));
    return prefix;
}

std::string firstToken(const std::string& text) {
    const size_t end = text.find_first_of(" \t\r\n#");
    return text.substr(0, end);
}

TriangleMesh importOpenMesh(const fs::path& file, const FormatInfo& format, std::string& data,
                            const std::string& name, ImportReport* report) {
    const detail::Prepass pre = detail::validateMesh(format.format, data, name);
    requireReaders();

    TriangleMesh mesh;
    // The pre-pass counts are backed by data; the cap (every vertex and triangle takes some
    // bytes of the file) only guards this promise against a slip in a validator.
    mesh.reserve(std::min(pre.vertices, data.size() / 4), std::min(pre.triangles, data.size()));
    MeshImporter importer(mesh, format.format == MeshFormat::Obj);
    importer.restoreRepeatedCorners(&pre.repeatedCorners);
    bool ok = false;
    std::string readerMessage;
    {
        const std::lock_guard<std::mutex> lock(openMeshMutex());
        CaptureOpenMeshLog log;
        BufferStreamBuf buffer(data);
        std::istream in(&buffer);
        OmIo::Options options = OmIo::Options::VertexNormal;
        options += OmIo::Options::VertexColor;
        options += OmIo::Options::VertexTexCoord;
        if (pre.binaryStl) options += OmIo::Options::Binary;
        try {
            // The OFF reader takes its header flags (normals, colours, binary) from sniffing a
            // file by name, a step IOManager skips for streams; without it the flags would be
            // whatever the last OFF file read in this process had. So the file itself is sniffed,
            // and must still start as the validated buffer does.
            if (format.format == MeshFormat::Off) {
                if (!OmIo::OFFReader().can_u_read(name)) throw InputError(name + ": OpenMesh does not recognise the OFF header");
                if (firstToken(readPrefix(file, 256)) != firstToken(data))
                    throw InputError(name + ": the file changed while it was being read");
            }
            ok = OmIo::IOManager().read(in, format.name, importer, options);
        } catch (const InputError&) {
            throw;
        } catch (const std::bad_alloc&) {
            throw InputError(name + ": out of memory while reading");
        } catch (const std::exception& e) {
            throw InputError(name + ": OpenMesh failed: " + e.what());
        }
        if (!ok) readerMessage = log.firstLine();
    }
    if (!importer.error().empty()) throw InputError(name + ": " + importer.error());
    if (!ok)
        throw InputError(name + ": OpenMesh could not read the file" + (readerMessage.empty() ? "" : " (" + readerMessage + ")"));
    importer.resolveHalfedgeFaces();
    if (!importer.error().empty()) throw InputError(name + ": " + importer.error());
    if (mesh.triangleCount() == 0) throw InputError(name + ": contains no triangles");
    importer.finishNormals();
    importer.finishColors();
    importer.finishUVs();
    if (!importer.error().empty()) throw InputError(name + ": " + importer.error());
    // The reserve above follows the pre-pass, which counts STL corners before they are merged
    // into shared vertices (about six times too many): spare capacity would stay resident for
    // as long as the mesh is rendered.
    mesh.shrinkToFit();

    if (report) {
        report->format = format.name;
        importer.reportPolygons(*report);
        report->warnings = pre.warnings;
        report->degenerateTriangles = importer.degenerateTriangles() + pre.droppedDegenerate;
        report->seamVerticesSplit = importer.seamVerticesSplit();
    }
    for (const std::string& warning : pre.warnings) std::cerr << "warning: " + warning + "\n";
    detail::recentre(mesh);
    return mesh;
}

}  // namespace

namespace detail {

// One entry for every format: VTK files are recognised by their bytes, the rest by extension.
TriangleMesh importMesh(const fs::path& file, ImportReport* report) {
    const std::string name = file.string();
    requireRegularFile(file, name);
    const bool vtkExt = isVtkExtension(file);
    std::optional<FormatInfo> format;
    std::string unknownFormat;
    if (!vtkExt) {
        try {
            format = formatFromExtension(file, name);
        } catch (const InputError& e) {
            unknownFormat = e.what();  // unless the content says VTK
        }
    }
    std::string data = readFile(file, name);
    const VtkKind kind = sniffVtk(data);
    if (kind != VtkKind::None) {
        ImportReport local;
        TriangleMesh mesh = loadVtk(kind, data, name, report ? *report : local);
        return mesh;
    }
    if (vtkExt)
        throw InputError(name + (data.rfind("#VRML V1.0", 0) == 0
                                     ? std::string(": VRML 1.0 is not supported (VTK reads VRML 2.0, '#VRML V2.0 utf8')")
                                     : std::string(": not a VTK file (expected '# vtk DataFile Version', an XML <VTKFile> of type PolyData or UnstructuredGrid, or '#VRML V2.0')")));
    if (!format) throw InputError(unknownFormat);
    return importOpenMesh(file, *format, data, name, report);
}

}  // namespace detail

}  // namespace rtwall
