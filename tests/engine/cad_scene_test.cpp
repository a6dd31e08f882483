// Massive-CAD support in the engine: groups of groups flattened in double precision, scene
// rebasing far from the origin (watertightness, self-intersection and image equality against the
// same scene at the origin), BVH settings, and generated scenes loaded from files and caches.

#include <rtwall/engine.h>
#include <rtwall/engine_embree.h>
#include <rtwall/vec.h>

#include "scene_impl.h"
#include "shading_scenes.h"
#include "test_util.h"

#include "generators.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
    const fs::path dir = fs::path(::testing::TempDir()) / "rtwall_cad_tests" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

fs::path writeScene(const fs::path& dir, const std::string& text) {
    const fs::path file = dir / "scene.toml";
    std::ofstream(file) << text;
    return file;
}

std::string loadError(const fs::path& file) {
    return test::inputErrorOf([&] { loadSceneFile(file); });
}

// ------------------------------------------------------------------------------------ groups

TEST(SceneGroups, GroupsOfGroupsAreFlattenedWithComposedTransforms) {
    const fs::path dir = scratch("groups");
    const fs::path file = writeScene(dir, test::sceneText("groups"));
    const SceneDesc s = loadSceneFile(file);
    ASSERT_EQ(s.instances.size(), 5u);
    EXPECT_EQ(s.origin, (std::array<double, 3>{0, 0, 0}));
    // Order: depth first, as written.
    const double tx[5] = {101, 99, 102, 98, 0}, ty[5] = {10, 10, 20, 20, 0}, sc[5] = {1, 1, 2, 2, 1};
    for (size_t i = 0; i < 5; ++i) {
        EXPECT_DOUBLE_EQ(s.instances[i].transform.m[3], tx[i]) << i;
        EXPECT_DOUBLE_EQ(s.instances[i].transform.m[7], ty[i]) << i;
        EXPECT_DOUBLE_EQ(s.instances[i].transform.m[0], sc[i]) << i;
    }
    // The inner material wins; the outer instance's material fills in the rest.
    EXPECT_EQ(s.materials[s.instances[0].material].name, "red");
    EXPECT_EQ(s.materials[s.instances[1].material].name, "blue");
    EXPECT_EQ(s.materials[s.instances[4].material].name, "");
    // One mesh, shared by every instance: no copies.
    EXPECT_EQ(s.meshes.size(), 1u);
}

TEST(SceneGroups, MistakesNameTheLine) {
    const fs::path dir = scratch("group_errors");
    const std::string head = "[[mesh]]\nname = \"box\"\nshape = \"box\"\n";
    auto err = [&](const std::string& text) { return loadError(writeScene(dir, head + text)); };
    // A group may only use groups defined before it: no cycles, not even a self-reference.
    EXPECT_NE(err("[[group]]\nname = \"g\"\n[[group.instance]]\ngroup = \"g\"\n").find(":7: "), std::string::npos);
    EXPECT_NE(err("[[group]]\nname = \"g\"\n[[group.instance]]\ngroup = \"g\"\n").find("defined before"), std::string::npos);
    EXPECT_NE(err("[[instance]]\ngroup = \"nope\"\n").find(":5: "), std::string::npos);
    EXPECT_NE(err("[[instance]]\nmesh = \"box\"\ngroup = \"x\"\n").find("exactly one of 'mesh' and 'group'"), std::string::npos);
    EXPECT_NE(err("[[group]]\nname = \"g\"\n").find("at least one"), std::string::npos);
    EXPECT_NE(err("[[group]]\nname = \"g\"\n[[group.instance]]\nmesh = \"box\"\ncolour = 1\n").find("unknown key 'colour'"),
              std::string::npos);
    EXPECT_NE(err("[bvh]\nquality = \"ultra\"\n").find("'ultra' is not one of"), std::string::npos);
    EXPECT_NE(err("[load]\ncache = 1\n").find("expected true or false"), std::string::npos);
}

// Ten levels of ten children each would be 10^10 instances: refused before anything is expanded.
TEST(SceneGroups, ExpansionIsBounded) {
    const fs::path dir = scratch("group_bomb");
    std::string text = "[[mesh]]\nname = \"box\"\nshape = \"box\"\n[[group]]\nname = \"g0\"\n";
    for (int k = 0; k < 10; ++k) text += "[[group.instance]]\nmesh = \"box\"\n";
    for (int level = 1; level <= 10; ++level) {
        text += "[[group]]\nname = \"g" + std::to_string(level) + "\"\n";
        for (int k = 0; k < 10; ++k) text += "[[group.instance]]\ngroup = \"g" + std::to_string(level - 1) + "\"\n";
    }
    text += "[[instance]]\ngroup = \"g10\"\n";
    const std::string e = loadError(writeScene(dir, text));
    EXPECT_NE(e.find("more than 16777216 mesh instances"), std::string::npos) << e;
}

