// Congruent shapes found, not just declared (issue 29): meshes of an assembly that are the same
// shape up to a rigid motion are stored once, the motion moved into their instances.
//
// Candidates share a signature: vertex and triangle counts and the texture coordinates and
// colours as a multiset (a motion changes positions and normals only). Within such a group a
// mesh is compared with each shape kept so far: the spread of its vertices about their centroid
// (a rotation invariant) must agree; where the vertices correspond by index (a writer or
// tessellator that meets the same shape twice lays its vertices out alike), the rotation that
// best maps the kept shape's vertices onto the candidate's (Horn's closed form: the top
// eigenvector of a 4x4 symmetric matrix) is verified on every vertex, within `tolerance` times
// the shape's bounding-box diagonal, and on every normal; where the triangles differ, only a
// retriangulation of flat regions is accepted (planarRetriangulation). Where they do not
// correspond by index, the correspondence is found (permutedMotion). The rotation is proper by
// construction, so a chiral shape's mirror image never matches: it stays a mesh of its own (an
// instance with a negative determinant would turn its triangles' winding inside out, and with
// it which side emits and what "front" means to the shading); an achiral shape's mirror image
// is that shape turned, and is found.
#include "mesh_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <tuple>

namespace rtwall::detail {
namespace {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>;  // row-major

uint64_t fnv(const void* data, size_t bytes, uint64_t h = 1469598103934665603ull) {
    const auto* p = static_cast<const uint8_t*>(data);
    for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

Vec3 at(const TriangleMesh& m, size_t v) {
    const float* p = m.positions() + 3 * v;
    return {p[0], p[1], p[2]};
}

struct Shape {
    size_t mesh;
    Vec3 centroid;
    double spread;    // mean squared distance of the vertices from the centroid
    double diagonal;  // of the bounding box
    double floatStep;  // 4 float steps at the largest coordinate the file stored (origin() added back)
};

// How far two vertices may lie apart and still correspond: the tolerance relative to the shape,
// but never finer than the precision the file stored its coordinates with (a part placed 300
// units from the origin in floats is known to about 3e-5 only).
double limitOf(const Shape& s, double tolerance) { return std::max(tolerance * s.diagonal, s.floatStep); }

Shape describe(const TriangleMesh& m, size_t index) {
    Shape s{index, {0, 0, 0}, 0, 0, 0};
    const size_t n = m.vertexCount();
    Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < n; ++v) {
        const Vec3 p = at(m, v);
        for (int k = 0; k < 3; ++k) {
            s.centroid[k] += p[k] / double(n);
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    }
    for (size_t v = 0; v < n; ++v) {
        const Vec3 p = at(m, v);
        for (int k = 0; k < 3; ++k) s.spread += (p[k] - s.centroid[k]) * (p[k] - s.centroid[k]) / double(n);
    }
    double largest = 0;
    for (int k = 0; k < 3; ++k) largest = std::max({largest, std::fabs(lo[k] + m.origin()[k]), std::fabs(hi[k] + m.origin()[k])});
    s.floatStep = n ? 4.0 * largest * 0x1.0p-23 : 0.0;
    s.diagonal = n ? std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2])) : 0;
    return s;
}

