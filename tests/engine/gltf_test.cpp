// glTF 2.0 assemblies (issue 20): files written by an independent writer (tools/gltf_testgen.py,
// Python's standard library) read into unique meshes placed by instances, materials mapped onto
// rtwall's, the three encodings (data URIs, GLB, external files) alike to the rendered byte, and
// every malformed file one InputError line naming the file and the fault.
#include "test_util.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

// The generated files, written once per process into a directory of its own (ctest runs the
// tests of this program in parallel processes).
const fs::path& generated() {
    static const fs::path dir = [] {
        const fs::path d = test::processScratchDir("gltf-generated");
        const std::string cmd = "python3 " + (test::sourceDir() / "tools" / "gltf_testgen.py").string() + " --malformed --out " + d.string();
        EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
        return d;
    }();
    return dir;
}

size_t partNamed(const Assembly& a, const std::string& name) {
    for (size_t i = 0; i < a.parts.size(); ++i)
        if (a.parts[i].name == name) return i;
    ADD_FAILURE() << "no part " << name;
    return 0;
}

std::vector<const AssemblyInstance*> instancesOf(const Assembly& a, const std::string& part) {
    const size_t p = partNamed(a, part);
    std::vector<const AssemblyInstance*> out;
    for (const AssemblyInstance& in : a.instances)
        if (in.part == p) out.push_back(&in);
    return out;
}

// The world position of the mesh's vertex v under the instance.
std::array<double, 3> worldVertex(const Assembly& a, const AssemblyInstance& in, size_t v) {
    const Float3 p = a.meshes[in.mesh]->position(v);
    const auto& m = in.transform;
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

// The centre of the instance's box (its vertices' mean).
std::array<double, 3> centre(const Assembly& a, const AssemblyInstance& in) {
    std::array<double, 3> c{0, 0, 0};
    const size_t n = a.meshes[in.mesh]->vertexCount();
    for (size_t v = 0; v < n; ++v) {
        const auto w = worldVertex(a, in, v);
        for (int k = 0; k < 3; ++k) c[k] += w[k] / double(n);
    }
    return c;
}

void expectNear3(const std::array<double, 3>& got, std::array<double, 3> want) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], 1e-6) << "component " << k;
}

