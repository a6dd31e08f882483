// Mesh files that hold many bodies (issue 29): a plant exported as one OBJ, PLY or STL is one
// mesh, though it may hold the same bolt a thousand times. Its bodies (triangles joined through
// shared vertices) are made meshes of their own, the congruence test of assemblies
// (congruence.cpp) finds those that are the same shape up to a rigid motion, and those are kept
// once and placed by instances; the bodies without a copy go back together into one mesh.
#include "mesh_internal.h"

#include <algorithm>
#include <numeric>

namespace rtwall {
namespace {

// Union-find over vertices, joined by the triangles.
struct Components {
    std::vector<uint32_t> parent;
    explicit Components(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
    uint32_t find(uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    }
    void join(uint32_t a, uint32_t b) {
        a = find(a), b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

// The triangles `tris` of `m` (and the vertices they use) as a mesh of their own, in the same
// coordinates and with the same origin.
TriangleMesh subMesh(const TriangleMesh& m, const std::vector<uint32_t>& tris, std::vector<uint32_t>& localOf) {
    std::vector<uint32_t> used;
    std::vector<uint32_t> indices;
    indices.reserve(3 * tris.size());
    for (uint32_t t : tris)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m.indices()[3 * size_t(t) + size_t(k)];
            if (localOf[v] == UINT32_MAX) {
                localOf[v] = uint32_t(used.size());
                used.push_back(v);
            }
            indices.push_back(localOf[v]);
        }
    TriangleMesh out;
    std::vector<float> xyz(3 * used.size()), normals, uvs;
    std::vector<uint8_t> colors;
    for (size_t i = 0; i < used.size(); ++i) std::copy_n(m.positions() + 3 * size_t(used[i]), 3, xyz.begin() + ptrdiff_t(3 * i));
    if (m.hasNormals()) {
        normals.resize(3 * used.size());
        for (size_t i = 0; i < used.size(); ++i) std::copy_n(m.normals() + 3 * size_t(used[i]), 3, normals.begin() + ptrdiff_t(3 * i));
    }
    if (m.hasUVs()) {
        uvs.resize(2 * used.size());
        for (size_t i = 0; i < used.size(); ++i) std::copy_n(m.uvs() + 2 * size_t(used[i]), 2, uvs.begin() + ptrdiff_t(2 * i));
    }
    if (m.hasColors()) {
        colors.resize(3 * used.size());
        for (size_t i = 0; i < used.size(); ++i) std::copy_n(m.colors() + 3 * size_t(used[i]), 3, colors.begin() + ptrdiff_t(3 * i));
    }
    for (uint32_t v : used) localOf[v] = UINT32_MAX;  // ready for the next body
    detail::MeshAccess::setVertexCount(out, used.size());
    detail::MeshAccess::positions(out).assign(std::move(xyz));
    detail::MeshAccess::indices(out).assign(std::move(indices));
    if (m.hasNormals()) out.setNormals(std::move(normals));
    if (m.hasUVs()) out.setUVs(std::move(uvs));
    if (m.hasColors()) out.setColors(std::move(colors));
    out.setOrigin(m.origin());
    return out;
}

Assembly whole(std::shared_ptr<const TriangleMesh> mesh, const std::string& name) {
    Assembly a;
    a.format = "mesh";
    const auto& o = mesh->origin();
    a.meshes.push_back(std::move(mesh));
    a.meshNames.push_back(name);
    a.materials.push_back(AssemblyMaterial{});
    a.parts.push_back({name, -1});
    a.instances.push_back({0, 0, 0, {1, 0, 0, o[0], 0, 1, 0, o[1], 0, 0, 1, o[2]}});
    return a;
}

}  // namespace

Assembly shareCongruentBodies(std::shared_ptr<const TriangleMesh> mesh, const std::string& name, double tolerance) {
    const TriangleMesh& m = *mesh;
    const size_t nt = m.triangleCount();
    Components c(m.vertexCount());
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t* i = m.indices() + 3 * t;
        c.join(i[0], i[1]);
        c.join(i[0], i[2]);
    }
    // Bodies in the order of their first triangle.
    std::vector<uint32_t> bodyOfRoot(m.vertexCount(), UINT32_MAX);
    std::vector<std::vector<uint32_t>> bodies;
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t r = c.find(m.indices()[3 * t]);
        if (bodyOfRoot[r] == UINT32_MAX) {
            bodyOfRoot[r] = uint32_t(bodies.size());
            bodies.emplace_back();
        }
        bodies[bodyOfRoot[r]].push_back(uint32_t(t));
    }
    // One body, or a soup of unconnected triangles (an unwelded STL: under 4 triangles a body on
    // average), has nothing to find: the mesh stays as it is.
    if (bodies.size() < 2 || 4 * bodies.size() > nt) return whole(std::move(mesh), name);
    Assembly a;
    a.format = "mesh";
    a.materials.push_back(AssemblyMaterial{});
    a.parts.push_back({name, -1});
    const auto& o = m.origin();
    const detail::Affine place{1, 0, 0, o[0], 0, 1, 0, o[1], 0, 0, 1, o[2]};
    std::vector<uint32_t> localOf(m.vertexCount(), UINT32_MAX);
    for (size_t b = 0; b < bodies.size(); ++b) {
        a.meshes.push_back(std::make_shared<const TriangleMesh>(subMesh(m, bodies[b], localOf)));
        a.meshNames.push_back(name + " body " + std::to_string(b + 1));
        a.instances.push_back({uint32_t(b), 0, 0, place});
    }
    a.congruentMeshes = detail::shareCongruentMeshes(a, tolerance);
    if (a.congruentMeshes == 0) return whole(std::move(mesh), name);
    // The bodies without a copy go back together, as the file had them, into one mesh placed first.
    std::vector<size_t> uses(a.meshes.size());
    for (const AssemblyInstance& in : a.instances) ++uses[in.mesh];
    std::vector<uint32_t> singles;
    for (size_t b = 0; b < a.instances.size(); ++b)  // instance b places body b
        if (uses[a.instances[b].mesh] == 1)
            singles.insert(singles.end(), bodies[b].begin(), bodies[b].end());
    Assembly out;
    out.format = "mesh";
    out.materials = a.materials;
    out.parts = a.parts;
    out.congruentMeshes = a.congruentMeshes;
    if (!singles.empty()) {
        std::sort(singles.begin(), singles.end());
        out.meshes.push_back(std::make_shared<const TriangleMesh>(subMesh(m, singles, localOf)));
        out.meshNames.push_back(name + " (bodies without copies)");
        out.instances.push_back({0, 0, 0, place});
    }
    std::vector<uint32_t> renumber(a.meshes.size(), UINT32_MAX);
    for (const AssemblyInstance& in : a.instances) {
        if (uses[in.mesh] == 1) continue;
        if (renumber[in.mesh] == UINT32_MAX) {
            renumber[in.mesh] = uint32_t(out.meshes.size());
            out.meshes.push_back(a.meshes[in.mesh]);
            out.meshNames.push_back(a.meshNames[in.mesh]);
        }
        AssemblyInstance k = in;
        k.mesh = renumber[in.mesh];
        out.instances.push_back(k);
    }
    return out;
}

}  // namespace rtwall
