// Canonical mesh bytes (encodeMesh, decodeMesh) and the content hash meshes and assets go by.
// A mesh is not a message: it travels inside MeshData as a blob, and clients cache it by hash.
#include "message_fields.h"

#include <xxhash.h>

namespace rtwall::cluster {

// -- Meshes --------------------------------------------------------------------------------------

namespace {

void writeMesh(Writer& w, const TriangleMesh& mesh) {
    const size_t vertices = mesh.vertexCount(), triangles = mesh.triangleCount();
    w.u64(vertices);
    const float* p = mesh.positions();
    for (size_t i = 0; i < 3 * vertices; ++i) w.f32(p[i]);
    w.u64(triangles);
    const uint32_t* idx = mesh.indices();
    for (size_t i = 0; i < 3 * triangles; ++i) w.u32(idx[i]);
    w.boolean(mesh.hasNormals());
    if (const float* n = mesh.normals())
        for (size_t i = 0; i < 3 * vertices; ++i) w.f32(n[i]);
    // Version 4: vertex colours, after the normals.
    w.boolean(mesh.hasColors());
    if (const uint8_t* c = mesh.colors()) w.bytes(c, 3 * vertices);
    // Version 5: texture coordinates (u, v per vertex), after the colours.
    w.boolean(mesh.hasUVs());
    if (const float* t = mesh.uvs())
        for (size_t i = 0; i < 2 * vertices; ++i) w.f32(t[i]);
}

}  // namespace

std::vector<uint8_t> encodeMesh(const TriangleMesh& mesh) {
    return measureAndWrite([&](Writer& w) { writeMesh(w, mesh); });
}

TriangleMesh decodeMesh(const uint8_t* data, size_t size) {
    if (size > kMaxMeshBytes) fail("mesh of " + std::to_string(size) + " bytes exceeds the limit");
    Reader r(data, size);
    constexpr size_t kVertexBytes = 3 * sizeof(float), kTriangleBytes = 3 * sizeof(uint32_t);
    TriangleMesh mesh;

    const uint64_t vertices = r.u64();
    // 32-bit indices address at most 2^32 - 1 vertices (TriangleMesh's own limit).
    r.expectElements(vertices, kVertexBytes, std::numeric_limits<uint32_t>::max());
    mesh.reserve(size_t(vertices), 0);
    for (uint64_t v = 0; v < vertices; ++v) {
        Float3 p;
        FieldReader(r).float3(p);
        mesh.addVertex(p);
    }

    const uint64_t triangles = r.u64();
    r.expectElements(triangles, kTriangleBytes, kMaxMeshBytes / kTriangleBytes);
    mesh.reserve(size_t(vertices), size_t(triangles));
    for (uint64_t t = 0; t < triangles; ++t) {
        uint32_t c[3];
        for (uint32_t& i : c) {
            i = r.u32();
            if (i >= vertices)
                fail("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(i) + " of " +
                     std::to_string(vertices));
        }
        mesh.addTriangle(c[0], c[1], c[2]);
    }

    if (r.boolean()) {
        // The encoder writes the flag only for a mesh with normals, which has vertices; anything
        // else would not re-encode to the same bytes (and hash).
        if (vertices == 0) fail("normals flag set on a mesh without vertices");
        r.expectElements(vertices, kVertexBytes, std::numeric_limits<uint32_t>::max());
        std::vector<float> normals(size_t(3 * vertices));
        for (float& n : normals) n = r.f32();
        mesh.setNormals(std::move(normals));
    }
    if (r.boolean()) {
        if (vertices == 0) fail("colours flag set on a mesh without vertices");
        r.expectElements(vertices, 3, std::numeric_limits<uint32_t>::max());
        std::vector<uint8_t> colors(size_t(3 * vertices));
        r.bytes(colors.data(), colors.size());
        mesh.setColors(std::move(colors));
    }
    if (r.boolean()) {
        if (vertices == 0) fail("texture coordinates flag set on a mesh without vertices");
        r.expectElements(vertices, 2 * sizeof(float), std::numeric_limits<uint32_t>::max());
        std::vector<float> uv(size_t(2 * vertices));
        for (size_t i = 0; i < uv.size(); ++i) {
            uv[i] = r.f32();
            if (!std::isfinite(uv[i])) fail("vertex " + std::to_string(i / 2) + " has a non-finite texture coordinate");
        }
        mesh.setUVs(std::move(uv));
    }
    r.expectEnd();
    return mesh;
}

Hash128 hashBytes(const uint8_t* data, size_t size) {
    const XXH128_hash_t h = XXH3_128bits(data, size);
    return {h.low64, h.high64};
}

}  // namespace rtwall::cluster
