// Congruent shapes found, not just declared (issue 29): meshes of an assembly that are the same
// shape up to a rigid motion are stored once, the motion moved into their instances.
//
// Candidates share a signature: vertex and triangle counts and the exact texture coordinate and
// colour arrays (a writer or tessellator that meets the same shape twice lays its vertices out
// alike; a motion changes positions and normals only). Within such a group a mesh is
// compared with each shape kept so far: the spread of its vertices about their centroid (a
// rotation invariant) must agree, then the rotation that best maps the kept shape's vertices
// onto the candidate's (Horn's closed form: the top eigenvector of a 4x4 symmetric matrix) is
// verified on every vertex, within `tolerance` times the shape's bounding-box diagonal, and on
// every normal; where the triangles differ, only a retriangulation of flat regions is accepted
// (planarRetriangulation). The rotation is proper by construction, so a mirrored copy never matches: it
// stays a mesh of its own (an instance with a negative determinant would turn its triangles'
// winding inside out, and with it which side emits and what "front" means to the shading).
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

// The proper rotation R that best maps `from`'s centred vertices onto `to`'s (Horn 1987).
Mat3 bestRotation(const TriangleMesh& from, const Shape& f, const TriangleMesh& to, const Shape& t) {
    double S[9] = {};  // S[3 i + j] = sum (a - ca)_i (b - cb)_j
    for (size_t v = 0; v < from.vertexCount(); ++v) {
        const Vec3 a = at(from, v), b = at(to, v);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) S[3 * i + j] += (a[i] - f.centroid[i]) * (b[j] - t.centroid[j]);
    }
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
bool planarRetriangulation(const TriangleMesh& a, const TriangleMesh& b, double limit) {
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
        const uint32_t* j = b.indices() + 3 * t;
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
        uint64_t h = 1469598103934665603ull;  // FNV-1a's offset basis
        if (m.hasUVs()) h = fnv(m.uvs(), 2 * m.vertexCount() * sizeof(float), h);
        if (m.hasColors()) h = fnv(m.colors(), 3 * m.vertexCount(), h);
        const int flags = int(m.hasNormals()) | int(m.hasUVs()) << 1 | int(m.hasColors()) << 2;
        Group& group = kept[{m.vertexCount(), m.triangleCount(), h, flags}];
        const Shape mine = describe(m, i);
        bool found = false;
        const double root = std::sqrt(mine.spread), reach = std::max(limitOf(mine, tolerance), group.widest) + 1e-12 * root;
        for (auto it = group.byRoot.lower_bound(root - reach); it != group.byRoot.end() && it->first <= root + reach; ++it) {
            const Shape& s = it->second;
            const TriangleMesh& k = *a.meshes[s.mesh];
            if (!sameVertexLayout(k, m)) continue;
            auto fit = motionBetween(k, s, m, mine, tolerance);
            if (fit && !sameTriangles(k, m) && !planarRetriangulation(k, m, limitOf(s, tolerance))) fit.reset();
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