TEST(Gltf, StructureMeshesStoredOnceAndInstanced) {
    const Assembly a = loadAssembly(generated() / "embedded.gltf");
    EXPECT_EQ(a.format, "gltf");
    // One mesh per primitive: box, colour quad, pane, and the pipe's two primitives.
    ASSERT_EQ(a.meshes.size(), 5u);
    ASSERT_EQ(a.meshNames.size(), 5u);
    EXPECT_EQ(a.parts.size(), 9u);
    ASSERT_EQ(a.instances.size(), 11u);
    // The box: three nodes and four EXT_mesh_gpu_instancing instances, all of one mesh.
    const uint32_t box = instancesOf(a, "box_a").at(0)->mesh;
    EXPECT_EQ(a.meshNames[box], "box");
    EXPECT_EQ(std::count_if(a.instances.begin(), a.instances.end(), [&](const AssemblyInstance& i) { return i.mesh == box; }), 7);
    EXPECT_EQ(a.meshes[box]->triangleCount(), 12u);
    EXPECT_TRUE(a.meshes[box]->hasNormals());
    EXPECT_TRUE(a.meshes[box]->hasUVs());

    // Transforms: translation; translation and rotation; a scaled parent over a matrix.
    expectNear3(centre(a, *instancesOf(a, "box_a").at(0)), {-2.0, 0.5, 0.0});
    expectNear3(centre(a, *instancesOf(a, "box_b").at(0)), {2.0, 0.5, 0.0});
    const AssemblyInstance& c = *instancesOf(a, "box_c").at(0);
    expectNear3(centre(a, c), {0.0, 0.5, -2.0});  // group: scale 0.5, then (0, 0, -2); box_c: (0, 1, 0)
    EXPECT_NEAR(c.transform[0], 0.5, 1e-12);
    EXPECT_EQ(a.parts[instancesOf(a, "box_c").at(0)->part].parent, int32_t(partNamed(a, "group")));
    EXPECT_EQ(a.parts[partNamed(a, "group")].parent, int32_t(partNamed(a, "root")));
    // box_b is turned 45 degrees about y: its corner (0.5, *, 0.5) lies on the x axis.
    const AssemblyInstance& b = *instancesOf(a, "box_b").at(0);
    EXPECT_NEAR(b.transform[0], std::sqrt(0.5), 1e-12);
    EXPECT_NEAR(b.transform[2], std::sqrt(0.5), 1e-12);
    const auto bolts = instancesOf(a, "bolts");
    ASSERT_EQ(bolts.size(), 4u);
    expectNear3(centre(a, *bolts[2]), {1.5, 0.1, -1.5});
    EXPECT_NEAR(bolts[2]->transform[5], 0.2, 1e-7);

    // The pipe: a triangle strip of 6 vertices (4 triangles) and a triangle, of two materials.
    const auto pipe = instancesOf(a, "pipes");
    ASSERT_EQ(pipe.size(), 2u);
    EXPECT_EQ(a.meshes[pipe[0]->mesh]->triangleCount(), 4u);
    EXPECT_EQ(a.meshes[pipe[1]->mesh]->triangleCount(), 1u);
    EXPECT_EQ(a.materials[pipe[0]->material].name, "steel");
    EXPECT_EQ(a.materials[pipe[1]->material].name, "default");
    // The strip's triangles all face +z (every other one is wound the other way in the strip).
    const TriangleMesh& strip = *a.meshes[pipe[0]->mesh];
    for (size_t t = 0; t < strip.triangleCount(); ++t) {
        const Float3 p0 = strip.position(strip.indices()[3 * t]), p1 = strip.position(strip.indices()[3 * t + 1]),
                     p2 = strip.position(strip.indices()[3 * t + 2]);
        const float nz = (p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x);
        EXPECT_LT(nz, 0.0f) << "triangle " << t;  // (0,0),(0,.3),(1,0): clockwise seen from +z, as the strip starts
    }
}

TEST(Gltf, VertexColoursTextureAndMaterials) {
    const Assembly a = loadAssembly(generated() / "embedded.gltf");
    const TriangleMesh& quad = *a.meshes[instancesOf(a, "floor_colours").at(0)->mesh];
    ASSERT_TRUE(quad.hasColors());
    // Linear 1.0 / 0.0 encode to sRGB 255 / 0: red, green, blue, white.
    const uint8_t want[12] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
    for (int i = 0; i < 12; ++i) EXPECT_EQ(quad.colors()[i], want[i]) << i;

    const AssemblyMaterial& glass = a.materials[instancesOf(a, "window").at(0)->material];
    EXPECT_EQ(glass.name, "glass");
    EXPECT_FLOAT_EQ(glass.transmission, 1.0f);
    EXPECT_FLOAT_EQ(glass.ior, 1.45f);
    const AssemblyMaterial& textured = a.materials[instancesOf(a, "box_a").at(0)->material];
    ASSERT_FALSE(textured.baseColorTexture.empty());
    const auto& png = *a.files.at(textured.baseColorTexture);
    ASSERT_GT(png.size(), 8u);
    EXPECT_EQ(png[1], 'P');  // the encoded PNG, decoded by the engine

    // The mapping onto rtwall's materials (docs/assemblies.md, "Materials").
    const SceneDesc d = sceneFromMeshFile(generated() / "embedded.gltf");
    auto material = [&](const std::string& name) {
        for (const Material& m : d.materials)
            if (m.name == name) return m;
        ADD_FAILURE() << name;
        return Material{};
    };
    EXPECT_EQ(material("glass").type, MaterialType::Glass);
    EXPECT_FLOAT_EQ(material("glass").ior, 1.45f);
    EXPECT_EQ(material("steel").type, MaterialType::Metal);
    EXPECT_FLOAT_EQ(material("steel").roughness, 0.2f);
    EXPECT_EQ(material("painted").type, MaterialType::Phong);
    EXPECT_EQ(material("textured").texture.kind, TextureKind::Image);
    EXPECT_TRUE(d.files.count(material("textured").texture.file));
    EXPECT_EQ(d.instances.size(), 11u);
    EXPECT_EQ(d.meshes.size(), 5u);
    EXPECT_EQ(d.partPath(d.instances[instancesOf(a, "box_c").at(0) - a.instances.data()].part), "root/group/box_c");
}