// The eigenvector of the largest eigenvalue of a symmetric 4x4 matrix (cyclic Jacobi).
std::array<double, 4> topEigenvector(std::array<double, 16> a) {
    std::array<double, 16> v{};
    for (int i = 0; i < 4; ++i) v[5 * i] = 1;
    for (int sweep = 0; sweep < 50; ++sweep) {
        double off = 0;
        for (int p = 0; p < 4; ++p)
            for (int q = p + 1; q < 4; ++q) off += a[4 * p + q] * a[4 * p + q];
        if (off < 1e-30) break;
        for (int p = 0; p < 4; ++p)
            for (int q = p + 1; q < 4; ++q) {
                const double apq = a[4 * p + q];
                if (std::fabs(apq) < 1e-300) continue;
                const double theta = (a[4 * q + q] - a[4 * p + p]) / (2 * apq);
                const double t = (theta >= 0 ? 1 : -1) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
                const double c = 1 / std::sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 4; ++k) {  // A <- J^T A J
                    const double akp = a[4 * k + p], akq = a[4 * k + q];
                    a[4 * k + p] = c * akp - s * akq;
                    a[4 * k + q] = s * akp + c * akq;
                }
                for (int k = 0; k < 4; ++k) {
                    const double apk = a[4 * p + k], aqk = a[4 * q + k];
                    a[4 * p + k] = c * apk - s * aqk;
                    a[4 * q + k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 4; ++k) {
                    const double vkp = v[4 * k + p], vkq = v[4 * k + q];
                    v[4 * k + p] = c * vkp - s * vkq;
                    v[4 * k + q] = s * vkp + c * vkq;
                }
            }
    }
    int best = 0;
    for (int i = 1; i < 4; ++i)
        if (a[5 * i] > a[5 * best]) best = i;
    return {v[best], v[4 + best], v[8 + best], v[12 + best]};
}

// The proper rotation R maximising sum (R a_i) . b_i for S = sum a_i b_i^T (S[3 i + j] =
// sum a_i b_j over centred pairs): Horn's closed form (1987), the top eigenvector of a 4x4
// symmetric matrix as a quaternion.
Mat3 hornRotation(const double* S) {
    const double xx = S[0], xy = S[1], xz = S[2], yx = S[3], yy = S[4], yz = S[5], zx = S[6], zy = S[7], zz = S[8];
    const std::array<double, 16> N = {xx + yy + zz, yz - zy,       zx - xz,        xy - yx,  //
                                      yz - zy,      xx - yy - zz,  xy + yx,        zx + xz,  //
                                      zx - xz,      xy + yx,       -xx + yy - zz,  yz + zy,  //
                                      xy - yx,      zx + xz,       yz + zy,        -xx - yy + zz};
    const auto q = topEigenvector(N);
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double n = w * w + x * x + y * y + z * z;
    const double s = n > 0 ? 2 / n : 0;
    return {1 - s * (y * y + z * z), s * (x * y - w * z),     s * (x * z + w * y),
            s * (x * y + w * z),     1 - s * (x * x + z * z), s * (y * z - w * x),
            s * (x * z - w * y),     s * (y * z + w * x),     1 - s * (x * x + y * y)};
}

// The proper rotation R that best maps `from`'s centred vertices onto `to`'s, vertex i to vertex i.
Mat3 bestRotation(const TriangleMesh& from, const Shape& f, const TriangleMesh& to, const Shape& t) {
    double S[9] = {};  // S[3 i + j] = sum (a - ca)_i (b - cb)_j
    for (size_t v = 0; v < from.vertexCount(); ++v) {
        const Vec3 a = at(from, v), b = at(to, v);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) S[3 * i + j] += (a[i] - f.centroid[i]) * (b[j] - t.centroid[j]);
    }
    return hornRotation(S);
}

Vec3 rotate(const Mat3& r, const Vec3& p) {
    return {r[0] * p[0] + r[1] * p[1] + r[2] * p[2], r[3] * p[0] + r[4] * p[1] + r[5] * p[2], r[6] * p[0] + r[7] * p[1] + r[8] * p[2]};
}

