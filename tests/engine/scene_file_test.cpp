// Scene files: what loads, and how every kind of mistake is reported (file, line, key).
#include "scene_file_keys.h"
#include "test_util.h"

#include <gtest/gtest.h>

namespace rtwall {
namespace {

using test::inputErrorOf;
using test::scratchDir;
using test::writeFile;

// Mitsuba's rule, every key read: the loader reads only keys of its tables, and every key of the
// tables is documented, with the tables' help, in configs/README.md.
TEST(SceneFile, EveryKeyOfTheTablesIsDocumented) {
    const std::vector<std::string> missing =
        toml_reader::undocumentedKeys(scene_keys::kAll, test::sourceDir() / "configs/README.md");
    EXPECT_TRUE(missing.empty()) << ::testing::PrintToString(missing);
}

const std::string kMinimal = test::sceneText("minimal");

TEST(SceneFile, LoadsEveryTable) {
    const auto file = writeFile(scratchDir() / "s.toml", kMinimal);
    const SceneDesc s = loadSceneFile(file);
    EXPECT_EQ(s.settings.width, 64);
    EXPECT_EQ(s.settings.height, 48);
    ASSERT_EQ(s.meshes.size(), 1u);
    ASSERT_EQ(s.instances.size(), 1u);
    EXPECT_EQ(s.materials.at(s.instances[0].material).type, MaterialType::Phong);
    EXPECT_DOUBLE_EQ(s.instances[0].transform.m[3], 1.0);
    EXPECT_DOUBLE_EQ(s.instances[0].transform.m[7], 2.0);
    EXPECT_DOUBLE_EQ(s.instances[0].transform.m[11], 3.0);
    ASSERT_NE(s.findCamera("front"), nullptr);
    EXPECT_EQ(s.lights.size(), 1u);
}

TEST(SceneFile, EveryShippedConfigLoads) {
    // Like Equalizer's loader test: every example under configs/ must load.
    int count = 0;
    for (const auto& e : std::filesystem::directory_iterator(test::sourceDir() / "configs")) {
        if (e.path().extension() != ".toml") continue;
        SCOPED_TRACE(e.path().string());
        EXPECT_NO_THROW(loadSceneFile(e.path()));
        ++count;
    }
    EXPECT_GT(count, 0);
}

// [[section]]: slot i is the i-th table; points are rebased with everything else, in double.
TEST(SceneFile, LoadsSectionPlanesInTheRebasedCoordinates) {
    const auto file = writeFile(scratchDir() / "s.toml", R"(
[[mesh]]
name = "ball"
shape = "sphere"
[[instance]]
mesh = "ball"
translate = [1000000.5, 0, -200000.25]
[[section]]
point = [1000000.75, 2, -200000.25]
normal = [0, 0, 2]
cap_color = [0.2, 0.4, 0.6]
[[section]]
point = [0, 0, 0]
normal = [1, 0, 0]
enabled = false
caps = false
)");
    const SceneDesc s = loadSceneFile(file);
    ASSERT_NE(s.origin[0], 0.0) << "the scene is far from the origin: rebased";
    const SectionPlane& a = s.sections[0];
    EXPECT_TRUE(a.enabled);
    EXPECT_TRUE(a.caps);
    EXPECT_FLOAT_EQ(float(s.origin[0] + double(a.point.x)), 1000000.75f);
    EXPECT_DOUBLE_EQ(double(a.point.x), 1000000.75 - s.origin[0]) << "subtracted in double, exact";
    EXPECT_DOUBLE_EQ(double(a.point.z), -200000.25 - s.origin[2]);
    EXPECT_EQ(a.normal, (Float3{0, 0, 2}));
    EXPECT_EQ(a.capColor, (Color{0.2f, 0.4f, 0.6f}));
    EXPECT_FALSE(s.sections[1].enabled);
    EXPECT_FALSE(s.sections[1].caps);
    for (int i = 2; i < kMaxSections; ++i) EXPECT_EQ(s.sections[i], SectionPlane{});
}

TEST(SceneFile, SameMeshFileIsLoadedOnce) {
    const auto dir = scratchDir();
    std::filesystem::copy_file(test::sourceDir() / "configs/meshes/knot.ply", dir / "knot.ply");
    const auto file = writeFile(dir / "s.toml", R"(
[[mesh]]
name = "a"
file = "knot.ply"
[[mesh]]
name = "b"
file = "./knot.ply"
)");
    const SceneDesc s = loadSceneFile(file);
    ASSERT_EQ(s.meshes.size(), 2u);
    EXPECT_EQ(s.meshes[0].mesh.get(), s.meshes[1].mesh.get()) << "one file must be one copy in memory";
}

struct BadScene {
    const char* name;
    const char* text;
    const char* place;  // expected "file:line" suffix
    const char* what;   // expected substring
};

class SceneFileErrors : public ::testing::TestWithParam<BadScene> {};

TEST_P(SceneFileErrors, NameFileLineAndProblem) {
    const BadScene& b = GetParam();
    const auto file = writeFile(scratchDir() / "bad.toml", b.text);
    const std::string msg = inputErrorOf([&] { loadSceneFile(file); });
    EXPECT_NE(msg.find(file.string() + ":" + b.place), std::string::npos) << msg;
    EXPECT_NE(msg.find(b.what), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "must be one line: " << msg;
}

INSTANTIATE_TEST_SUITE_P(
    All, SceneFileErrors,
    ::testing::Values(
        BadScene{"Malformed", "[image]\nwidth = = 3\n", "2", ""},
        BadScene{"UnknownTopLevelKey", "[image]\nwidth = 3\n\n[rendr]\nx = 1\n", "4", "unknown key 'rendr'"},
        BadScene{"UnknownKeyInTable", "[image]\nwidth = 3\nhieght = 4\n", "3", "unknown key 'hieght'"},
        BadScene{"WrongType", "[image]\nwidth = \"wide\"\n", "2", "key 'width': expected an integer, got a string"},
        BadScene{"OutOfRange", "[image]\nwidth = -5\n", "2", "out of range"},
        BadScene{"NotFinite", "[[light]]\ntype = \"point\"\nposition = [0, nan, 0]\n", "3", "must be finite"},
        BadScene{"NanNumber", "[[camera]]\nposition = [0,0,1]\nlook_at = [0,0,0]\nfov = nan\n", "4", "finite"},
        BadScene{"WrongArrayLength", "[[camera]]\nposition = [0, 0]\nlook_at = [0,0,0]\n", "2", "array of 3 numbers"},
        BadScene{"UnknownMaterialType", "[[material]]\nname = \"m\"\ntype = \"velvet\"\n", "3",
                 "'velvet' is not one of lambert, phong, mirror, glass"},
        BadScene{"UnknownMeshReference", "[[instance]]\nmesh = \"ghost\"\n", "2", "no [[mesh]] is named 'ghost'"},
        BadScene{"UnknownMaterialReference",
                 "[[mesh]]\nname = \"b\"\nshape = \"box\"\n\n[[instance]]\nmesh = \"b\"\nmaterial = \"gold\"\n", "7",
                 "no [[material]] is named 'gold'"},
        BadScene{"MissingRequiredKey", "[[mesh]]\nshape = \"box\"\n", "1", "missing required key 'name'"},
        BadScene{"MissingMeshFile", "[[mesh]]\nname = \"m\"\nfile = \"nowhere.obj\"\n", "3", "nowhere.obj"},
        BadScene{"FileAndShape", "[[mesh]]\nname = \"m\"\nfile = \"a.obj\"\nshape = \"box\"\n", "1",
                 "exactly one of 'file' and 'shape'"},
        BadScene{"DuplicateName", "[[mesh]]\nname = \"m\"\nshape = \"box\"\n[[mesh]]\nname = \"m\"\nshape = \"box\"\n",
                 "5", "used twice"},
        BadScene{"TableWhereArrayExpected", "[mesh]\nname = \"m\"\n", "1", "[[mesh]]"},
        // Section planes (issue 20).
        BadScene{"SectionUnknownKey", "[[section]]\npoint = [0,0,0]\nnormal = [1,0,0]\ncap_colour = [1,0,0]\n", "4",
                 "unknown key 'cap_colour'"},
        BadScene{"SectionWithoutNormal", "[[section]]\npoint = [0,0,0]\n", "1", "missing required key 'normal'"},
        BadScene{"SectionZeroNormal", "[[section]]\npoint = [0,0,0]\nnormal = [0,0,0]\n", "3",
                 "key 'normal' must not be zero"},
        BadScene{"SectionCapColorAboveOne", "[[section]]\npoint = [0,0,0]\nnormal = [0,1,0]\ncap_color = [0,3,0]\n", "4",
                 "key 'cap_color': components must lie in [0, 1]"},
        BadScene{"SectionEnabledNotABoolean", "[[section]]\npoint = [0,0,0]\nnormal = [0,1,0]\nenabled = 1\n", "4",
                 "key 'enabled': expected true or false"},
        BadScene{"SevenSections",
                 "[[section]]\npoint = [0,0,0]\nnormal = [1,0,0]\n[[section]]\npoint = [0,0,0]\nnormal = [1,0,0]\n"
                 "[[section]]\npoint = [0,0,0]\nnormal = [1,0,0]\n[[section]]\npoint = [0,0,0]\nnormal = [1,0,0]\n"
                 "[[section]]\npoint = [0,0,0]\nnormal = [1,0,0]\n[[section]]\npoint = [0,0,0]\nnormal = [1,0,0]\n"
                 "[[section]]\npoint = [0,0,0]\nnormal = [1,0,0]\n",
                 "19", "more than 6 [[section]] planes"},
        BadScene{"ColorAboveOne", "[[material]]\nname = \"m\"\ncolor = [2, 0, 0]\n", "3", "[0, 1]"},
        BadScene{"DegenerateCamera", "[[camera]]\nposition = [0,0,0]\nlook_at = [0,0,0]\n", "3", "own position"},
        BadScene{"HugeShape", "[[mesh]]\nname = \"k\"\nshape = \"torus_knot\"\nsegments = 1000000\nsides = 4000\n", "4",
                 "below 2^26"},
        BadScene{"UvMappingOnAMeshWithoutUVs",
                 "[[mesh]]\nname = \"b\"\nshape = \"box\"\n[[material]]\nname = \"m\"\ntexture = \"checker\"\n"
                 "texture_mapping = \"uv\"\n[[instance]]\nmesh = \"b\"\nmaterial = \"m\"\n",
                 "8", "material 'm' has texture_mapping = \"uv\", but mesh 'b' (shape:box) has no texture coordinates"},
        BadScene{"UvBumpInAGroupOnAMeshWithoutUVs",
                 "[[mesh]]\nname = \"b\"\nshape = \"box\"\n[[material]]\nname = \"m\"\nbump = 0.5\nbump_mapping = \"uv\"\n"
                 "[[group]]\nname = \"g\"\n[[group.instance]]\nmesh = \"b\"\n[[instance]]\ngroup = \"g\"\nmaterial = \"m\"\n",
                 "12", "material 'm' has bump_mapping = \"uv\", but mesh 'b'"},
        BadScene{"UnknownMapping", "[[material]]\nname = \"m\"\nalpha = \"checker\"\nalpha_mapping = \"uvw\"\n", "4",
                 "'uvw' is not one of auto, uv, xz"},
        BadScene{"UnknownAlphaMode", "[[material]]\nname = \"m\"\nalpha_mode = \"blend\"\n", "3",
                 "'blend' is not one of mask, hashed"},
        BadScene{"OpacityAboveOne", "[[material]]\nname = \"m\"\nopacity = 1.5\n", "3", "opacity"},
        BadScene{"ZeroScale", "[[mesh]]\nname = \"b\"\nshape = \"box\"\n[[instance]]\nmesh = \"b\"\nscale = [1, 0, 1]\n",
                 "6", "must not be zero"}),
    [](const auto& param) { return std::string(param.param.name); });

// `movable` marks an instance, or every instance a group expands to, and nothing else.
TEST(SceneFile, MovableMarksTheInstancesItExpandsTo) {
    const auto dir = scratchDir();
    const auto file = writeFile(dir / "s.toml", R"(
[[mesh]]
name = "b"
shape = "box"
[[group]]
name = "valve"
[[group.instance]]
mesh = "b"
[[group.instance]]
mesh = "b"
translate = [0, 1, 0]
[[instance]]
mesh = "b"
[[instance]]
group = "valve"
movable = true
[[instance]]
mesh = "b"
movable = true
translate = [3, 0, 0]
)");
    const SceneDesc s = loadSceneFile(file);
    ASSERT_EQ(s.instances.size(), 4u);
    EXPECT_FALSE(s.instances[0].movable);
    EXPECT_TRUE(s.instances[1].movable && s.instances[2].movable) << "both of the group's instances";
    EXPECT_TRUE(s.instances[3].movable);
    const auto bad = writeFile(dir / "bad.toml", "[[mesh]]\nname = \"b\"\nshape = \"box\"\n[[instance]]\nmesh = \"b\"\nmovable = \"yes\"\n");
    EXPECT_NE(test::inputErrorOf([&] { loadSceneFile(bad); }).find("movable"), std::string::npos);
}

// A mesh with texture coordinates takes "uv" (and "auto", the default); the keys are read.
TEST(SceneFile, UvMappingsOnAMeshWithUVs) {
    const auto dir = scratchDir();
    std::filesystem::copy_file(test::dataDir() / "meshes/uv_seam.obj", dir / "uv.obj", std::filesystem::copy_options::overwrite_existing);
    const auto file = writeFile(dir / "s.toml", R"(
[[mesh]]
name = "q"
file = "uv.obj"
[[material]]
name = "m"
texture = "checker"
texture_mapping = "uv"
alpha = "checker"
bump = 0.5
bump_mapping = "object"
[[material]]
name = "d"
texture = "checker"
bump = 0.5
[[instance]]
mesh = "q"
material = "m"
[[instance]]
mesh = "q"
material = "d"
)");
    const SceneDesc s = loadSceneFile(file);
    ASSERT_EQ(s.materials.size(), 2u);
    EXPECT_EQ(s.materials[0].texture.mapping, TextureMapping::Uv);
    EXPECT_EQ(s.materials[0].alpha.mapping, TextureMapping::Auto);
    EXPECT_EQ(s.materials[0].bumpMapping, TextureMapping::Object);
    EXPECT_EQ(s.materials[1].texture.mapping, TextureMapping::Auto);
    EXPECT_EQ(s.materials[1].bumpMapping, TextureMapping::Auto);
    EXPECT_TRUE(s.meshes[0].mesh->hasUVs());
}

TEST(SceneFile, MissingFileIsAnInputError) {
    const std::string msg = inputErrorOf([] { loadSceneFile("/nonexistent/scene.toml"); });
    EXPECT_NE(msg.find("/nonexistent/scene.toml: no such file"), std::string::npos) << msg;
}

TEST(SceneFile, BinaryGarbageIsAnInputError) {
    std::string junk;
    for (int i = 0; i < 4096; ++i) junk += char((i * 7919) & 0xFF);
    const auto file = writeFile(scratchDir() / "junk.toml", junk);
    const std::string msg = inputErrorOf([&] { loadSceneFile(file); });
    EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
}

TEST(SceneFile, MeshFileGetsAFramingCamera) {
    const SceneDesc s = sceneFromMeshFile(test::sourceDir() / "configs/meshes/knot.ply");
    ASSERT_EQ(s.cameras.size(), 1u);
    const Bounds3 b = s.worldBounds();
    // The camera looks at the centre of the bounds from outside them.
    const CameraDesc& c = s.cameras[0];
    EXPECT_NEAR(c.lookAt.x, 0.5f * (b.lo.x + b.hi.x), 1e-5f);
    EXPECT_NEAR(c.lookAt.y, 0.5f * (b.lo.y + b.hi.y), 1e-5f);
    EXPECT_FALSE(c.position.x >= b.lo.x && c.position.x <= b.hi.x && c.position.y >= b.lo.y &&
                 c.position.y <= b.hi.y && c.position.z >= b.lo.z && c.position.z <= b.hi.z);
    EXPECT_FALSE(s.lights.empty());
}

}  // namespace
}  // namespace rtwall