Image render(const SceneDesc& d) {
    SceneDesc s = d;
    s.settings.width = 160;
    s.settings.height = 120;
    s.settings.threads = 2;
    const Scene scene(s);
    return renderFrame(scene, Camera(s.cameras.front(), s.settings.width, s.settings.height), s.settings);
}

// Data URIs, GLB and external files hold the same assembly: the same image to the byte, and one
// that shows the checker texture's red.
TEST(Gltf, ThreeEncodingsRenderAlike) {
    const Image embedded = render(sceneFromMeshFile(generated() / "embedded.gltf"));
    if (std::getenv("RTWALL_DUMP")) writePng(embedded, "/tmp/gltf_embedded.png");
    const Image binary = render(sceneFromMeshFile(generated() / "binary.glb"));
    const Image external = render(sceneFromMeshFile(generated() / "external.gltf"));
    EXPECT_EQ(loadAssembly(generated() / "binary.glb").format, "glb");
    EXPECT_TRUE(embedded.rgb == binary.rgb);
    EXPECT_TRUE(embedded.rgb == external.rgb);
    size_t red = 0;
    for (size_t i = 0; i + 2 < embedded.rgb.size(); i += 3)
        red += embedded.rgb[i] > 2 * embedded.rgb[i + 1] + 30 && embedded.rgb[i] > 2 * embedded.rgb[i + 2] + 30;
    EXPECT_GT(red, 20u);
}

size_t uniqueTriangles(const Assembly& a) {
    size_t n = 0;
    for (const auto& m : a.meshes) n += m->triangleCount();
    return n;
}

size_t instancedTriangles(const Assembly& a) {
    size_t n = 0;
    for (const AssemblyInstance& in : a.instances) n += a.meshes[in.mesh]->triangleCount();
    return n;
}

// Issue 29: 21 glTF meshes, 20 of them over one box's accessors (two materials between them, and
// four more copies by EXT_mesh_gpu_instancing): the box is stored once. The same assembly with
// every box over accessors of its own (the same bytes) is 21 meshes as far as accessors tell,
// 2 after congruent-shape detection, and renders to the same bytes either way.
TEST(Gltf, PrimitivesOverTheSameAccessorsAreOneMesh) {
    const Assembly shared = loadAssembly(generated() / "shared_accessors.glb");
    ASSERT_EQ(shared.meshes.size(), 2u);
    EXPECT_EQ(uniqueTriangles(shared), 332u);  // 12 + 320
    ASSERT_EQ(shared.instances.size(), 25u);  // 21 nodes and 4 EXT_mesh_gpu_instancing copies
    EXPECT_EQ(instancedTriangles(shared), 608u);
    const uint32_t box = instancesOf(shared, "box node 0").at(0)->mesh;
    EXPECT_EQ(shared.meshNames[box], "box00");  // named after the first glTF mesh that uses it
    for (int i = 0; i < 20; ++i) {
        const AssemblyInstance& in = *instancesOf(shared, "box node " + std::to_string(i)).at(0);
        EXPECT_EQ(in.mesh, box) << i;
        EXPECT_EQ(shared.materials[in.material].name, i % 2 ? "blue" : "red") << i;  // its own material
    }
    for (const AssemblyInstance* in : instancesOf(shared, "bolts")) EXPECT_EQ(in->mesh, box);
    EXPECT_EQ(instancesOf(shared, "bolts").size(), 4u);

    AssemblyOptions off;
    off.shareCongruent = false;
    const Assembly copied = loadAssembly(generated() / "copied_accessors.glb", off);
    EXPECT_EQ(copied.meshes.size(), 21u);
    EXPECT_EQ(uniqueTriangles(copied), 560u);
    EXPECT_EQ(instancedTriangles(copied), 608u);
    // Congruent-shape detection (on by default) finds the copies over other accessors too.
    const Assembly found = loadAssembly(generated() / "copied_accessors.glb");
    EXPECT_EQ(found.meshes.size(), 2u);
    EXPECT_EQ(found.congruentMeshes, 19u);
    EXPECT_EQ(uniqueTriangles(found), 332u);

    // All three render to the same bytes: the copies are exact, so their motion is exactly the
    // identity.
    const Image a = render(sceneFromMeshFile(generated() / "shared_accessors.glb"));
    const Image b = render(sceneFromMeshFile(generated() / "copied_accessors.glb"));
    SceneDesc undetected = sceneFromMeshFile(generated() / "copied_accessors.glb");
    const SceneDesc flat = sceneFromAssembly(copied, generated() / "copied_accessors.glb");
    undetected.meshes = flat.meshes;
    undetected.instances = flat.instances;
    EXPECT_TRUE(render(undetected).rgb == a.rgb);
    if (std::getenv("RTWALL_DUMP")) writePng(a, "/tmp/gltf_shared.png");
    EXPECT_TRUE(a.rgb == b.rgb);
    // Not an empty picture: the red and the blue boxes both show.
    size_t red = 0, blue = 0;
    for (size_t i = 0; i + 2 < a.rgb.size(); i += 3) {
        red += a.rgb[i] > 2 * a.rgb[i + 2] + 30;
        blue += a.rgb[i + 2] > 2 * a.rgb[i] + 30;
    }
    EXPECT_GT(red, 100u);
    EXPECT_GT(blue, 100u);
}

