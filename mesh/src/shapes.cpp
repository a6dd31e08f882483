#include "rtwall/mesh.h"
#include "rtwall/vec.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rtwall {
namespace {

void appendNormal(std::vector<float>& normals, Float3 n) {
    normals.push_back(n.x);
    normals.push_back(n.y);
    normals.push_back(n.z);
}

// Every shape is addressed with 32-bit indices; refuse sizes whose vertex count would not fit
// rather than wrapping silently.
void requireVertexCount(const char* shape, double vertices) {
    if (vertices >= 4294967295.0)
        throw std::invalid_argument(std::string(shape) + ": too many vertices for 32-bit indices");
}

}  // namespace

TriangleMesh makeSphere(int rings, int segments) {
    if (rings < 2 || segments < 3)
        throw std::invalid_argument("makeSphere: need rings >= 2 and segments >= 3, got " +
                                    std::to_string(rings) + " x " + std::to_string(segments));
    requireVertexCount("makeSphere", double(rings - 1) * segments + 2);

    // Single pole vertices: no texture coordinates need a seam, and a shared pole avoids
    // zero-area sliver triangles there.
    const auto ringCount = static_cast<uint32_t>(rings - 1);
    const auto segs = static_cast<uint32_t>(segments);
    TriangleMesh mesh;
    mesh.reserve(size_t(ringCount) * segs + 2, size_t(2) * segs * ringCount);
    std::vector<float> normals;
    normals.reserve(3 * (size_t(ringCount) * segs + 2));

    const uint32_t north = mesh.addVertex({0, 1, 0});
    appendNormal(normals, {0, 1, 0});
    for (uint32_t r = 0; r < ringCount; ++r) {
        const double theta = std::numbers::pi * (r + 1) / rings;  // polar angle from +y
        for (uint32_t s = 0; s < segs; ++s) {
            const double phi = 2.0 * std::numbers::pi * s / segments;
            const Float3 p{float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                           float(-std::sin(theta) * std::sin(phi))};
            mesh.addVertex(p);
            appendNormal(normals, normalize(p));
        }
    }
    const uint32_t south = mesh.addVertex({0, -1, 0});
    appendNormal(normals, {0, -1, 0});

    // Counter-clockwise seen from outside, so the geometric normal agrees with the shading one.
    auto ringVertex = [&](uint32_t r, uint32_t s) { return 1 + r * segs + s % segs; };
    for (uint32_t s = 0; s < segs; ++s) mesh.addTriangle(north, ringVertex(0, s), ringVertex(0, s + 1));
    for (uint32_t r = 0; r + 1 < ringCount; ++r) {
        for (uint32_t s = 0; s < segs; ++s) {
            const uint32_t a = ringVertex(r, s), b = ringVertex(r, s + 1);
            const uint32_t c = ringVertex(r + 1, s), d = ringVertex(r + 1, s + 1);
            mesh.addTriangle(a, c, d);
            mesh.addTriangle(a, d, b);
        }
    }
    for (uint32_t s = 0; s < segs; ++s)
        mesh.addTriangle(south, ringVertex(ringCount - 1, s + 1), ringVertex(ringCount - 1, s));
    mesh.setNormals(std::move(normals));
    return mesh;
}