// ------------------------------------------------------------------------- far from the origin

std::string sphereScene(double x, double y, double z) {
    return test::sphereOverFloor(x, y, z, "\n[image]\nwidth = 160\nheight = 120\n[render]\nambient = [0.1, 0.1, 0.1]", 48, 96,
                                 "[[light]]\ntype = \"directional\"\ndirection = [-0.3, -1, -0.2]\n");
}

// A far scene is rebased: the single-precision data is small, the origin holds the offset.
TEST(FarFromOrigin, SceneIsRebasedInDoublePrecision) {
    const SceneDesc s = loadSceneFile(writeScene(scratch("rebase"), sphereScene(148376, 1234, -223423)));
    EXPECT_NEAR(s.origin[0], 148376, 8);
    EXPECT_NEAR(s.origin[2], -223423, 8);
    for (const InstanceDesc& in : s.instances) EXPECT_LT(std::fabs(in.transform.m[3]) + std::fabs(in.transform.m[11]), 20.0);
    EXPECT_LT(length(s.cameras[0].position), 50.0f);
    // The exact world position survives in double: origin + relative = what the file said.
    EXPECT_DOUBLE_EQ(s.origin[0] + s.instances[0].transform.m[3], 148376.0);
    EXPECT_DOUBLE_EQ(s.origin[2] + s.instances[0].transform.m[11], -223423.0);
}

// Embree's verify style: the same picture at the origin and at (148376, 1234, -223423), and at
// (1e6, -2e5, 3e5). Tolerance: mean difference under 0.25 levels, at most 0.2% of pixels more
// than 8 levels off (tessellation edges may round differently after the rebase).
TEST(FarFromOrigin, RendersLikeAtTheOrigin) {
    auto render = [](const std::string& name, double x, double y, double z) {
        const SceneDesc s = loadSceneFile(writeScene(scratch(name), sphereScene(x, y, z)));
        const Scene scene(s);
        RenderSettings rs = s.settings;
        rs.threads = 2;
        return renderFrame(scene, Camera(s.cameras[0], rs.width, rs.height), rs);
    };
    const Image ref = render("at_origin", 0, 0, 0);
    for (const auto& [name, x, y, z] : std::vector<std::tuple<std::string, double, double, double>>{
             {"embree_verify", 148376, 1234, -223423}, {"million", 1e6, -2e5, 3e5}}) {
        const Image far = render(name, x, y, z);
        ASSERT_EQ(far.rgb.size(), ref.rgb.size());
        double sum = 0;
        size_t off = 0;
        for (size_t i = 0; i < ref.rgb.size(); ++i) {
            const int d = std::abs(int(ref.rgb[i]) - int(far.rgb[i]));
            sum += d;
            off += d > 8;
        }
        EXPECT_LT(sum / double(ref.rgb.size()), 0.25) << name;
        EXPECT_LE(double(off) / double(ref.rgb.size()), 0.002) << name;
    }
}

// A closed sphere at (1e6, -2e5, 3e5): rays aimed at its inside never slip through a shared edge
// (fewer than 0.002% may, Embree's verify bound; we expect none), and rays spawned outward from
// the hit points, offset by the engine's scale-aware rule, never hit the sphere again (it is
// convex), so there is no self-intersection and no shadow acne.
TEST(FarFromOrigin, ClosedMeshIsWatertightAndSpawnedRaysDoNotSelfIntersect) {
    const fs::path dir = scratch("watertight");
    const fs::path file = writeScene(dir, R"(
[bvh]
robust = true
[[mesh]]
name = "ball"
shape = "sphere"
rings = 64
segments = 128
[[instance]]
mesh = "ball"
scale = 3
translate = [1000000, -200000, 300000]
)");
    const SceneDesc s = loadSceneFile(file);
    const Scene scene(s);
    const Float3 centre{float(1e6 - s.origin[0]), float(-2e5 - s.origin[1]), float(3e5 - s.origin[2])};
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    std::mt19937 rng(7);
    std::normal_distribution<float> g;
    const int rays = 200000;
    int leaks = 0, selfHits = 0;
    for (int i = 0; i < rays; ++i) {
        const Float3 from = centre + normalize(Float3{g(rng), g(rng), g(rng)}) * 20.0f;
        const Float3 to = centre + normalize(Float3{g(rng), g(rng), g(rng)}) * 2.0f;
        const Float3 d = normalize(to - from);
        RTCRayHit rh{};
        rh.ray = {from.x, from.y, from.z, 0.0f, d.x, d.y, d.z, 0.0f, INFINITY, 0xFFFFFFFFu, 0, 0};
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(embreeScene(scene), &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
            ++leaks;
            continue;
        }
        const Float3 p = from + d * rh.ray.tfar;
        // The hit facet's own normal (the instance is a uniform scale, so object space will do):
        // the sphere is a convex polyhedron, so nothing above a facet's plane can hit it again.
        Float3 ng = normalize(Float3{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
        if (dot(ng, p - centre) < 0) ng = ng * -1.0f;
        // shading.cpp's offsetOrigin rule: (1 + max|p|) / 65536 along the normal.
        const float eps = (1.0f + std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)})) / 65536.0f;
        const Float3 org = p + ng * eps;
        Float3 out = normalize(Float3{g(rng), g(rng), g(rng)});
        if (dot(out, ng) < 0) out = out * -1.0f;
        RTCRay shadow{org.x, org.y, org.z, 0.0f, out.x, out.y, out.z, 0.0f, INFINITY, 0xFFFFFFFFu, 0, 0};
        rtcOccluded1(embreeScene(scene), &ctx, &shadow);
        if (shadow.tfar < 0) ++selfHits;
    }
    EXPECT_EQ(leaks, 0) << "of " << rays;
    EXPECT_EQ(selfHits, 0) << "of " << rays - leaks;
}