// glTF's alphaMode, alphaCutoff and doubleSided (issue 29), mapped onto rtwall's alpha modes.
TEST(Gltf, AlphaModesMapOntoMasksAndHashedAlpha) {
    const Assembly a = loadAssembly(generated() / "alpha.glb");
    ASSERT_EQ(a.materials.size(), 5u);
    using Alpha = AssemblyMaterial::Alpha;
    EXPECT_EQ(a.materials[0].alphaMode, Alpha::Mask);
    EXPECT_FLOAT_EQ(a.materials[0].alphaCutoff, 0.4f);
    EXPECT_EQ(a.materials[1].alphaMode, Alpha::Blend);
    EXPECT_EQ(a.materials[2].alphaMode, Alpha::Mask);
    EXPECT_FLOAT_EQ(a.materials[2].alphaCutoff, 0.5f);  // glTF's default
    EXPECT_EQ(a.materials[3].alphaMode, Alpha::Opaque);
    EXPECT_TRUE(a.materials[3].doubleSided);
    EXPECT_FALSE(a.materials[0].doubleSided);

    const SceneDesc d = sceneFromMeshFile(generated() / "alpha.glb");
    ASSERT_EQ(d.materials.size(), 5u);
    const Material& mask = d.materials[0];
    EXPECT_EQ(mask.alphaMode, AlphaMode::Mask);
    EXPECT_EQ(mask.alphaChannel, AlphaChannel::Alpha);
    EXPECT_EQ(mask.alpha, mask.texture);  // the base colour texture's alpha
    EXPECT_FLOAT_EQ(mask.alphaCutoff, 0.4f);
    EXPECT_EQ(d.materials[1].alphaMode, AlphaMode::Hashed);
    EXPECT_FLOAT_EQ(d.materials[1].opacity, 0.5f);
    EXPECT_EQ(d.materials[1].alpha.kind, TextureKind::None);
    EXPECT_FLOAT_EQ(d.materials[2].opacity, 0.3f);
    EXPECT_FLOAT_EQ(d.materials[3].opacity, 1.0f);  // OPAQUE ignores alpha
    EXPECT_TRUE(d.materials[3].twoSided);
    EXPECT_FALSE(d.materials[4].twoSided);
    EXPECT_TRUE(rendersStochastically(d));  // the blend's coins average over frames
}

