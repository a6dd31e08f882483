// Polygon triangulation, one routine for every importer (OpenMesh's formats and VTK's). Internal
// to rtwall_mesh.
//
// CAD exporters write concave and keyhole polygons (a face with a hole, bridged to it by an edge
// walked once in each direction) as single faces, and a fan from the first corner fills them in:
// a ring becomes a disc. Convex polygons, by far the most common and nearly all quads, keep the
// fan after a cheap convexity test; the rest are ear-clipped in the plane that fits them best.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rtwall {
struct ImportReport;
}

namespace rtwall::detail {

enum class PolygonKind {
    Triangle,          // three corners: taken as they are
    Fan,               // strictly convex in its plane: a fan from the first corner
    EarClipped,        // concave, keyhole, or with repeated corners or collinear runs
    Degenerate,        // no area at all (every corner on one line or one point): a fan of
                       // zero-area triangles, which the importers count as degenerate
    SelfIntersecting,  // ear clipping found no ear for what was left (the boundary crosses
                       // itself, so no triangulation can follow it): that rest is fanned
};

// Turns polygons into triangles. One object per import: its scratch buffers are reused, so a
// file of millions of polygons allocates nothing per polygon once they have grown.
class PolygonTriangulator {
public:
    // The polygon's corners are vertices corners[0..n) (n >= 3) of `positions`, three floats per
    // vertex. Writes its triangles, three vertex indices each and wound like the polygon, to
    // triangles(), where they stay until the next call. Corners on a straight line between their
    // neighbours, and repeated corners, end up in no triangle: they add no area.
    //
    // The plane is the one of the polygon's Newell normal (its area vector, which fits a
    // non-planar polygon best); the polygon is projected onto the coordinate plane most nearly
    // parallel to it, which keeps the float coordinates exact and, for a planar polygon, gives
    // the same triangulation as the best-fit plane itself. Ear clipping treats the two visits of
    // a keyhole's bridge corners as separate corners at the same point, so a face with a
    // bridged hole keeps its hole.
    PolygonKind triangulate(const float* positions, const uint32_t* corners, size_t n);
    const std::vector<uint32_t>& triangles() const { return out_; }

private:
    bool strictlyConvex() const;
    void earClip();
    bool isEar(int a, int b, int c);
    void unlink(int i);
    void classify(int i);
    double cross(int a, int b, int c) const;
    bool flatInSpace(int a, int b, int c) const;
    void buildGrid();
    size_t cellOf(int i) const;
    void emit(int a, int b, int c);

    std::vector<uint32_t> out_;
    const float* positions_ = nullptr;
    // The polygon in its plane; prev_/next_ link the corners not yet cut off.
    std::vector<double> u_, v_;
    std::vector<uint32_t> id_;
    std::vector<int> prev_, next_;
    std::vector<uint8_t> alive_;
    std::vector<uint8_t> blocking_;  // reflex or flat: only such corners can lie inside an ear
    std::vector<int> blockers_;      // corners that may be blocking (pruned as they stop)
    size_t blockingCount_ = 0;       // live corners that are blocking
    std::vector<int> queue_;         // corners to try as ears, in order
    std::vector<size_t> queued_;     // per corner: its last place in queue_
    int start_ = 0;                  // a corner not yet cut off
    bool selfIntersecting_ = false;
    bool clipping_ = false;
    // For large polygons, a uniform grid over the blocking corners so that an ear test looks at
    // the corners near the ear only. Cells drop corners that stopped blocking as they are
    // scanned; a corner that starts blocking again goes back into its cell.
    int gridX_ = 0, gridY_ = 0;
    double gridU0_ = 0, gridV0_ = 0, gridInvU_ = 0, gridInvV_ = 0;
    std::vector<int> cellStart_, cellEnd_, cellItems_;
    std::vector<uint8_t> listed_;  // in blockers_ or in a grid cell
};

// Adds the outcome for one face to the report's polygon counts.
void countPolygon(ImportReport& report, PolygonKind kind);

}  // namespace rtwall::detail
