// Scene files that name assembly files (issue 20): a STEP assembly written through OpenCASCADE
// (rtwall gen step) brought into a TOML scene by [[mesh]] file = "...step": its meshes once, its
// instances under the [[instance]]'s transform, its part names and materials kept, the
// tessellation from [import] or the [[mesh]]; bad files and keys are one-line errors. And the
// shipped demo scene (configs/demos/step_assembly.toml) loads and renders.
#include "step_assembly.h"
#include "test_util.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <set>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

const fs::path& stepFile() { return test::stepAssembly(); }  // 21 part instances (3 modules of 7) of 3 parts

// A floor mesh and one instance of the assembly, which the tests below add to.
const std::string kFloorAndPlant = "\n[[mesh]]\nname = \"floor\"\nshape = \"quad\"\n[[instance]]\nmesh = \"plant\"";

std::string sceneWith(const std::string& rest) {
    return "[[mesh]]\nname = \"plant\"\nfile = \"" + stepFile().string() + "\"\n" + rest;
}

TEST(AssemblyScene, StepAssemblyPlacedByInstancesWithItsPartsAndMaterials) {
    const auto dir = test::scratchDir();
    const SceneDesc s = loadSceneFile(test::writeFile(dir / "s.toml", sceneWith(kFloorAndPlant + R"(
[[instance]]
mesh = "plant"
translate = [1000, 0, 0]
rotate = [0, 0, 90]
[[instance]]
mesh = "floor"
)")));
    const Assembly a = loadAssembly(stepFile());
    ASSERT_EQ(a.instances.size(), 21u);
    // Meshes once: the three parts and the floor, whatever the number of placements.
    ASSERT_EQ(s.meshes.size(), 4u);
    ASSERT_EQ(s.instances.size(), 43u);
    std::set<const TriangleMesh*> unique;
    for (const InstanceDesc& in : s.instances) unique.insert(s.meshes[in.mesh].mesh.get());
    EXPECT_EQ(unique.size(), 4u);
    // The first placement is the file's own transform; the second has its transform on top.
    const Transform second = Transform::translate(1000, 0, 0) * Transform::rotateDegrees(0, 0, 1, 90);
    for (size_t i = 0; i < 21; ++i) {
        Transform t;
        t.m = a.instances[i].transform;
        for (int k = 0; k < 12; ++k) {
            EXPECT_NEAR(s.instances[i].transform.m[k], t.m[k], 1e-9) << i << "," << k;
            EXPECT_NEAR(s.instances[21 + i].transform.m[k], (second * t).m[k], 1e-9) << i << "," << k;
        }
        EXPECT_EQ(s.meshes[s.instances[i].mesh].mesh->triangleCount(), a.meshes[a.instances[i].mesh]->triangleCount());
        EXPECT_EQ(s.meshes[s.instances[i].mesh].mesh, s.meshes[s.instances[21 + i].mesh].mesh);
        EXPECT_EQ(s.instances[i].part, s.instances[21 + i].part);
    }
    // Part names kept: the path of every instance is the file's, and the materials are the file's colours.
    ASSERT_EQ(s.parts.size(), a.parts.size());
    for (size_t i = 0; i < 21; ++i) {
        const std::string path = s.partPath(s.instances[i].part);
        EXPECT_FALSE(path.empty());
        EXPECT_EQ(s.materials[s.instances[i].material].color.x, a.materials[a.instances[i].material].baseColor[0]);
    }
    EXPECT_EQ(s.instances[42].part, -1);
    EXPECT_EQ(instancesMatching(s, "bolt*").size(), 2u * 12u);  // four bolts per module, 3 modules, 2 placements
}

// glTF too: its node tree as instances, its textures carried as the scene's files (so that
// render clients get them from the master), its materials mapped as a whole file's are.
TEST(AssemblyScene, GltfAssemblyWithTexturesInASceneFile) {
    const auto dir = test::scratchDir();
    const std::string cmd = "python3 " + (test::sourceDir() / "tools" / "gltf_testgen.py").string() + " --out " + dir.string();
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const SceneDesc s = loadSceneFile(test::writeFile(dir / "s.toml", R"(
[[mesh]]
name = "g"
file = "external.gltf"
[[instance]]
mesh = "g"
scale = 2
)"));
    const SceneDesc alone = sceneFromMeshFile(dir / "external.gltf");
    ASSERT_EQ(s.instances.size(), alone.instances.size());
    EXPECT_EQ(s.meshes.size(), alone.meshes.size());
    EXPECT_EQ(s.parts.size(), alone.parts.size());
    EXPECT_EQ(s.files.size(), alone.files.size());
    EXPECT_FALSE(s.files.empty()) << "the base-colour texture travels with the scene";
    for (size_t i = 0; i < s.instances.size(); ++i) {
        EXPECT_EQ(s.materials[s.instances[i].material], alone.materials[alone.instances[i].material]);
        EXPECT_EQ(s.partPath(s.instances[i].part), alone.partPath(alone.instances[i].part));
        EXPECT_NEAR(s.instances[i].transform.m[0], 2 * alone.instances[i].transform.m[0], 1e-9);
    }
    const std::string e = test::inputErrorOf([&] {
        loadSceneFile(test::writeFile(dir / "b.toml", "[[mesh]]\nname = \"g\"\nfile = \"external.gltf\"\nangular_deflection = 0.2\n"));
    });
    EXPECT_NE(e.find("b.toml:4"), std::string::npos) << e;
}

TEST(AssemblyScene, TessellationIsASceneSetting) {
    const auto dir = test::scratchDir();
    auto triangles = [](const SceneDesc& s) {
        size_t n = 0;
        for (const MeshDesc& m : s.meshes) n += m.mesh->triangleCount();
        return n;
    };
    const SceneDesc coarse = loadSceneFile(test::writeFile(dir / "c.toml", "[import]\nlinear_deflection = 1.0\nangular_deflection = 1.0\n" +
                                                                              sceneWith("[[instance]]\nmesh = \"plant\"\n")));
    const SceneDesc fine = loadSceneFile(test::writeFile(dir / "f.toml", "[import]\nlinear_deflection = 0.01\nangular_deflection = 0.1\n" +
                                                                            sceneWith("[[instance]]\nmesh = \"plant\"\n")));
    EXPECT_GT(triangles(fine), 2 * triangles(coarse));
    // A [[mesh]] of its own overrides [import]; the same file at the same tolerance is read once.
    const SceneDesc both = loadSceneFile(test::writeFile(dir / "b.toml", "[import]\nlinear_deflection = 1.0\nangular_deflection = 1.0\n" +
                                                                            sceneWith(R"(
[[mesh]]
name = "fine"
file = ")" + stepFile().string() + R"("
linear_deflection = 0.01
angular_deflection = 0.1
[[mesh]]
name = "again"
file = ")" + stepFile().string() + R"("
linear_deflection = 1.0
angular_deflection = 1.0
[[instance]]
mesh = "fine"
)")));
    EXPECT_EQ(both.meshes.size(), 6u) << "coarse once (plant, again) and fine once";
    EXPECT_EQ(triangles(both), triangles(coarse) + triangles(fine));
}

TEST(AssemblyScene, BadFilesAndKeysAreOneLineErrors) {
    const auto dir = test::scratchDir();
    test::writeFile(dir / "broken.step", "ISO-10303-21;\nHEADER;\nthis is not STEP\n");
    std::string e = test::inputErrorOf([&] {
        loadSceneFile(test::writeFile(dir / "a.toml", "[[mesh]]\nname = \"x\"\nfile = \"broken.step\"\n"));
    });
    EXPECT_NE(e.find("a.toml:3"), std::string::npos) << e;
    EXPECT_NE(e.find("broken.step"), std::string::npos) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;

    e = test::inputErrorOf([&] { loadSceneFile(test::writeFile(dir / "b.toml", "[import]\nlinear_deflection = 0\n")); });
    EXPECT_NE(e.find("b.toml:2: [import]: key 'linear_deflection'"), std::string::npos) << e;
    e = test::inputErrorOf([&] { loadSceneFile(test::writeFile(dir / "c.toml", "[import]\nlinear = 0.1\n")); });
    EXPECT_NE(e.find("unknown key 'linear'"), std::string::npos) << e;
    e = test::inputErrorOf([&] {
        loadSceneFile(test::writeFile(dir / "d.toml", "[[mesh]]\nname = \"s\"\nshape = \"box\"\nlinear_deflection = 0.1\n"));
    });
    EXPECT_NE(e.find("d.toml:4"), std::string::npos) << e;
    EXPECT_NE(e.find("only STEP and IGES files are tessellated"), std::string::npos) << e;
    e = test::inputErrorOf([&] {
        loadSceneFile(test::writeFile(dir / "e.toml", sceneWith("[[material]]\nname = \"m\"\n[[instance]]\nmesh = \"plant\"\nmaterial = \"m\"\n")));
    });
    EXPECT_NE(e.find("an assembly file keeps its own materials"), std::string::npos) << e;
    e = test::inputErrorOf([&] {
        loadSceneFile(test::writeFile(dir / "f.toml", sceneWith("[[instance]]\nmesh = \"plant\"\n[parts]\nhide = [\"nut*\"]\n")));
    });
    EXPECT_NE(e.find("[parts]: key 'hide': 'nut*': no part or mesh matches it"), std::string::npos) << e;
    e = test::inputErrorOf([&] {
        loadSceneFile(test::writeFile(dir / "g.toml", sceneWith("[[mesh]]\nname = \"plant\"\nshape = \"box\"\n")));
    });
    EXPECT_NE(e.find("mesh name 'plant' is used twice"), std::string::npos) << e;
}

TEST(AssemblyScene, PartsTableHidesIsolatesAndHighlights) {
    const auto dir = test::scratchDir();
    const SceneDesc s = loadSceneFile(test::writeFile(dir / "s.toml", sceneWith(kFloorAndPlant + R"(
[[instance]]
mesh = "floor"
[parts]
hide = ["bracket*"]
highlight = ["bolt 1"]
)")));
    size_t hidden = 0, highlighted = 0;
    for (const InstanceDesc& in : s.instances) {
        hidden += in.visibility == Visibility::Hidden;
        highlighted += in.visibility == Visibility::Highlighted;
    }
    EXPECT_EQ(hidden, 6u);       // two brackets per module
    EXPECT_EQ(highlighted, 3u);  // the first bolt of each module
}

// The shipped demo: configs/demos/step_assembly.toml names ../../out/step-assembly/assembly.step,
// which `tools/bootstrap.sh demo step-assembly` generates; here a copy of it beside a generated
// assembly renders a small frame that shows the parts (their colours) and the highlighted bolts.
TEST(AssemblyScene, ShippedDemoSceneLoadsAndRenders) {
    const auto dir = test::scratchDir();
    fs::create_directories(dir / "configs" / "demos");
    fs::copy_file(test::sourceDir() / "configs" / "demos" / "step_assembly.toml", dir / "configs" / "demos" / "step_assembly.toml");
    gen::genStep({.out = dir / "out" / "step-assembly", .instances = 700});  // what bootstrap.sh asks for
    SceneDesc s = loadSceneFile(dir / "configs" / "demos" / "step_assembly.toml");
    EXPECT_EQ(s.instances.size(), 701u);
    EXPECT_EQ(s.meshes.size(), 4u);
    size_t highlighted = 0;
    for (const InstanceDesc& in : s.instances) highlighted += in.visibility == Visibility::Highlighted;
    EXPECT_EQ(highlighted, 4u);
    ASSERT_NE(s.findCamera("overview"), nullptr);
    s.settings.width = 160;
    s.settings.height = 120;
    s.settings.supersample = 1;
    const Scene scene(s);
    const Image img = renderFrame(scene, Camera(s.cameras.front(), s.settings.width, s.settings.height), s.settings, 1);
    // The blue brackets and the yellow bolts show among the grey plates and the floor.
    size_t blue = 0, yellow = 0;
    for (size_t i = 0; i + 2 < img.rgb.size(); i += 3) {
        const int r = img.rgb[i], g = img.rgb[i + 1], b = img.rgb[i + 2];
        blue += b > r + 40 && b > g + 20;
        yellow += r > b + 60 && g > b + 40;
    }
    EXPECT_GT(blue, 50u);
    EXPECT_GT(yellow, 5u);
}

}  // namespace
}  // namespace rtwall
