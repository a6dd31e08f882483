#include "triangulate.h"

#include "rtwall/mesh.h"

#include <algorithm>
#include <cmath>

namespace rtwall::detail {
namespace {

// Above this many blocking corners an ear test looks them up in a grid instead of trying each.
constexpr size_t kGridMinBlockers = 32;

// Twice the signed area of the triangle (a, b, p): positive when it turns left (counter-clockwise).
inline double orient(double ua, double va, double ub, double vb, double up, double vp) {
    return (ub - ua) * (vp - va) - (vb - va) * (up - ua);
}

}  // namespace

double PolygonTriangulator::cross(int a, int b, int c) const {
    return orient(u_[size_t(a)], v_[size_t(a)], u_[size_t(b)], v_[size_t(b)], u_[size_t(c)], v_[size_t(c)]);
}

// Whether the corners are on one line in space (not only in the plane they were projected to).
bool PolygonTriangulator::flatInSpace(int a, int b, int c) const {
    const float* pa = positions_ + 3 * size_t(id_[size_t(a)]);
    const float* pb = positions_ + 3 * size_t(id_[size_t(b)]);
    const float* pc = positions_ + 3 * size_t(id_[size_t(c)]);
    double ab[3], ac[3];
    for (int k = 0; k < 3; ++k) {
        ab[k] = double(pb[k]) - double(pa[k]);
        ac[k] = double(pc[k]) - double(pa[k]);
    }
    return ab[1] * ac[2] - ab[2] * ac[1] == 0 && ab[2] * ac[0] - ab[0] * ac[2] == 0 && ab[0] * ac[1] - ab[1] * ac[0] == 0;
}

void PolygonTriangulator::emit(int a, int b, int c) {
    out_.push_back(id_[size_t(a)]);
    out_.push_back(id_[size_t(b)]);
    out_.push_back(id_[size_t(c)]);
}

PolygonKind PolygonTriangulator::triangulate(const float* positions, const uint32_t* corners, size_t n) {
    out_.clear();
    if (n == 3) {
        out_.assign(corners, corners + 3);
        return PolygonKind::Triangle;
    }
    // Newell's normal, with coordinates taken relative to the first corner so that a polygon far
    // from the origin keeps its small differences.
    const float* o = positions + 3 * size_t(corners[0]);
    double normal[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i) {
        const float* p = positions + 3 * size_t(corners[i]);
        const float* q = positions + 3 * size_t(corners[i + 1 == n ? 0 : i + 1]);
        double a[3], b[3];
        for (int k = 0; k < 3; ++k) {
            a[k] = double(p[k]) - double(o[k]);
            b[k] = double(q[k]) - double(o[k]);
        }
        normal[0] += (a[1] - b[1]) * (a[2] + b[2]);
        normal[1] += (a[2] - b[2]) * (a[0] + b[0]);
        normal[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    if (normal[0] == 0 && normal[1] == 0 && normal[2] == 0) {
        for (size_t k = 1; k + 1 < n; ++k) {
            out_.push_back(corners[0]);
            out_.push_back(corners[k]);
            out_.push_back(corners[k + 1]);
        }
        return PolygonKind::Degenerate;
    }
    // Drop the axis the normal is closest to; the other two, in right-handed order (swapped when
    // the normal points down that axis), show the polygon counter-clockwise.
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (std::fabs(normal[k]) > std::fabs(normal[axis])) axis = k;
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    if (normal[axis] < 0) std::swap(ua, va);

    positions_ = positions;
    u_.resize(n);
    v_.resize(n);
    id_.assign(corners, corners + n);
    for (size_t i = 0; i < n; ++i) {
        const float* p = positions + 3 * size_t(corners[i]);
        u_[i] = double(p[ua]) - double(o[ua]);
        v_[i] = double(p[va]) - double(o[va]);
    }
    if (strictlyConvex()) {
        for (size_t k = 1; k + 1 < n; ++k) emit(0, int(k), int(k + 1));
        return PolygonKind::Fan;
    }
    earClip();
    return selfIntersecting_ ? PolygonKind::SelfIntersecting : PolygonKind::EarClipped;
}

// Every corner turns left, and the boundary goes round once: the direction of its edges rotates
// monotonically, so the sign of their u component changes exactly twice per turn (a pentagram
// turns left everywhere too, but goes round twice).
bool PolygonTriangulator::strictlyConvex() const {
    const int m = int(id_.size());
    int changes = 0, first = 0, last = 0;
    for (int i = 0; i < m; ++i) {
        const int a = i == 0 ? m - 1 : i - 1, c = i + 1 == m ? 0 : i + 1;
        if (!(cross(a, i, c) > 0)) return false;
        const double du = u_[size_t(c)] - u_[size_t(i)];
        const int sign = (du > 0) - (du < 0);
        if (sign == 0) continue;
        if (first == 0) first = sign;
        if (last != 0 && sign != last) ++changes;
        last = sign;
    }
    if (first != last) ++changes;
    return changes <= 2;
}

// A corner blocks ears when it is reflex or flat: if any corner lies inside a candidate ear, one
// of those does.
void PolygonTriangulator::classify(int i) {
    const bool blocking = cross(prev_[size_t(i)], i, next_[size_t(i)]) <= 0;
    if (blocking == bool(blocking_[size_t(i)])) return;
    blocking_[size_t(i)] = blocking;
    if (!blocking) {
        --blockingCount_;
        return;
    }
    ++blockingCount_;
    if (listed_[size_t(i)]) return;
    listed_[size_t(i)] = 1;
    if (gridX_ > 0) {
        const size_t cell = cellOf(i);
        cellItems_[size_t(cellEnd_[cell]++)] = i;
        return;
    }
    blockers_.push_back(i);
    // Corners that start blocking while ears are cut (float rounding can make a nearly flat
    // corner reflex) go to the grid once there are many, not to an ever longer list.
    if (clipping_ && blockers_.size() > 4 * kGridMinBlockers) buildGrid();
}

size_t PolygonTriangulator::cellOf(int i) const {
    const int cx = std::clamp(int((u_[size_t(i)] - gridU0_) * gridInvU_), 0, gridX_ - 1);
    const int cy = std::clamp(int((v_[size_t(i)] - gridV0_) * gridInvV_), 0, gridY_ - 1);
    return size_t(cy) * size_t(gridX_) + size_t(cx);
}

void PolygonTriangulator::unlink(int i) {
    const int p = prev_[size_t(i)], q = next_[size_t(i)];
    alive_[size_t(i)] = 0;
    if (blocking_[size_t(i)]) {
        blocking_[size_t(i)] = 0;
        --blockingCount_;
    }
    next_[size_t(p)] = q;
    prev_[size_t(q)] = p;
    start_ = q;
    classify(p);
    classify(q);
}

// A uniform grid over the polygon's bounds with about one blocking corner a cell, in cells as
// square as the bounds allow. Each cell has room for every corner that lies in it, so a corner
// that starts blocking later goes back into its own cell.
void PolygonTriangulator::buildGrid() {
    double u0 = u_[0], u1 = u_[0], v0 = v_[0], v1 = v_[0];
    for (size_t i = 1; i < u_.size(); ++i) {
        u0 = std::min(u0, u_[i]);
        u1 = std::max(u1, u_[i]);
        v0 = std::min(v0, v_[i]);
        v1 = std::max(v1, v_[i]);
    }
    const double target = double(blockers_.size()), w = u1 - u0, h = v1 - v0;
    int gx = 1, gy = 1;
    if (w > 0 && h > 0) {
        gx = int(std::clamp(std::sqrt(target * w / h), 1.0, target));
        gy = int(std::clamp(target / gx, 1.0, target));
    } else if (w > 0) {
        gx = int(target);
    } else if (h > 0) {
        gy = int(target);
    }
    gridX_ = gx;
    gridY_ = gy;
    gridU0_ = u0;
    gridV0_ = v0;
    gridInvU_ = w > 0 ? gx / w : 0;
    gridInvV_ = h > 0 ? gy / h : 0;
    cellStart_.assign(size_t(gx) * size_t(gy) + 1, 0);
    for (int i = 0; i < int(u_.size()); ++i) ++cellStart_[cellOf(i) + 1];
    for (size_t c = 1; c < cellStart_.size(); ++c) cellStart_[c] += cellStart_[c - 1];
    cellItems_.resize(u_.size());
    cellEnd_.assign(cellStart_.begin(), cellStart_.end() - 1);
    for (const int i : blockers_) {
        listed_[size_t(i)] = 0;
        if (alive_[size_t(i)] && blocking_[size_t(i)]) {
            listed_[size_t(i)] = 1;
            cellItems_[size_t(cellEnd_[cellOf(i)]++)] = i;
        }
    }
    blockers_.clear();
}

// (a, b, c) turns left at b; it is an ear when no blocking corner lies in the closed triangle.
// Corners at the same point as a, b or c do not count: in a keyhole they are the other visit of
// a bridge corner, whose angle lies outside this one.
bool PolygonTriangulator::isEar(int a, int b, int c) {
    // a and c may block (b turns left, so it does not), but not their own ear.
    if (blockingCount_ <= size_t(blocking_[size_t(a)]) + size_t(blocking_[size_t(c)])) return true;
    const double ua = u_[size_t(a)], va = v_[size_t(a)], ub = u_[size_t(b)], vb = v_[size_t(b)];
    const double uc = u_[size_t(c)], vc = v_[size_t(c)];
    const double u0 = std::min({ua, ub, uc}), u1 = std::max({ua, ub, uc});
    const double v0 = std::min({va, vb, vc}), v1 = std::max({va, vb, vc});
    auto blocks = [&](int p) {
        if (p == a || p == b || p == c) return false;
        const double up = u_[size_t(p)], vp = v_[size_t(p)];
        if (up < u0 || up > u1 || vp < v0 || vp > v1) return false;
        if ((up == ua && vp == va) || (up == ub && vp == vb) || (up == uc && vp == vc)) return false;
        return orient(ua, va, ub, vb, up, vp) >= 0 && orient(ub, vb, uc, vc, up, vp) >= 0 &&
               orient(uc, vc, ua, va, up, vp) >= 0;
    };
    // Scans a list of corners, dropping those that stopped blocking (cut off, or no longer
    // reflex); [begin, end) shrinks as they go.
    auto scan = [&](std::vector<int>& items, int begin, int& end) {
        for (int k = begin; k < end;) {
            const int p = items[size_t(k)];
            if (!blocking_[size_t(p)]) {
                listed_[size_t(p)] = 0;
                items[size_t(k)] = items[size_t(--end)];
                continue;
            }
            if (blocks(p)) return true;
            ++k;
        }
        return false;
    };
    if (gridX_ == 0) {
        int end = int(blockers_.size());
        const bool blocked = scan(blockers_, 0, end);
        blockers_.resize(size_t(end));
        return !blocked;
    }
    // Row by row, only the cells the triangle crosses: a long thin diagonal ear (a star's spike)
    // crosses a few cells of each row but its bounding box would cover a square of them. The
    // row's band and the triangle's extent in it get a margin of a millionth of a cell, far
    // more than the rounding that assigns corners to cells.
    const int cy0 = std::clamp(int((v0 - gridV0_) * gridInvV_), 0, gridY_ - 1);
    const int cy1 = std::clamp(int((v1 - gridV0_) * gridInvV_), 0, gridY_ - 1);
    const double cellV = gridInvV_ > 0 ? 1 / gridInvV_ : 0, marginU = gridInvU_ > 0 ? 1e-6 / gridInvU_ : 0;
    const double tu[3] = {ua, ub, uc}, tv[3] = {va, vb, vc};
    for (int cy = cy0; cy <= cy1; ++cy) {
        double lo = u0, hi = u1;
        if (gridY_ > 1) {
            const double bandLo = gridV0_ + cy * cellV - 1e-6 * cellV, bandHi = gridV0_ + (cy + 1) * cellV + 1e-6 * cellV;
            lo = INFINITY, hi = -INFINITY;
            for (int k = 0; k < 3; ++k) {
                if (tv[k] >= bandLo && tv[k] <= bandHi) lo = std::min(lo, tu[k]), hi = std::max(hi, tu[k]);
                const int n = k == 2 ? 0 : k + 1;
                for (const double line : {bandLo, bandHi}) {
                    if ((tv[k] - line) * (tv[n] - line) >= 0) continue;
                    const double u = tu[k] + (line - tv[k]) * (tu[n] - tu[k]) / (tv[n] - tv[k]);
                    lo = std::min(lo, u), hi = std::max(hi, u);
                }
            }
            if (lo > hi) continue;
        }
        const int cx0 = std::clamp(int((lo - marginU - gridU0_) * gridInvU_), 0, gridX_ - 1);
        const int cx1 = std::clamp(int((hi + marginU - gridU0_) * gridInvU_), 0, gridX_ - 1);
        for (int cx = cx0; cx <= cx1; ++cx) {
            const size_t cell = size_t(cy) * size_t(gridX_) + size_t(cx);
            if (scan(cellItems_, cellStart_[cell], cellEnd_[cell])) return false;
        }
    }
    return true;
}

// Cuts off ears until a triangle is left. Corners are tried in order; cutting one off queues its
// two neighbours again, the only corners whose ear could have changed with it (bar a blocking
// corner that stopped blocking, which a further round over all corners finds). Flat corners (on
// a line with their neighbours, repeated, or the tip of a zero-width spike such as a collapsed
// bridge) are cut off without a triangle, unless they are flat only in the projection: a
// non-planar polygon can have an edge along the axis projected away, and its triangle is then
// kept (it covers nothing in the plane, so it overlaps no other). A whole round without an ear
// means the boundary crosses itself.
void PolygonTriangulator::earClip() {
    const int m = int(id_.size());
    prev_.resize(size_t(m));
    next_.resize(size_t(m));
    alive_.assign(size_t(m), 1);
    blocking_.assign(size_t(m), 0);
    listed_.assign(size_t(m), 0);
    blockers_.clear();
    clipping_ = false;
    blockingCount_ = 0;
    gridX_ = gridY_ = 0;
    selfIntersecting_ = false;
    for (int i = 0; i < m; ++i) {
        prev_[size_t(i)] = i == 0 ? m - 1 : i - 1;
        next_[size_t(i)] = i + 1 == m ? 0 : i + 1;
    }
    for (int i = 0; i < m; ++i) classify(i);
    if (blockers_.size() > kGridMinBlockers) buildGrid();
    clipping_ = true;

    // A corner is tried at its last place in the queue only: the neighbours of an ear just cut
    // off wait for the next round instead of being tried at once, so ears are cut from all
    // along the boundary in turn. Cutting the next corner at once would grow a fan of ever
    // longer slivers from one corner, slower to test and worse to render.
    queue_.clear();
    queued_.resize(size_t(m));
    auto enqueue = [&](int j) {
        queued_[size_t(j)] = queue_.size();
        queue_.push_back(j);
    };
    for (int i = 0; i < m; ++i) enqueue(i);
    int remaining = m;
    start_ = 0;
    size_t head = 0;
    bool progress = false;
    while (remaining > 3) {
        if (head == queue_.size()) {
            if (!progress) {
                selfIntersecting_ = true;
                const int s = start_;
                for (int j = next_[size_t(s)]; next_[size_t(j)] != s; j = next_[size_t(j)]) emit(s, j, next_[size_t(j)]);
                return;
            }
            progress = false;
            queue_.clear();
            head = 0;
            int j = start_;
            do {
                enqueue(j);
                j = next_[size_t(j)];
            } while (j != start_);
        }
        const size_t at = head++;
        const int i = queue_[at];
        if (!alive_[size_t(i)] || queued_[size_t(i)] != at) continue;
        const int a = prev_[size_t(i)], c = next_[size_t(i)];
        const double turn = cross(a, i, c);
        if (turn == 0 || (turn > 0 && isEar(a, i, c))) {
            if (turn != 0 || !flatInSpace(a, i, c)) emit(a, i, c);
            unlink(i);
            --remaining;
            enqueue(a);
            enqueue(c);
            progress = true;
        }
    }
    if (remaining == 3) {
        const int i = start_;
        const double turn = cross(prev_[size_t(i)], i, next_[size_t(i)]);
        if (turn != 0 || !flatInSpace(prev_[size_t(i)], i, next_[size_t(i)])) emit(prev_[size_t(i)], i, next_[size_t(i)]);
        if (turn < 0) selfIntersecting_ = true;
    }
}

void countPolygon(ImportReport& report, PolygonKind kind) {
    switch (kind) {
    case PolygonKind::Triangle: return;
    case PolygonKind::Fan: ++report.polygonsFanned; break;
    case PolygonKind::EarClipped: ++report.polygonsEarClipped; break;
    case PolygonKind::Degenerate: ++report.polygonsDegenerate; break;
    case PolygonKind::SelfIntersecting: ++report.polygonsSelfIntersecting; break;
    }
    ++report.polygonsTriangulated;
}

}  // namespace rtwall::detail