// ------------------------------------------------------------------------------- BVH settings

TEST(BvhSettings, EveryQualityAndCompactModeGivesTheSameImage) {
    const fs::path dir = scratch("bvh");
    const SceneDesc base = loadSceneFile(writeScene(dir, sphereScene(0, 0, 0)));
    RenderSettings rs = base.settings;
    rs.threads = 2;
    const Image ref = renderFrame(Scene(base), Camera(base.cameras[0], rs.width, rs.height), rs);
    for (auto q : {BvhSettings::Quality::Low, BvhSettings::Quality::Medium, BvhSettings::Quality::High})
        for (bool compact : {false, true}) {
            SceneDesc s = base;
            s.bvh = {q, compact, true};
            const Scene scene(s);
            EXPECT_GT(scene.embreeBytes(), 0u);
            const Image img = renderFrame(scene, Camera(s.cameras[0], rs.width, rs.height), rs);
            size_t off = 0;
            for (size_t i = 0; i < img.rgb.size(); ++i) off += std::abs(int(img.rgb[i]) - int(ref.rgb[i])) > 8;
            EXPECT_LE(off, img.rgb.size() / 1000) << int(q) << " " << compact;
        }
}

TEST(BvhSettings, BuildCanBeCancelled) {
    const SceneDesc s = loadSceneFile(writeScene(scratch("cancel"), sphereScene(0, 0, 0)));
    EXPECT_THROW(Scene(s, [](double) { return false; }), Cancelled);
}

// ------------------------------------------------------------------------- generated scenes

Image renderScene(const SceneDesc& s, int w, int h) {
    RenderSettings rs = s.settings;
    rs.width = w;
    rs.height = h;
    rs.threads = 2;
    const Scene scene(s);
    return renderFrame(scene, Camera(s.cameras[0], w, h), rs);
}