// `to` = R `from` + t on every vertex within tolerance x the diagonal, and on every normal within
// 1e-3: the motion (row-major 3x4 [R | t]) when it holds.
std::optional<Affine> motionBetween(const TriangleMesh& from, const Shape& f, const TriangleMesh& to, const Shape& t, double tolerance) {
    // Exact copies (the same position and normal bits): exactly the identity, so that an
    // assembly of copies renders to the bytes it rendered before detection.
    if (std::memcmp(from.positions(), to.positions(), 3 * from.vertexCount() * sizeof(float)) == 0 &&
        (!from.hasNormals() || std::memcmp(from.normals(), to.normals(), 3 * from.vertexCount() * sizeof(float)) == 0))
        return Affine{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    const double limit = std::max(limitOf(f, tolerance), limitOf(t, tolerance));
    if (std::fabs(std::sqrt(f.spread) - std::sqrt(t.spread)) > limit) return std::nullopt;
    const Mat3 R = bestRotation(from, f, to, t);
    const Vec3 rc = rotate(R, f.centroid);
    const Vec3 tr{t.centroid[0] - rc[0], t.centroid[1] - rc[1], t.centroid[2] - rc[2]};
    for (size_t v = 0; v < from.vertexCount(); ++v) {
        const Vec3 a = rotate(R, at(from, v)), b = at(to, v);
        const double dx = a[0] + tr[0] - b[0], dy = a[1] + tr[1] - b[1], dz = a[2] + tr[2] - b[2];
        if (dx * dx + dy * dy + dz * dz > limit * limit) return std::nullopt;
    }
    if (from.hasNormals())
        for (size_t v = 0; v < from.vertexCount(); ++v) {
            const float* na = from.normals() + 3 * v;
            const float* nb = to.normals() + 3 * v;
            const Vec3 r = rotate(R, {na[0], na[1], na[2]});
            const double dx = r[0] - nb[0], dy = r[1] - nb[1], dz = r[2] - nb[2];
            if (dx * dx + dy * dy + dz * dz > 1e-6) return std::nullopt;
        }
    return Affine{R[0], R[1], R[2], tr[0], R[3], R[4], R[5], tr[1], R[6], R[7], R[8], tr[2]};
}

// Same counts, texture coordinates and colours (the triangles may differ: see planarRetriangulation).
bool sameVertexLayout(const TriangleMesh& a, const TriangleMesh& b) {
    if (a.vertexCount() != b.vertexCount() || a.triangleCount() != b.triangleCount() || a.hasNormals() != b.hasNormals() ||
        a.hasUVs() != b.hasUVs() || a.hasColors() != b.hasColors())
        return false;
    if (a.hasUVs() && std::memcmp(a.uvs(), b.uvs(), 2 * a.vertexCount() * sizeof(float)) != 0) return false;
    if (a.hasColors() && std::memcmp(a.colors(), b.colors(), 3 * a.vertexCount()) != 0) return false;
    return true;
}

bool sameTriangles(const TriangleMesh& a, const TriangleMesh& b) {
    return std::memcmp(a.indices(), b.indices(), 3 * a.triangleCount() * sizeof(uint32_t)) == 0;
}

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

// Where two meshes have corresponding vertices (checked before) but other triangles: the same
// surface when only flat regions are triangulated otherwise (OCCT's mesher triangulates the
// cocircular points of a cylinder's cap disk one way or another, as float noise breaks the
// Delaunay ties). Holds when the total areas agree and every triangle of `b` lies in the plane,
// and faces the way, of a triangle of `a` that shares a vertex with it.
bool planarRetriangulation(const TriangleMesh& a, const uint32_t* bIndices, double limit) {
    const size_t nt = a.triangleCount();
    std::vector<std::vector<uint32_t>> around(a.vertexCount());
    double areaA = 0, areaB = 0;
    std::vector<Vec3> normalA(nt);
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t* i = a.indices() + 3 * t;
        const Vec3 n = cross(sub(at(a, i[1]), at(a, i[0])), sub(at(a, i[2]), at(a, i[0])));
        areaA += norm(n) / 2;
        const double len = norm(n);
        normalA[t] = len > 0 ? Vec3{n[0] / len, n[1] / len, n[2] / len} : Vec3{0, 0, 0};
        for (int k = 0; k < 3; ++k) around[i[k]].push_back(uint32_t(t));
    }
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t* j = bIndices + 3 * t;
        // b's triangle in a's coordinates: the same vertex numbers.
        const Vec3 p0 = at(a, j[0]), p1 = at(a, j[1]), p2 = at(a, j[2]);
        const Vec3 n = cross(sub(p1, p0), sub(p2, p0));
        const double len = norm(n);
        areaB += len / 2;
        if (len == 0) continue;  // a degenerate triangle adds nothing to the surface
        const Vec3 u{n[0] / len, n[1] / len, n[2] / len};
        bool inPlane = false;
        for (int k = 0; k < 3 && !inPlane; ++k)
            for (uint32_t s : around[j[k]]) {
                if (dot(normalA[s], u) < 0.9999) continue;
                const Vec3 q = at(a, a.indices()[3 * s]);
                if (std::fabs(dot(normalA[s], sub(p0, q))) <= limit && std::fabs(dot(normalA[s], sub(p1, q))) <= limit &&
                    std::fabs(dot(normalA[s], sub(p2, q))) <= limit) {
                    inPlane = true;
                    break;
                }
            }
        if (!inPlane) return false;
    }
    return std::fabs(areaA - areaB) <= 1e-6 * std::max(areaA, 1e-30);
}

