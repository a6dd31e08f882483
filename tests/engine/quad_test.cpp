// [bvh] primitives = "auto": triangle pairs handed to Embree as quads (issue 3, memory). The
// quad path must hit what the triangle path hits (closed meshes stay closed, near the origin and
// far from it), map every hit back to the same triangle and barycentrics (so normals, colours and
// alpha masks interpolate as before), and meshes whose pairs do not all pair must still render.
#include "material.h"
#include "scene_impl.h"
#include "shading.h"

#include <rtwall/engine.h>
#include <rtwall/engine_embree.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <cstdio>
#include <random>

namespace rtwall {
namespace {

using Prims = BvhSettings::Primitives;

SceneDesc oneMesh(std::shared_ptr<const TriangleMesh> mesh, const Transform& t, Prims prims, bool robust) {
    SceneDesc d;
    d.meshes.push_back({"m", "test", std::move(mesh)});
    d.materials.push_back(Material{});
    d.instances.push_back({0, 0, t});
    d.bvh.primitives = prims;
    d.bvh.robust = robust;
    return d;
}

struct RayHit {
    bool hit = false;
    float t = 0;
    TriangleHit tri{};
};

RayHit trace(const Scene& scene, const Float3& org, const Float3& dir) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray = {org.x, org.y, org.z, 0.0f, dir.x, dir.y, dir.z, 0.0f, INFINITY, 0xFFFFFFFFu, 0, 0};
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(embreeScene(scene), &ctx, &rh);
    RayHit r;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return r;
    r.hit = true;
    r.t = rh.ray.tfar;
    const InstanceData& inst = scene.impl().instances.at(rh.hit.instID[0]);
    r.tri = triangleHit(*inst.prims, rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v);
    return r;
}

// Smallest barycentric weight of a hit: near 0 the ray grazes an edge, where the two paths may
// round a hit onto either neighbour.
float edgeWeight(const TriangleHit& h) { return std::min({1.0f - h.u - h.v, h.u, h.v}); }

// A sphere's triangles pair as fans (north cap) and as (a,c,d),(a,d,b) quads: every pair shares
// an edge. Rays from a shell around it aimed inside: the quad path misses nothing the triangle
// path hits, finds the same distance, and maps the hit to the same triangle and barycentrics.
// Near the origin and at (1e6, -2e5, 3e5), fast and robust traversal.
TEST(QuadPrimitives, ClosedMeshHitsTheSameTrianglesAsTheTrianglePath) {
    auto sphere = std::make_shared<const TriangleMesh>(makeSphere(64, 128));
    for (bool robust : {false, true})
        for (const Float3 at : {Float3{0, 0, 0}, Float3{1e6f, -2e5f, 3e5f}}) {
            // A float origin far out is what an unrebased scene would give Embree; the engine
            // rebases scene files, but the primitives must cope with either.
            const Transform t = Transform::translate(at.x, at.y, at.z) * Transform::scale(3, 3, 3);
            const Scene quads(oneMesh(sphere, t, Prims::Auto, robust));
            const Scene tris(oneMesh(sphere, t, Prims::Triangles, robust));
            const Scene::PrimitiveStats st = quads.primitiveStats();
            ASSERT_EQ(st.quads, sphere->triangleCount() / 2);
            ASSERT_EQ(st.pairsSharingEdge, st.pairs);
            ASSERT_EQ(st.separateTriangles, 0u);
            ASSERT_EQ(tris.primitiveStats().quads, 0u);
            EXPECT_LT(quads.embreeBytes(), tris.embreeBytes());

            std::mt19937 rng(11);
            std::normal_distribution<float> g;
            const int rays = 100000;
            int leaksQ = 0, leaksT = 0, throughQ = 0, throughT = 0, otherTriangle = 0, far = 0;
            double worstT = 0, worstP = 0;
            for (int i = 0; i < rays; ++i) {
                const Float3 from = at + normalize(Float3{g(rng), g(rng), g(rng)}) * 20.0f;
                const Float3 to = at + normalize(Float3{g(rng), g(rng), g(rng)}) * 2.0f;
                const Float3 d = normalize(to - from);
                const RayHit q = trace(quads, from, d), r = trace(tris, from, d);
                leaksQ += !q.hit;
                leaksT += !r.hit;
                if (!q.hit || !r.hit) continue;
                // A ray that slips through a shared edge of the near side hits the far side.
                if (q.t > r.t * 1.01f) {
                    ++throughQ;
                    continue;
                }
                if (r.t > q.t * 1.01f) {
                    ++throughT;
                    continue;
                }
                worstT = std::max(worstT, double(std::fabs(q.t - r.t)) / double(r.t));
                if (q.tri.prim != r.tri.prim) {
                    // Only a ray through the shared diagonal or an edge may land on the neighbour.
                    ++otherTriangle;
                    far += edgeWeight(r.tri) > 1e-3f;
                    continue;
                }
                const Float3 pq = objectPosition(*sphere, q.tri.prim, q.tri.u, q.tri.v);
                const Float3 pr = objectPosition(*sphere, r.tri.prim, r.tri.u, r.tri.v);
                worstP = std::max<double>(worstP, maxAbsComponent(pq - pr));
            }
            const std::string where = std::string(robust ? "robust" : "fast") + (at.x != 0 ? " far" : " origin");
            EXPECT_EQ(leaksQ, 0) << where;
            EXPECT_EQ(leaksT, 0) << where;
            // Robust traversal is watertight for both; Embree's fast intersectors are not, and
            // may let a ray through a shared edge of the near side: quads no more often than
            // triangles, and within Embree's own verify bound of 0.002% either way.
            if (robust) {
                EXPECT_EQ(throughQ, 0) << where;
                EXPECT_EQ(throughT, 0) << where;
            }
            EXPECT_LE(throughQ, std::max(throughT, rays / 50000)) << where << " (triangles: " << throughT << ")";
            EXPECT_EQ(far, 0) << where << ": hits on another triangle away from its edges";
            EXPECT_LE(otherTriangle, rays / 1000) << where;
            // Distances agree to float rounding, and the mapped triangle and barycentrics give the
            // same object-space point (unit sphere; far out, the world coordinates carry only
            // ~1/16 unit, a third of that in object space).
            EXPECT_LT(worstT, at.x != 0 ? 2e-4 : 1e-5) << where;
            EXPECT_LT(worstP, at.x != 0 ? 0.05 : 2e-5) << where;
            std::printf("%s: %d/%d through the near side (quads/triangles), %d on the neighbour triangle, worst "
                        "distance %.2g, worst point %.2g\n",
                        where.c_str(), throughQ, throughT, otherTriangle, worstT, worstP);
        }
}

// Builds a mesh of random quads whose triangle pairs come in every layout: both triangles
// rotated at random (all nine codes), some pairs that share no edge, some window-layout pairs,
// and an odd triangle at the end. Vertex normals and colours make the attributes visible.
TriangleMesh mixedMesh(std::mt19937& rng, int quads, bool withUnpaired, bool oddTail) {
    TriangleMesh m;
    std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
    std::uniform_int_distribution<int> rot(0, 2), pct(0, 99);
    std::vector<float> normals;
    std::vector<uint8_t> colors;
    auto vertex = [&](const Float3& p) {
        const Float3 n = normalize(Float3{uni(rng), uni(rng), 2.0f});
        normals.insert(normals.end(), {n.x, n.y, n.z});
        colors.insert(colors.end(), {uint8_t(pct(rng) * 2), uint8_t(pct(rng) * 2), uint8_t(pct(rng) * 2)});
        return m.addVertex(p);
    };
    auto rotated = [&](uint32_t a, uint32_t b, uint32_t c, int r) {
        const uint32_t t[3] = {a, b, c};
        m.addTriangle(t[r % 3], t[(r + 1) % 3], t[(r + 2) % 3]);
    };
    // A grid of quads in z = 0 facing +z, each with a jittered (non-planar) corner.
    const int side = int(std::ceil(std::sqrt(double(quads))));
    for (int k = 0; k < quads; ++k) {
        const float x = float(k % side) * 2.0f / float(side) - 1.0f, y = float(k / side) * 2.0f / float(side) - 1.0f;
        const float s = 1.9f / float(side);
        const uint32_t a = vertex({x, y, 0}), b = vertex({x + s, y, 0.02f * uni(rng)}), c = vertex({x + s, y + s, 0}),
                       d = vertex({x, y + s, 0});
        if (withUnpaired && pct(rng) < 10) {
            // Two triangles of the quad but stored apart from each other: the pair (a,b,c) and a
            // lone triangle elsewhere in the quad share only a corner.
            const uint32_t e = vertex({x + 0.5f * s, y + s, 0});
            rotated(a, b, c, rot(rng));
            rotated(a, e, d, rot(rng));  // shares only a with (a,b,c)
            continue;
        }
        if (pct(rng) < 30) {
            m.addTriangle(a, b, c);  // the window layout: (q3,q0,q1),(q2,q3,q1) with q = (b,c,d,a)
            m.addTriangle(d, a, c);
        } else {
            rotated(a, b, c, rot(rng));
            rotated(a, c, d, rot(rng));
        }
    }
    if (oddTail) {
        const uint32_t a = vertex({-1, 1.2f, 0}), b = vertex({1, 1.2f, 0}), c = vertex({0, 1.6f, 0});
        m.addTriangle(a, b, c);
    }
    m.setNormals(normals);
    m.setColors(colors);
    return m;
}

// Every hit maps back to the triangle the triangle path finds, with the same barycentrics, so the
// interpolated normal, colour and object position (what alpha masks read) agree within 1e-5.
TEST(QuadPrimitives, MixedPairLayoutsInterpolateLikeTriangles) {
    std::mt19937 rng(5);
    for (bool unpaired : {false, true}) {
        auto mesh = std::make_shared<const TriangleMesh>(mixedMesh(rng, 400, unpaired, true));
        const Scene quads(oneMesh(mesh, Transform{}, Prims::Auto, false));
        const Scene tris(oneMesh(mesh, Transform{}, Prims::Triangles, false));
        const Scene::PrimitiveStats st = quads.primitiveStats();
        ASSERT_EQ(st.quads, mesh->triangleCount() / 2);
        EXPECT_EQ(st.quadsInPlace, 0u) << "mixed layouts need a quad buffer";
        EXPECT_GT(st.quadIndexBytes, 0u);
        EXPECT_EQ(st.separateTriangles, st.pairs - st.pairsSharingEdge + 1) << "the unpaired second halves and the odd tail";
        if (unpaired) {
            EXPECT_LT(st.pairsSharingEdge, st.pairs);
        }
        EXPECT_FALSE(quads.impl().meshPrims[0].codes.empty()) << "the pairs come in several layouts";

        std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
        const int rays = 50000;
        int hits = 0, mismatch = 0, otherTriangle = 0, far = 0;
        double worstN = 0, worstC = 0, worstP = 0;
        for (int i = 0; i < rays; ++i) {
            const Float3 from{uni(rng) * 1.1f, uni(rng) * 1.4f + 0.2f, 3.0f};
            const Float3 d = normalize(Float3{uni(rng) * 0.05f, uni(rng) * 0.05f, -1.0f});
            const RayHit q = trace(quads, from, d), r = trace(tris, from, d);
            if (q.hit != r.hit) {
                ++mismatch;
                continue;
            }
            if (!q.hit) continue;
            ++hits;
            // The mapped triangle and barycentrics give the point Embree hit, on an edge too
            // (a degenerate quad's hit rounded past its diagonal must not become another triangle).
            const Float3 pq = objectPosition(*mesh, q.tri.prim, q.tri.u, q.tri.v);
            EXPECT_LT(maxAbsComponent(pq - (from + d * q.t)), 1e-4f);
            if (q.tri.prim != r.tri.prim) {
                ++otherTriangle;
                far += edgeWeight(r.tri) > 1e-3f;
                continue;
            }
            const uint32_t* t = mesh->indices() + 3 * size_t(q.tri.prim);
            auto normalAt = [&](const TriangleHit& h) {
                return mesh->normal(t[0]) * (1.0f - h.u - h.v) + mesh->normal(t[1]) * h.u + mesh->normal(t[2]) * h.v;
            };
            const Float3 nq = normalAt(q.tri), nr = normalAt(r.tri);
            worstN = std::max<double>(worstN, maxAbsComponent(nq - nr));
            const Color cq = vertexColorAt(*mesh, q.tri.prim, q.tri.u, q.tri.v), cr = vertexColorAt(*mesh, r.tri.prim, r.tri.u, r.tri.v);
            worstC = std::max<double>(worstC, maxAbsComponent(cq - cr));
            const Float3 pr = objectPosition(*mesh, r.tri.prim, r.tri.u, r.tri.v);
            worstP = std::max<double>(worstP, maxAbsComponent(pq - pr));
        }
        EXPECT_GT(hits, rays / 2);
        EXPECT_LE(mismatch, rays / 10000) << "hit/miss differs only for rays grazing an outer edge";
        EXPECT_EQ(far, 0);
        EXPECT_LE(otherTriangle, rays / 500);
        EXPECT_LT(worstN, 1e-5);
        EXPECT_LT(worstC, 1e-5);
        EXPECT_LT(worstP, 1e-5);
    }
}

// A mesh stored in the window layout is read in place: no quad index buffer at all.
TEST(QuadPrimitives, WindowLayoutNeedsNoQuadBuffer) {
    TriangleMesh m;
    for (int k = 0; k < 50; ++k) {
        const float x = float(k);
        const uint32_t a = m.addVertex({x, 0, 0}), b = m.addVertex({x + 1, 0, 0}), c = m.addVertex({x + 1, 1, 0}),
                       d = m.addVertex({x, 1, 0});
        m.addTriangle(a, b, c);
        m.addTriangle(d, a, c);
    }
    auto mesh = std::make_shared<const TriangleMesh>(std::move(m));
    const Scene quads(oneMesh(mesh, Transform{}, Prims::Auto, false));
    const Scene::PrimitiveStats st = quads.primitiveStats();
    EXPECT_EQ(st.quads, 50u);
    EXPECT_EQ(st.quadsInPlace, 50u);
    EXPECT_EQ(st.quadIndexBytes, 0u);
    const RayHit h = trace(quads, {10.25f, 0.75f, 1.0f}, {0, 0, -1});  // above the diagonal: triangle (d,a,c)
    ASSERT_TRUE(h.hit);
    EXPECT_EQ(h.tri.prim, 21u);
    const Float3 p = objectPosition(*mesh, h.tri.prim, h.tri.u, h.tri.v);
    EXPECT_NEAR(p.x, 10.25f, 1e-5f);
    EXPECT_NEAR(p.y, 0.75f, 1e-5f);
}

// Meshes that mostly do not pair stay triangles: a pair of triangles that share no edge.
TEST(QuadPrimitives, UnpairableMeshStaysTriangles) {
    TriangleMesh m;
    for (int k = 0; k < 20; ++k) {
        const float x = float(k);
        const uint32_t a = m.addVertex({x, 0, 0}), b = m.addVertex({x + 1, 0, 0}), c = m.addVertex({x + 1, 1, 0}),
                       d = m.addVertex({x, 1, 0}), e = m.addVertex({x - 0.5f, 2, 0});
        m.addTriangle(a, b, c);
        m.addTriangle(a, d, e);  // shares a corner only
    }
    auto mesh = std::make_shared<const TriangleMesh>(std::move(m));
    const Scene scene(oneMesh(mesh, Transform{}, Prims::Auto, false));
    const Scene::PrimitiveStats st = scene.primitiveStats();
    EXPECT_EQ(st.quads, 0u);
    EXPECT_EQ(st.pairsSharingEdge, 0u);
    EXPECT_EQ(st.separateTriangles, 40u);
    const RayHit h = trace(scene, {4.7f, 1.5f, 1.0f}, {0, 0, -1});  // in (a,d,e) of pair 5
    ASSERT_TRUE(h.hit);
    EXPECT_EQ(h.tri.prim, 11u);
}

// Whole images: vertex normals (Phong highlight), vertex colours and an alpha mask cut by marble
// veins, shadows through the holes, packet and single-ray kernels. Quads and triangles agree to
// rounding: mean difference under 0.05 levels, at most 0.1% of channels more than 2 levels off
// (a ray through a shared edge may fall on either side; the intersection arithmetic differs).
TEST(QuadPrimitives, ImagesWithNormalsColoursAndAlphaMatchTheTrianglePath) {
    std::mt19937 rng(9);
    auto mesh = std::make_shared<const TriangleMesh>(mixedMesh(rng, 2500, true, true));
    SceneDesc d;
    d.meshes.push_back({"mixed", "test", mesh});
    d.meshes.push_back({"ball", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(24, 48))});
    Material leaf;
    leaf.type = MaterialType::Phong;
    leaf.specular = {0.4f, 0.4f, 0.4f};
    leaf.alpha.kind = TextureKind::Marble;
    leaf.alpha.scale = 0.25f;
    leaf.alpha.color2 = {0, 0, 0};
    leaf.alphaCutoff = 0.35f;
    d.materials = {leaf, Material{}};
    d.instances.push_back({0, 0, Transform{}});
    d.instances.push_back({1, 1, Transform::translate(0.2, 0.1, -1.0) * Transform::scale(0.5, 0.5, 0.5)});
    d.lights.push_back(Light{LightType::Point, {1.0f, 1.5f, 3.0f}, {0, -1, 0}, {1, 1, 1}, 12.0f});
    CameraDesc cam;
    cam.position = {0.3f, -0.4f, 3.2f};
    cam.lookAt = {0, 0.1f, 0};
    d.cameras.push_back(cam);
    RenderSettings rs;
    rs.width = 200;
    rs.height = 160;
    rs.threads = 2;
    rs.ambient = {0.1f, 0.1f, 0.1f};
    for (KernelType kernel : {KernelType::Packet, KernelType::Single}) {
        rs.kernel = kernel;
        SceneDesc dq = d, dt = d;
        dq.bvh.primitives = Prims::Auto;
        dt.bvh.primitives = Prims::Triangles;
        const Scene sq(dq), st(dt);
        ASSERT_GT(sq.primitiveStats().quads, 0u);
        const Image a = renderFrame(sq, Camera(cam, rs.width, rs.height), rs);
        const Image b = renderFrame(st, Camera(cam, rs.width, rs.height), rs);
        ASSERT_EQ(a.rgb.size(), b.rgb.size());
        double sum = 0;
        size_t off = 0, holes = 0;
        for (size_t i = 0; i < a.rgb.size(); ++i) {
            const int diff = std::abs(int(a.rgb[i]) - int(b.rgb[i]));
            sum += diff;
            off += diff > 2;
        }
        // The mask really cuts holes: the background shows through in the leaf's area.
        const Image bg = [&] {
            SceneDesc e = dt;
            e.instances.clear();
            e.instances.push_back({1, 1, d.instances[1].transform});
            return renderFrame(Scene(e), Camera(cam, rs.width, rs.height), rs);
        }();
        for (size_t i = 0; i < a.rgb.size(); ++i) holes += a.rgb[i] == bg.rgb[i];
        EXPECT_GT(holes, a.rgb.size() / 10);
        EXPECT_LT(sum / double(a.rgb.size()), 0.05) << int(kernel);
        EXPECT_LE(off, a.rgb.size() / 1000) << int(kernel);
    }
}

}  // namespace
}  // namespace rtwall