TriangleMesh makeBox() {
    // Eight shared corners and no vertex normals: interpolated normals would round the edges,
    // and the geometric normal is exactly right for flat faces.
    TriangleMesh mesh;
    mesh.reserve(8, 12);
    for (int i = 0; i < 8; ++i)
        mesh.addVertex({(i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : -1.0f, (i & 4) ? 1.0f : -1.0f});
    // Corner i has x = bit 0, y = bit 1, z = bit 2. Each face is listed counter-clockwise
    // seen from outside.
    const uint32_t faces[6][4] = {
        {0, 4, 6, 2},  // -x
        {1, 3, 7, 5},  // +x
        {0, 1, 5, 4},  // -y
        {2, 6, 7, 3},  // +y
        {0, 2, 3, 1},  // -z
        {4, 5, 7, 6},  // +z
    };
    for (const auto& f : faces) {
        mesh.addTriangle(f[0], f[1], f[2]);
        mesh.addTriangle(f[0], f[2], f[3]);
    }
    return mesh;
}

TriangleMesh makeQuad() {
    TriangleMesh mesh;
    mesh.reserve(4, 2);
    mesh.addVertex({-1, 0, -1});
    mesh.addVertex({-1, 0, 1});
    mesh.addVertex({1, 0, 1});
    mesh.addVertex({1, 0, -1});
    mesh.addTriangle(0, 1, 2);
    mesh.addTriangle(0, 2, 3);
    mesh.setNormals({0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0});
    return mesh;
}

TriangleMesh makeTorusKnot(int p, int q, int segments, int sides, float tubeRadius) {
    if (p < 1 || q < 1 || segments < 3 || sides < 3 || !(tubeRadius > 0.0f) || !std::isfinite(tubeRadius))
        throw std::invalid_argument("makeTorusKnot: need p, q >= 1, segments, sides >= 3 and a positive tube "
                                    "radius, got p=" + std::to_string(p) + " q=" + std::to_string(q) +
                                    " segments=" + std::to_string(segments) + " sides=" +
                                    std::to_string(sides) + " tubeRadius=" + std::to_string(tubeRadius));
    requireVertexCount("makeTorusKnot", double(segments) * sides);

    // The (p,q) knot winds p times around the z axis and q times through the hole of a torus
    // with radii 2 and 1, scaled by 1/3 so the curve stays within the unit ball.
    const double P = p, Q = q;
    auto curve = [&](double t) {
        const double r = (2.0 + std::cos(Q * t)) / 3.0;
        return Float3{float(r * std::cos(P * t)), float(r * std::sin(P * t)), float(std::sin(Q * t) / 3.0)};
    };
    auto tangent = [&](double t) {
        const double r = (2.0 + std::cos(Q * t)) / 3.0, dr = -Q * std::sin(Q * t) / 3.0;
        return normalize(Float3{float(dr * std::cos(P * t) - r * P * std::sin(P * t)),
                                float(dr * std::sin(P * t) + r * P * std::cos(P * t)),
                                float(Q * std::cos(Q * t) / 3.0)});
    };

    const auto segs = static_cast<uint32_t>(segments), ring = static_cast<uint32_t>(sides);
    TriangleMesh mesh;
    mesh.reserve(size_t(segs) * ring, size_t(2) * segs * ring);
    std::vector<float> normals;
    normals.reserve(3 * size_t(segs) * ring);
    for (uint32_t i = 0; i < segs; ++i) {
        const double t = 2.0 * std::numbers::pi * i / segments;
        const Float3 c = curve(t), T = tangent(t);
        // The frame leans on the direction from the torus core circle to the curve. Unlike a
        // Frenet or parallel-transported frame it is periodic, so the tube closes without a
        // twist, and it is never parallel to T because the curve always advances around z.
        const Float3 core{float(2.0 / 3.0 * std::cos(P * t)), float(2.0 / 3.0 * std::sin(P * t)), 0.0f};
        const Float3 d = c - core;
        const Float3 N = normalize(d - dot(d, T) * T);
        const Float3 B = cross(T, N);
        for (uint32_t j = 0; j < ring; ++j) {
            const double a = 2.0 * std::numbers::pi * j / sides;
            // For a tube of constant radius the surface normal is exactly the offset direction.
            const Float3 n = normalize(float(std::cos(a)) * N + float(std::sin(a)) * B);
            mesh.addVertex(c + tubeRadius * n);
            appendNormal(normals, n);
        }
    }
    for (uint32_t i = 0; i < segs; ++i) {
        const uint32_t i1 = (i + 1) % segs;
        for (uint32_t j = 0; j < ring; ++j) {
            const uint32_t j1 = (j + 1) % ring;
            const uint32_t a = i * ring + j, b = i1 * ring + j, c = i1 * ring + j1, d = i * ring + j1;
            mesh.addTriangle(a, c, b);
            mesh.addTriangle(a, d, c);
        }
    }
    mesh.setNormals(std::move(normals));
    return mesh;
}

}  // namespace rtwall