uint64_t mix(uint64_t x) {  // splitmix64's finaliser
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// The texture coordinates and colours as a multiset: a sum of per-vertex hashes, the same for
// any numbering of the same vertices.
uint64_t attributeHash(const TriangleMesh& m) {
    uint64_t h = 0;
    for (size_t v = 0; v < m.vertexCount(); ++v) {
        uint64_t x = 1469598103934665603ull;
        if (m.hasUVs()) x = fnv(m.uvs() + 2 * v, 2 * sizeof(float), x);
        if (m.hasColors()) x = fnv(m.colors() + 3 * v, 3, x);
        h += mix(x);
    }
    return h;
}

bool sameAttributes(const TriangleMesh& a, size_t i, const TriangleMesh& b, size_t j) {
    if (a.hasUVs() && std::memcmp(a.uvs() + 2 * i, b.uvs() + 2 * j, 2 * sizeof(float)) != 0) return false;
    if (a.hasColors() && std::memcmp(a.colors() + 3 * i, b.colors() + 3 * j, 3) != 0) return false;
    return true;
}

// A mesh's vertices about its centroid, their distances from it in order, and a grid of cells
// to find a vertex near a point.
struct Cloud {
    std::vector<Vec3> p;
    std::vector<std::pair<double, uint32_t>> byRadius;
    double cell = 0;
    std::vector<std::pair<uint64_t, uint32_t>> cells;  // (cell key, vertex), sorted

    Cloud(const TriangleMesh& m, const Shape& s) : p(m.vertexCount()), byRadius(m.vertexCount()) {
        for (size_t v = 0; v < p.size(); ++v) {
            p[v] = sub(at(m, v), s.centroid);
            byRadius[v] = {norm(p[v]), uint32_t(v)};
        }
        std::sort(byRadius.begin(), byRadius.end());
    }
    static uint64_t key(int64_t x, int64_t y, int64_t z) { return mix(uint64_t(x) ^ mix(uint64_t(y) ^ mix(uint64_t(z)))); }
    std::array<int64_t, 3> cellOf(const Vec3& q) const {
        return {int64_t(std::floor(q[0] / cell)), int64_t(std::floor(q[1] / cell)), int64_t(std::floor(q[2] / cell))};
    }
    void grid(double size) {
        cell = size;
        cells.resize(p.size());
        for (size_t v = 0; v < p.size(); ++v) {
            const auto c = cellOf(p[v]);
            cells[v] = {key(c[0], c[1], c[2]), uint32_t(v)};
        }
        std::sort(cells.begin(), cells.end());
    }
    // Calls f(vertex) for every vertex in the 27 cells around q (a superset of those within `cell`).
    template <class F>
    void near(const Vec3& q, F&& f) const {
        const auto c = cellOf(q);
        for (int64_t dx = -1; dx <= 1; ++dx)
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dz = -1; dz <= 1; ++dz) {
                    const uint64_t k = key(c[0] + dx, c[1] + dy, c[2] + dz);
                    for (auto it = std::lower_bound(cells.begin(), cells.end(), std::pair<uint64_t, uint32_t>{k, 0});
                         it != cells.end() && it->first == k; ++it)
                        f(it->second);
                }
    }
    // Vertices whose distance from the centroid lies within [r - d, r + d].
    std::pair<size_t, size_t> atRadius(double r, double d) const {
        const auto lo = std::lower_bound(byRadius.begin(), byRadius.end(), std::pair<double, uint32_t>{r - d, 0});
        const auto hi = std::upper_bound(byRadius.begin(), byRadius.end(), std::pair<double, uint32_t>{r + d, UINT32_MAX});
        return {size_t(lo - byRadius.begin()), size_t(hi - byRadius.begin())};
    }
};