// The four quads before the green backdrop, seen straight on; each pixel classified.
struct AlphaStage {
    SceneDesc scene;
    AlphaStage(int supersample) : scene(sceneFromMeshFile(generated() / "alpha.glb")) {
        CameraDesc& c = scene.cameras.front();
        c.position = {0, 0, 8};
        c.lookAt = {0, 0, 0};
        c.up = {0, 1, 0};
        c.fovY = 30.0f;
        scene.settings.width = 640;
        scene.settings.height = 240;
        scene.settings.threads = 2;
        scene.settings.supersample = supersample;
    }
    Image render(const TraceOptions& trace = {}) const {
        const Scene s(scene);
        return renderFrame(s, Camera(scene.cameras.front(), 640, 240), scene.settings, 0, nullptr, trace);
    }
};
// Pixels per scene unit at z = 0, and the pixel column of x there.
const double kPixelsPerUnit = 120.0 / (8.0 * std::tan(15.0 * M_PI / 180.0));
int columnOf(double x) { return int(std::lround(320.0 + x * kPixelsPerUnit)); }
enum class Hue { Green, Red, Blue, Yellow, Other };
Hue hueAt(const Image& img, int x, int y) {
    const uint8_t* p = img.rgb.data() + 3 * (size_t(y) * img.width + x);
    const int r = p[0], g = p[1], b = p[2];
    if (g > 2 * r + 20 && g > 2 * b + 20) return Hue::Green;
    if (r > 2 * g + 20 && r > 2 * b + 20) return Hue::Red;
    if (b > 2 * r + 20 && b > 2 * g + 20) return Hue::Blue;
    if (r > 2 * b + 20 && g > 2 * b + 20) return Hue::Yellow;
    return Hue::Other;
}
// Counts of each hue over the columns [x0, x1] (scene units at z = 0) and the rows of the
// quads' middle half (y in [-0.25, 0.25]).
std::map<Hue, int> hues(const Image& img, double x0, double x1) {
    std::map<Hue, int> n;
    const int rows = int(0.25 * kPixelsPerUnit);
    for (int y = 120 - rows; y <= 120 + rows; ++y)
        for (int x = columnOf(x0); x <= columnOf(x1); ++x) ++n[hueAt(img, x, y)];
    return n;
}

TEST(Gltf, AlphaModesRender) {
    const AlphaStage one(1);
    const Image img = one.render();
    if (std::getenv("RTWALL_DUMP")) writePng(img, "/tmp/gltf_alpha.png");
    const int area = hues(img, -2.25 - 0.35, -2.25 - 0.1)[Hue::Green] + hues(img, -2.25 - 0.35, -2.25 - 0.1)[Hue::Other];
    ASSERT_GT(area, 200);
    // MASK: the texture's transparent left half is a hole, its opaque right half is the red quad.
    EXPECT_EQ(hues(img, -2.25 - 0.35, -2.25 - 0.1)[Hue::Green], area);
    EXPECT_EQ(hues(img, -2.25 + 0.1, -2.25 + 0.35)[Hue::Red], area);
    // MASK with the base colour's alpha 0.3 below the cutoff: all hole; OPAQUE ignores alpha 0.1.
    const auto faded = hues(img, 0.75 - 0.35, 0.75 + 0.35);
    EXPECT_EQ(faded.size(), 1u);
    EXPECT_GT(faded.at(Hue::Green), 0);
    const auto opaque = hues(img, 2.25 - 0.35, 2.25 + 0.35);
    EXPECT_EQ(opaque.size(), 1u);
    EXPECT_GT(opaque.at(Hue::Yellow), 0);
    // BLEND at alpha 0.5, one ray a pixel: each pixel is the quad or the backdrop, with the
    // quad's share binomial around one half (n > 1000 pixels: 4 sigma is under 0.06).
    const auto blend = hues(img, -0.75 - 0.35, -0.75 + 0.35);
    const int n = blend.count(Hue::Blue) ? blend.at(Hue::Blue) : 0, m = blend.count(Hue::Green) ? blend.at(Hue::Green) : 0;
    EXPECT_GT(n + m, 1000);
    EXPECT_EQ(n + m, [&] { int t = 0; for (auto& [h, c] : blend) t += c; return t; }());
    const double share = double(n) / double(n + m), sigma = std::sqrt(0.25 / double(n + m));
    EXPECT_NEAR(share, 0.5, 4.0 * sigma) << n << " blue of " << n + m;

    // Deterministic: the same bytes again, from single rays, and from every packet width.
    EXPECT_TRUE(one.render().rgb == img.rgb);
    AlphaStage single(1);
    single.scene.settings.kernel = KernelType::Single;
    EXPECT_TRUE(single.render().rgb == img.rgb);
    for (int width : {4, 8, 16}) {
        TraceOptions trace;
        trace.packetWidth = width;
        EXPECT_TRUE(one.render(trace).rgb == img.rgb) << width;
    }

    // More rays per pixel blend: with 8 x 8 samples hardly a pixel of the quad is all one or the
    // other, and the mean is the blend of the two colours.
    const Image many = AlphaStage(8).render();
    const auto mixed = hues(many, -0.75 - 0.35, -0.75 + 0.35);
    const int pure = (mixed.count(Hue::Blue) ? mixed.at(Hue::Blue) : 0) + (mixed.count(Hue::Green) ? mixed.at(Hue::Green) : 0);
    EXPECT_LT(pure, (n + m) / 10) << "pixels still all quad or all backdrop";
}