// A small generated plant: every section file format, far from the origin, pumps as groups.
// Rendered from the mesh files and again from the caches: the same bytes.
TEST(GeneratedScenes, PowerplantRendersIdenticallyFromSourcesAndCache) {
    const fs::path dir = scratch("powerplant");
    gen::genPowerplant({.out = dir, .triangles = 60000, .copies = 2});
    std::set<std::string> exts;
    for (const auto& e : fs::directory_iterator(dir / "meshes")) exts.insert(e.path().extension().string());
    for (const char* ext : {".vtp", ".vtk", ".vtu", ".ply", ".obj"}) EXPECT_TRUE(exts.count(ext)) << ext;

    SceneLoadStats parse, fill, cached;
    SceneLoadOptions lo;
    lo.cache = false;
    lo.stats = &parse;
    const SceneDesc fromFiles = loadSceneFile(dir / "scene.toml", lo);
    EXPECT_EQ(parse.cacheHits, 0u);
    EXPECT_GT(fromFiles.origin[0], 1e5);  // rebased
    lo.cache = true;
    lo.stats = &fill;
    (void)loadSceneFile(dir / "scene.toml", lo);
    EXPECT_EQ(fill.cacheWritten, fill.filesImported);
    lo.stats = &cached;
    const SceneDesc fromCache = loadSceneFile(dir / "scene.toml", lo);
    EXPECT_EQ(cached.filesImported, 0u);
    EXPECT_EQ(cached.cacheHits, fill.filesImported);

    int64_t unique = 0;
    for (const MeshDesc& m : fromFiles.meshes) unique += int64_t(m.mesh->triangleCount());
    EXPECT_GE(unique, 60000);
    EXPECT_EQ(fromFiles.instances.size(), fromCache.instances.size());
    // The cached meshes are the mapped cache files, and those pages are what Embree reads: the
    // buffers of every mesh geometry are the mesh's own arrays, not copies. The index buffer is
    // the mesh's own too where the mesh went to Embree as triangles or as quads read in place;
    // other quads have the quad index buffer made for them (MeshPrimitives::quadIndex).
    {
        const Scene scene(fromCache);
        ASSERT_EQ(scene.impl().meshScenes.size(), fromCache.meshes.size());
        for (size_t i = 0; i < fromCache.meshes.size(); ++i) {
            const TriangleMesh& mesh = *fromCache.meshes[i].mesh;
            EXPECT_TRUE(mesh.isMapped()) << fromCache.meshes[i].name;
            EXPECT_NE(fromFiles.meshes[i].mesh->positions(), mesh.positions());
            RTCGeometry g = rtcGetGeometry(scene.impl().meshScenes[i], 0);
            ASSERT_NE(g, nullptr);
            EXPECT_EQ(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_VERTEX, 0), static_cast<const void*>(mesh.positions()));
            const MeshPrimitives& mp = scene.impl().meshPrims[i];
            const void* index = mp.quads > 0 && !mp.quadIndex.empty() ? static_cast<const void*>(mp.quadIndex.data())
                                                                         : static_cast<const void*>(mesh.indices());
            EXPECT_EQ(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_INDEX, 0), index);
        }
        EXPECT_GT(scene.geometryBytes(), 0u);
    }
    const Image a = renderScene(fromFiles, 96, 72), b = renderScene(fromCache, 96, 72);
    EXPECT_EQ(a.rgb, b.rgb);
    // Not a blank picture: the plant is in view.
    std::set<uint8_t> values(a.rgb.begin(), a.rgb.end());
    EXPECT_GT(values.size(), 20u);
}

TEST(GeneratedScenes, SunflowerFieldInstancesEveryPlantFromSharedMeshes) {
    const fs::path dir = scratch("sunflowers");
    gen::genSunflowers({.out = dir, .triangles = 2000, .instances = 150, .trees = 1, .treeTriangles = 5000});
    const SceneDesc s = loadSceneFile(dir / "scene.toml");
    // Patches hold 70 plants, so 150 plants make 3 patches = 210 plants; 4 meshes each, plus the
    // ground and the tree.
    EXPECT_EQ(s.instances.size(), 210u * 4 + 2);
    EXPECT_EQ(s.meshes.size(), 10u * 4 + 2);
    int64_t unique = 0, instanced = 0;
    for (const MeshDesc& m : s.meshes) unique += int64_t(m.mesh->triangleCount());
    for (const InstanceDesc& in : s.instances) instanced += int64_t(s.meshes[in.mesh].mesh->triangleCount());
    EXPECT_GT(instanced, 100 * unique / 10);
    const Image img = renderScene(s, 64, 48);
    std::set<uint8_t> values(img.rgb.begin(), img.rgb.end());
    EXPECT_GT(values.size(), 10u);

    // Alpha-masked foliage: the leaves' mask cuts holes that camera and shadow rays pass through,
    // so the same field with solid leaves renders differently.
    SceneDesc solid = s;
    bool masked = false;
    for (Material& m : solid.materials)
        if (m.name == "leaf") {
            masked = m.alpha.kind != TextureKind::None;
            m.alpha.kind = TextureKind::None;
        }
    ASSERT_TRUE(masked);
    const Image solidImg = renderScene(solid, 64, 48);
    EXPECT_NE(img.rgb, solidImg.rgb);
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// Loading reports progress and stops when asked (Ctrl-C in the command line).
TEST(SceneLoad, ProgressIsReportedAndCanCancel) {
    const fs::path dir = scratch("load_cancel");
    gen::genPowerplant({.out = dir, .triangles = 5000});
    std::vector<double> seen;
    SceneLoadOptions lo;
    lo.cache = false;
    lo.progress = [&](double f) {
        seen.push_back(f);
        return true;
    };
    (void)loadSceneFile(dir / "scene.toml", lo);
    ASSERT_FALSE(seen.empty());
    EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
    EXPECT_DOUBLE_EQ(seen.back(), 1.0);
    lo.progress = [](double) { return false; };
    EXPECT_THROW(loadSceneFile(dir / "scene.toml", lo), Cancelled);
}

}  // namespace
}  // namespace rtwall