// The orthonormal frame of two vectors (first along u, second in the plane of u and w).
Mat3 frameOf(const Vec3& u, const Vec3& w) {
    const double lu = norm(u);
    const Vec3 e1{u[0] / lu, u[1] / lu, u[2] / lu};
    const double d = dot(w, e1);
    Vec3 e2{w[0] - d * e1[0], w[1] - d * e1[1], w[2] - d * e1[2]};
    const double l2 = norm(e2);
    e2 = {e2[0] / l2, e2[1] / l2, e2[2] / l2};
    const Vec3 e3 = cross(e1, e2);
    return {e1[0], e2[0], e3[0], e1[1], e2[1], e3[1], e1[2], e2[2], e3[2]};  // columns e1 e2 e3
}

bool normalsAgree(const TriangleMesh& a, size_t i, const Mat3& R, const TriangleMesh& b, size_t j) {
    if (!a.hasNormals()) return true;
    const float* na = a.normals() + 3 * i;
    const float* nb = b.normals() + 3 * j;
    const Vec3 r = rotate(R, {na[0], na[1], na[2]});
    const double dx = r[0] - nb[0], dy = r[1] - nb[1], dz = r[2] - nb[2];
    return dx * dx + dy * dy + dz * dz <= 1e-6;
}

// Copies whose vertices are numbered otherwise (another writer, a mesher's other run, bodies of
// a triangle soup): no correspondence is given, so it is found. The distances of the vertices
// from the centroid must agree as sorted lists (a rotation invariant); the vertex farthest from
// the centroid and the one farthest from that axis anchor the rotation, tried against the
// candidate's vertices at the same distances (at most 256 pairs: a symmetric shape has many
// right answers, any one will do); a rotation that carries every vertex to a distinct unused
// vertex of the same attributes and normal within a loose bound gives the correspondence,
// Horn's fit on it the motion, verified on every vertex within the limit, and the triangles
// must be the same (as sets, winding kept) or a planar retriangulation of them.
std::optional<Affine> permutedMotion(const TriangleMesh& from, const Shape& f, const TriangleMesh& to, const Shape& t, double tolerance) {
    const size_t n = from.vertexCount();
    const double limit = std::max(limitOf(f, tolerance), limitOf(t, tolerance));
    if (n < 3 || !(limit > 0) || std::fabs(std::sqrt(f.spread) - std::sqrt(t.spread)) > limit) return std::nullopt;
    Cloud a(from, f), b(to, t);
    for (size_t i = 0; i < n; ++i)
        if (std::fabs(a.byRadius[i].first - b.byRadius[i].first) > 2 * limit) return std::nullopt;
    const uint32_t a1 = a.byRadius.back().second;
    const double r1 = a.byRadius.back().first;
    if (r1 <= 4 * limit) return std::nullopt;  // a point: no frame
    uint32_t a2 = a1;
    double off = 0;  // a2's distance from the axis through a1
    for (uint32_t v = 0; v < n; ++v) {
        const Vec3 c = cross(a.p[v], a.p[a1]);
        if (const double d = norm(c) / r1; d > off) off = d, a2 = v;
    }
    if (off <= 4 * limit) return std::nullopt;  // a line: no frame
    const Mat3 FA = frameOf(a.p[a1], a.p[a2]);
    // The anchors' noise turns the frame by about limit / off: the loose bound covers it at r1.
    const double loose = 4 * limit * (1 + r1 / off);
    b.grid(loose);
    const double d12 = norm(sub(a.p[a2], a.p[a1]));
    std::vector<uint32_t> perm(n), inverse(n);
    std::vector<uint8_t> used(n);
    int tries = 0;
    const auto [lo1, hi1] = b.atRadius(r1, 2 * limit);
    const auto [lo2, hi2] = b.atRadius(norm(a.p[a2]), 2 * limit);
    for (size_t i1 = lo1; i1 < hi1 && tries < 256; ++i1) {
        const uint32_t b1 = b.byRadius[i1].second;
        if (!sameAttributes(from, a1, to, b1)) continue;
        for (size_t i2 = lo2; i2 < hi2 && tries < 256; ++i2) {
            const uint32_t b2 = b.byRadius[i2].second;
            if (b2 == b1 || std::fabs(norm(sub(b.p[b2], b.p[b1])) - d12) > 4 * limit || !sameAttributes(from, a2, to, b2)) continue;
            ++tries;
            const Mat3 FB = frameOf(b.p[b1], b.p[b2]);
            Mat3 R{};  // FB FA^T
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) R[size_t(3 * r + c)] = FB[size_t(3 * r)] * FA[size_t(3 * c)] + FB[size_t(3 * r + 1)] * FA[size_t(3 * c + 1)] + FB[size_t(3 * r + 2)] * FA[size_t(3 * c + 2)];
            if (!normalsAgree(from, a1, R, to, b1)) continue;
            std::fill(used.begin(), used.end(), 0);
            bool all = true;
            for (size_t v = 0; v < n && all; ++v) {
                const Vec3 q = rotate(R, a.p[v]);
                uint32_t best = UINT32_MAX;
                double bestD = loose * loose;
                b.near(q, [&](uint32_t w) {
                    if (used[w]) return;
                    const Vec3 d = sub(b.p[w], q);
                    const double dd = dot(d, d);
                    if (dd <= bestD && sameAttributes(from, v, to, w) && normalsAgree(from, v, R, to, w)) bestD = dd, best = w;
                });
                if (best == UINT32_MAX) all = false;
                else used[best] = 1, perm[v] = best;
            }
            if (!all) continue;
            // Horn's rotation on the correspondence, then the strict check.
            double S[9] = {};
            for (size_t v = 0; v < n; ++v)
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) S[3 * i + j] += a.p[v][size_t(i)] * b.p[perm[v]][size_t(j)];
            const Mat3 H = hornRotation(S);
            bool fits = true;
            for (size_t v = 0; v < n && fits; ++v) {
                const Vec3 d = sub(rotate(H, a.p[v]), b.p[perm[v]]);
                fits = dot(d, d) <= limit * limit && normalsAgree(from, v, H, to, perm[v]);
            }
            if (!fits) continue;
            // The triangles of `to` in `from`'s numbering, each starting at its smallest vertex.
            for (size_t v = 0; v < n; ++v) inverse[perm[v]] = uint32_t(v);
            auto canonical = [](const uint32_t* i) {
                const int s = i[0] <= i[1] && i[0] <= i[2] ? 0 : i[1] <= i[2] ? 1 : 2;
                return std::array<uint32_t, 3>{i[s], i[(s + 1) % 3], i[(s + 2) % 3]};
            };
            const size_t nt = from.triangleCount();
            std::vector<uint32_t> remapped(3 * nt);
            std::vector<std::array<uint32_t, 3>> ta(nt), tb(nt);
            for (size_t k = 0; k < nt; ++k) {
                for (int c = 0; c < 3; ++c) remapped[3 * k + size_t(c)] = inverse[to.indices()[3 * k + size_t(c)]];
                ta[k] = canonical(from.indices() + 3 * k);
                tb[k] = canonical(remapped.data() + 3 * k);
            }
            std::sort(ta.begin(), ta.end());
            std::sort(tb.begin(), tb.end());
            if (ta != tb && !planarRetriangulation(from, remapped.data(), limit)) continue;
            const Vec3 rc = rotate(H, f.centroid);
            return Affine{H[0], H[1], H[2], t.centroid[0] - rc[0], H[3], H[4], H[5], t.centroid[1] - rc[1],
                          H[6], H[7], H[8], t.centroid[2] - rc[2]};
        }
    }
    return std::nullopt;
}

}  // namespace