// Issue 29: a flat export (every solid its own mesh, placed in world coordinates) of 20 solids
// that are 3 shapes, 3 of them with their vertices and triangles numbered otherwise, and 5 near
// misses: the 3 shapes are found and stored once, each instance placing the kept mesh where its
// own was; the near misses (scaled by 1.001, a vertex moved by 1e-3, renumbered or not) stay
// apart, and so do two inside-out mirror images from the bracket (not from each other) and the
// true mirror image of a chiral corner, while the true mirror image of the bracket, which has a
// plane of symmetry, is the bracket turned; so do two folds of one quad (the same vertices, other
// surfaces), while a moved copy of one fold is merged.
TEST(Gltf, CongruentShapesAreStoredOnce) {
    const fs::path file = generated() / "congruent.glb";
    AssemblyOptions off;
    off.shareCongruent = false;
    const Assembly flat = loadAssembly(file, off);
    const Assembly found = loadAssembly(file);
    ASSERT_EQ(flat.meshes.size(), 32u);
    EXPECT_EQ(flat.congruentMeshes, 0u);
    EXPECT_EQ(found.meshes.size(), 11u);
    EXPECT_EQ(found.congruentMeshes, 21u);
    ASSERT_EQ(found.instances.size(), 32u);
    EXPECT_EQ(instancedTriangles(found), instancedTriangles(flat));
    EXPECT_EQ(uniqueTriangles(flat), 618u);
    EXPECT_EQ(uniqueTriangles(found), 208u);  // the 11 kept shapes
    // Every instance's world vertices are where the flat file put them (within the tolerance,
    // 1e-5 of the diagonal, which is under 2.3 here; 500 units out, the floats' precision).
    for (size_t i = 0; i < found.instances.size(); ++i) {
        const AssemblyInstance& a = found.instances[i];
        const AssemblyInstance& b = flat.instances[i];
        const TriangleMesh& ma = *found.meshes[a.mesh];
        const size_t n = ma.vertexCount();
        ASSERT_EQ(n, flat.meshes[b.mesh]->vertexCount()) << i;
        const double limit = std::max(2.3e-5, 4 * 500.0 * 0x1.0p-23);
        // A renumbered copy's vertex v is some vertex of the file's mesh, each used once.
        const std::string& part = found.parts[a.part].name;
        const bool renumbered = part.find("renumbered") != std::string::npos || part == "bracket mirrored outward";
        std::vector<bool> taken(n);
        for (size_t v = 0; v < n; ++v) {
            const auto pa = worldVertex(found, a, v);
            size_t match = v;
            if (renumbered) {
                match = n;
                for (size_t w = 0; w < n && match == n; ++w) {
                    const auto pb = worldVertex(flat, b, w);
                    if (!taken[w] && std::fabs(pa[0] - pb[0]) <= limit && std::fabs(pa[1] - pb[1]) <= limit &&
                        std::fabs(pa[2] - pb[2]) <= limit)
                        match = w;
                }
                ASSERT_LT(match, n) << "instance " << i << " vertex " << v << ": no vertex of the file there";
                taken[match] = true;
            }
            const auto pb = worldVertex(flat, b, match);
            for (int k = 0; k < 3; ++k) ASSERT_NEAR(pa[k], pb[k], limit) << "instance " << i << " vertex " << v;
        }
    }
    // The near misses kept their own meshes.
    for (const char* name : {"plate scaled 1.001", "bolt with a vertex moved", "fold b", "bolt renumbered, vertex moved", "corner mirrored"}) {
        const uint32_t m = instancesOf(found, name).at(0)->mesh;
        EXPECT_EQ(std::count_if(found.instances.begin(), found.instances.end(), [&](const AssemblyInstance& in) { return in.mesh == m; }), 1)
            << name;
    }
    EXPECT_EQ(instancesOf(found, "fold a").at(0)->mesh, instancesOf(found, "fold a moved").at(0)->mesh);
    // Renumbered copies are found without a given correspondence.
    for (const char* name : {"bolt renumbered 1", "bolt renumbered 2"})
        EXPECT_EQ(instancesOf(found, name).at(0)->mesh, instancesOf(found, "bolt 0").at(0)->mesh) << name;
    EXPECT_EQ(instancesOf(found, "bracket renumbered").at(0)->mesh, instancesOf(found, "bracket 0").at(0)->mesh);
    // The two mirror images are congruent to each other, never to the bracket.
    const uint32_t mirrored = instancesOf(found, "bracket mirrored").at(0)->mesh;
    EXPECT_EQ(instancesOf(found, "bracket renumbered mirrored").at(0)->mesh, mirrored);
    EXPECT_NE(mirrored, instancesOf(found, "bracket 0").at(0)->mesh);
    // A true mirror image (wound outward) of the bracket, which has a plane of symmetry, is the
    // bracket turned; the chiral corner's is not the corner, though a turned corner is.
    EXPECT_EQ(instancesOf(found, "bracket mirrored outward").at(0)->mesh, instancesOf(found, "bracket 0").at(0)->mesh);
    EXPECT_EQ(instancesOf(found, "corner turned").at(0)->mesh, instancesOf(found, "corner").at(0)->mesh);
    // 500 units out the file's floats are coarser than the tolerance: the tolerance's floor is
    // their precision, and the plate there is found.
    EXPECT_EQ(instancesOf(found, "plate far out").at(0)->mesh, instancesOf(found, "plate 0").at(0)->mesh);
    // A tolerance of 1e-2 merges the scaled plate and the moved vertex too; never the mirror
    // or the other fold.
    AssemblyOptions loose;
    loose.congruenceTolerance = 1e-2;
    EXPECT_EQ(loadAssembly(file, loose).meshes.size(), 8u);

    // The renders agree: the merged instances' triangles differ from the file's by float
    // rounding only (a rigid motion is not exact in floats), so a few edge pixels may differ.
    const Image a = render(sceneFromMeshFile(file));
    SceneDesc flatScene = sceneFromMeshFile(file);  // its camera and lights, the flat file's meshes
    const SceneDesc undetected = sceneFromAssembly(flat, file);
    flatScene.meshes = undetected.meshes;
    flatScene.instances = undetected.instances;
    const Image b = render(flatScene);
    if (std::getenv("RTWALL_DUMP")) writePng(a, "/tmp/gltf_congruent.png");
    size_t differing = 0, worst = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        const size_t d = size_t(std::abs(int(a.rgb[i]) - int(b.rgb[i])));
        differing += d != 0;
        worst = std::max(worst, d);
    }
    EXPECT_LT(differing, a.rgb.size() / 200) << "worst " << worst;
}

