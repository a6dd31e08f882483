// Scenes by name (issue 17): one loader for builtin:NAME, scene files and mesh files, whatever
// the case of the extension (KNOT.PLY, SCENE.TOML, MODEL.OBJ), as every command uses it.
#include "test_util.h"

#include <gtest/gtest.h>

namespace rtwall {
namespace {

using test::scratchDir;
using test::writeFile;

int64_t trianglesOf(const SceneDesc& d) {
    int64_t n = 0;
    for (const InstanceDesc& in : d.instances) n += int64_t(d.meshes[in.mesh].mesh->triangleCount());
    return n;
}

int64_t uniqueTrianglesOf(const SceneDesc& d) {
    int64_t n = 0;
    for (const MeshDesc& m : d.meshes) n += int64_t(m.mesh->triangleCount());
    return n;
}

Image render(const SceneDesc& d, int w = 32, int h = 24) {
    RenderSettings s = d.settings;
    s.width = w;
    s.height = h;
    return renderFrame(Scene(d), Camera(d.cameras.front(), w, h), s);
}

TEST(SceneSource, KindFollowsTheNameInAnyCase) {
    EXPECT_EQ(sceneSourceKind("builtin:knots"), SceneSourceKind::Builtin);
    for (const char* name : {"a.toml", "A.TOML", "dir/Scene.Toml", "/abs/x.tOmL"})
        EXPECT_EQ(sceneSourceKind(name), SceneSourceKind::SceneFile) << name;
    for (const char* name : {"KNOT.PLY", "model.OBJ", "toml", "scene.toml/mesh.ply", "a.toml.ply", "x.tom", "BUILTIN:knots"})
        EXPECT_EQ(sceneSourceKind(name), SceneSourceKind::MeshFile) << name;
}

TEST(SceneSource, UpperCaseExtensionsLoadAsTheirLowerCaseTwins) {
    const auto dir = scratchDir();
    const auto meshes = test::sourceDir() / "configs/meshes";
    std::filesystem::copy_file(meshes / "knot.ply", dir / "knot.ply");
    std::filesystem::copy_file(meshes / "knot.ply", dir / "KNOT.PLY");
    std::filesystem::copy_file(test::dataDir() / "meshes/box_normals.obj", dir / "model.obj");
    std::filesystem::copy_file(test::dataDir() / "meshes/box_normals.obj", dir / "MODEL.OBJ");
    const std::string scene = R"([image]
width = 32
height = 24

[[mesh]]
name = "knot"
file = "KNOT.PLY"

[[instance]]
mesh = "knot"

[[camera]]
position = [0, 1, 4]
look_at = [0, 0, 0]
)";
    writeFile(dir / "scene.toml", scene);
    writeFile(dir / "SCENE.TOML", scene);

    const SceneDesc upperScene = loadScene((dir / "SCENE.TOML").string());
    EXPECT_EQ(upperScene.sourceFile, dir / "SCENE.TOML");
    EXPECT_EQ(trianglesOf(upperScene), 17280);
    EXPECT_EQ(render(upperScene).rgb, render(loadScene((dir / "scene.toml").string())).rgb);

    const SceneDesc knot = loadScene((dir / "KNOT.PLY").string());
    EXPECT_EQ(trianglesOf(knot), 17280);
    EXPECT_EQ(render(knot).rgb, render(loadScene((dir / "knot.ply").string())).rgb);

    const SceneDesc model = loadScene((dir / "MODEL.OBJ").string());
    EXPECT_EQ(trianglesOf(model), 12);
    EXPECT_EQ(render(model).rgb, render(loadScene((dir / "model.obj").string())).rgb);
}

TEST(SceneSource, BuiltinScenesTakeTheirTriangleCount) {
    SceneLoadOptions options;
    options.builtinTriangles = 200'000;
    const int64_t large = uniqueTrianglesOf(loadScene("builtin:knots", options));
    EXPECT_GT(large, 160'000);
    EXPECT_LT(large, 240'000);
    options.builtinTriangles = 5000;
    EXPECT_LT(uniqueTrianglesOf(loadScene("builtin:knots", options)), large / 10);
    EXPECT_NE(test::inputErrorOf([] { loadScene("builtin:teapot"); }).find("builtin scene 'teapot' does not exist"),
              std::string::npos);
}

TEST(SceneSource, AMissingFileIsAnInputErrorNamingIt) {
    EXPECT_NE(test::inputErrorOf([] { loadScene("/no/such/SCENE.TOML"); }).find("/no/such/SCENE.TOML"), std::string::npos);
    EXPECT_NE(test::inputErrorOf([] { loadScene("/no/such/KNOT.PLY"); }).find("/no/such/KNOT.PLY"), std::string::npos);
}

}  // namespace
}  // namespace rtwall