size_t shareCongruentMeshes(Assembly& a, double tolerance) {
    const size_t n = a.meshes.size();
    // Signature -> the shapes kept so far with it, by the root of their spread (a shape is only
    // fitted against those whose spread is within its limit, so many distinct shapes of one
    // layout do not make the search quadratic).
    struct Group {
        std::multimap<double, Shape> byRoot;
        double widest = 0;  // the largest limit of a shape kept in it
    };
    std::map<std::tuple<size_t, size_t, uint64_t, int>, Group> kept;
    std::vector<uint32_t> target(n);
    std::vector<std::optional<Affine>> motion(n);
    size_t merged = 0;
    for (size_t i = 0; i < n; ++i) {
        target[i] = uint32_t(i);
        const TriangleMesh& m = *a.meshes[i];
        const uint64_t h = attributeHash(m);
        const int flags = int(m.hasNormals()) | int(m.hasUVs()) << 1 | int(m.hasColors()) << 2;
        Group& group = kept[{m.vertexCount(), m.triangleCount(), h, flags}];
        const Shape mine = describe(m, i);
        bool found = false;
        const double root = std::sqrt(mine.spread), reach = std::max(limitOf(mine, tolerance), group.widest) + 1e-12 * root;
        for (auto it = group.byRoot.lower_bound(root - reach); it != group.byRoot.end() && it->first <= root + reach; ++it) {
            const Shape& s = it->second;
            const TriangleMesh& k = *a.meshes[s.mesh];
            std::optional<Affine> fit;
            if (sameVertexLayout(k, m)) {
                fit = motionBetween(k, s, m, mine, tolerance);
                if (fit && !sameTriangles(k, m) && !planarRetriangulation(k, m.indices(), limitOf(s, tolerance))) fit.reset();
            }
            if (!fit) fit = permutedMotion(k, s, m, mine, tolerance);
            if (fit) {
                target[i] = uint32_t(s.mesh);
                motion[i] = *fit;
                ++merged;
                found = true;
                break;
            }
        }
        if (!found) {
            group.byRoot.emplace(root, mine);
            group.widest = std::max(group.widest, limitOf(mine, tolerance));
        }
    }
    if (merged == 0) return 0;
    // Instances of a merged mesh place the kept one through the motion; the meshes left
    // unused are dropped and the rest renumbered in order.
    for (AssemblyInstance& in : a.instances) {
        const uint32_t m = in.mesh;
        if (target[m] == m) continue;
        in.transform = composeAffine(in.transform, *motion[m]);
        in.mesh = target[m];
    }
    std::vector<uint32_t> renumber(n, UINT32_MAX);
    std::vector<std::shared_ptr<const TriangleMesh>> meshes;
    std::vector<std::string> names;
    for (size_t i = 0; i < n; ++i) {
        if (target[i] != i) continue;
        renumber[i] = uint32_t(meshes.size());
        meshes.push_back(std::move(a.meshes[i]));
        names.push_back(std::move(a.meshNames[i]));
    }
    for (AssemblyInstance& in : a.instances) in.mesh = renumber[in.mesh];
    a.meshes = std::move(meshes);
    a.meshNames = std::move(names);
    return merged;
}

}  // namespace rtwall::detail