// Zero scales are legal glTF (exporters hide objects so), but nothing can be traced through a
// flat instance: box_a (scale 0 on y) and one of the four GPU-instanced bolts (scale 0) are left
// out, one warning line per node naming the file; the rest loads as ever.
TEST(Gltf, ZeroScaleInstancesAreLeftOutWithOneLinePerNode) {
    const Assembly a = loadAssembly(generated() / "zero_scale.glb");
    EXPECT_EQ(a.instances.size(), 9u);
    EXPECT_TRUE(instancesOf(a, "box_a").empty());
    EXPECT_EQ(instancesOf(a, "bolts").size(), 3u);
    EXPECT_EQ(instancesOf(a, "box_b").size(), 1u);
    std::vector<std::string> singular;
    for (const std::string& w : a.warnings)
        if (w.find("singular transform") != std::string::npos) singular.push_back(w);
    ASSERT_EQ(singular.size(), 2u) << ::testing::PrintToString(a.warnings);
    const std::string file = (generated() / "zero_scale.glb").string();
    EXPECT_EQ(singular[0], file + ": node 1: 1 instance with a singular transform (a zero scale) left out: nothing can be traced through it");
    EXPECT_EQ(singular[1].rfind(file + ": node 6: 1 instance", 0), 0u) << singular[1];
    // It renders as the same assembly with those two instances taken out.
    Assembly full = loadAssembly(generated() / "binary.glb");
    const size_t boxA = partNamed(full, "box_a"), bolts = partNamed(full, "bolts");
    size_t bolt = 0;
    std::vector<AssemblyInstance> kept;
    for (const AssemblyInstance& in : full.instances)
        if (in.part != boxA && !(in.part == bolts && bolt++ == 2)) kept.push_back(in);
    full.instances = kept;
    EXPECT_TRUE(render(sceneFromAssembly(full, generated() / "binary.glb")).rgb ==
                render(sceneFromAssembly(a, generated() / "zero_scale.glb")).rgb);
}

TEST(Gltf, MalformedFilesAreOneLineErrors) {
    const struct {
        const char* file;
        const char* fault;
    } cases[] = {
        {"truncated.glb", "truncated.glb: "},
        {"bad_json.gltf", "bad_json.gltf: "},
        {"accessor_overflow.gltf", "mesh 0 primitive 0 POSITION: accessor 0: 1000000 elements from byte 0 do not fit buffer view 0"},
        {"view_outside_buffer.gltf", "buffer view 0 (bytes 0 + "},
        {"bad_accessor_index.gltf", "mesh 0 primitive 0 POSITION: accessor 99 does not exist"},
        {"index_out_of_range.gltf", "mesh 1 primitive 0 index 0 = 200 is out of range (4 vertices)"},
        {"missing_buffer.gltf", "missing.bin"},
        {"huge_count.gltf", "2147483648 elements"},
        {"node_cycle.gltf", "node 3 is reached twice"},
        {"bad_alpha_mode.glb", "material 1: alphaMode 'SOMETIMES' is not OPAQUE, MASK or BLEND"},
        // Found by fuzz_import_gltf: tinygltf 2.7 read an image's buffer view past its buffer.
        {"image_view_outside_buffer.glb", "image 0: buffer view 12 lies outside its buffer"},
    };
    for (const auto& c : cases) {
        const fs::path f = generated() / c.file;
        const std::string e = test::inputErrorOf([&] { loadAssembly(f); });
        EXPECT_NE(e.find(f.string() + ": "), std::string::npos) << e;
        EXPECT_NE(e.find(c.fault), std::string::npos) << c.file << ": " << e;
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
    // From memory (the fuzz target's entry): an external URI is refused, not read.
    const std::string json = R"({"asset":{"version":"2.0"},"buffers":[{"uri":"/etc/passwd","byteLength":4}]})";
    const std::string e = test::inputErrorOf(
        [&] { decodeGltf(reinterpret_cast<const unsigned char*>(json.data()), json.size(), "memory.gltf"); });
    EXPECT_NE(e.find("memory.gltf: "), std::string::npos) << e;
    EXPECT_NE(e.find("not read here"), std::string::npos) << e;
}

}  // namespace
}  // namespace rtwall
