// A scene file edited while the wall runs (`rtwall run --watch`): diffScenes turns the edit into
// differential updates and refuses, one line each, what updates cannot express; through the real
// command, the frames after the edit are one machine's render of the edited file, and a file
// that does not parse leaves the running scene as it was.
#include "shading_scenes.h"
#include "test_util.h"
#include "../cli_util.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

namespace rtwall {
namespace {

bool mentions(const std::vector<std::string>& lines, const std::string& what) {
    for (const std::string& l : lines)
        if (l.find(what) != std::string::npos) return true;
    return false;
}

TEST(SceneDiff, AnUnchangedSceneIsNoEdit) {
    const SceneDesc d = test::materialZoo(test::scratchDir(), 32, 24);
    EXPECT_TRUE(diffScenes(d, d).empty());
    SceneDesc copy = d;  // equal values, other objects
    EXPECT_TRUE(diffScenes(d, copy).empty());
}

TEST(SceneDiff, ChangesBecomeUpdatesOfExactlyWhatChanged) {
    const SceneDesc d = test::materialZoo(test::scratchDir(), 32, 24);
    ASSERT_GE(d.materials.size(), 3u);
    ASSERT_GE(d.instances.size(), 2u);
    ASSERT_GE(d.lights.size(), 1u);
    SceneDesc e = d;
    e.materials[2].color.x += 0.125f;
    e.lights[0].intensity *= 2.0f;
    e.instances[1].transform = Transform::translate(0.5, 0, 0) * e.instances[1].transform;
    e.settings.supersample = 3;
    e.cameras.front().position.y += 1.0f;
    const SceneEdit edit = diffScenes(d, e);
    EXPECT_TRUE(edit.refused.empty());
    ASSERT_EQ(edit.materials.size(), 1u);
    EXPECT_EQ(edit.materials[0].first, 2u);
    EXPECT_EQ(edit.materials[0].second.color.x, e.materials[2].color.x);
    ASSERT_EQ(edit.lights.size(), 1u);
    EXPECT_EQ(edit.lights[0].first, 0u);
    ASSERT_EQ(edit.transforms.size(), 1u);
    EXPECT_EQ(edit.transforms[0].first, 1u);
    EXPECT_EQ(edit.transforms[0].second.m, e.instances[1].transform.m);
    ASSERT_TRUE(edit.settings);
    EXPECT_EQ(edit.settings->supersample, 3);
    ASSERT_TRUE(edit.camera);
    EXPECT_EQ(edit.camera->position.y, e.cameras.front().position.y);
}

// Which side emits is part of a material and of an area light (protocol version 6): an edit that
// only turns two-sided emission on is a material or light update.
TEST(SceneDiff, TwoSidedEmissionIsAnEdit) {
    const SceneDesc d = test::materialZoo(test::scratchDir(), 32, 24);
    SceneDesc e = d;
    e.materials[8].twoSided = true;  // the zoo's emissive lamp
    e.lights[1].twoSided = true;     // its area light
    const SceneEdit edit = diffScenes(d, e);
    EXPECT_TRUE(edit.refused.empty());
    ASSERT_EQ(edit.materials.size(), 1u);
    EXPECT_EQ(edit.materials[0].first, 8u);
    EXPECT_TRUE(edit.materials[0].second.twoSided);
    ASSERT_EQ(edit.lights.size(), 1u);
    EXPECT_EQ(edit.lights[0].first, 1u);
    EXPECT_TRUE(edit.lights[0].second.twoSided);
}

// [[section]] tables (issue 20): a plane added, moved or turned off in the file is an update of
// its slot, and only of the slots that changed.
TEST(SceneDiff, SectionPlanesAreUpdatesOfTheirSlots) {
    SceneDesc d = test::materialZoo(test::scratchDir(), 32, 24);
    d.sections[0].enabled = true;
    d.sections[0].normal = {0, 0, -1};
    d.sections[2].enabled = true;
    SceneDesc e = d;
    e.sections[0].point.z = 0.5f;          // moved
    e.sections[2].enabled = false;         // turned off
    e.sections[5].enabled = true;          // added
    e.sections[5].capColor = {0, 0, 1};
    const SceneEdit edit = diffScenes(d, e);
    EXPECT_TRUE(edit.refused.empty());
    EXPECT_FALSE(edit.empty());
    ASSERT_EQ(edit.sections.size(), 3u);
    EXPECT_EQ(edit.sections[0].first, 0u);
    EXPECT_EQ(edit.sections[0].second, e.sections[0]);
    EXPECT_EQ(edit.sections[1].first, 2u);
    EXPECT_FALSE(edit.sections[1].second.enabled);
    EXPECT_EQ(edit.sections[2].first, 5u);
    EXPECT_EQ(edit.sections[2].second, e.sections[5]);
    EXPECT_TRUE(diffScenes(e, e).empty());
}

TEST(SceneDiff, WhatUpdatesCannotExpressIsRefusedInOneLineEach) {
    const SceneDesc d = test::materialZoo(test::scratchDir(), 32, 24);
    auto refused = [&](auto change) {
        SceneDesc e = d;
        change(e);
        return diffScenes(d, e).refused;
    };
    EXPECT_TRUE(mentions(refused([](SceneDesc& e) { e.materials.push_back(e.materials.front()); }), "materials became"));
    EXPECT_TRUE(mentions(refused([](SceneDesc& e) { e.lights.clear(); }), "lights became"));
    EXPECT_TRUE(mentions(refused([](SceneDesc& e) { e.instances.pop_back(); }), "instances became"));
    EXPECT_TRUE(mentions(refused([](SceneDesc& e) { e.instances[0].material = 1 - e.instances[0].material % 2; }),
                         "instance 0 has another mesh or material"));
    EXPECT_TRUE(mentions(refused([](SceneDesc& e) { e.bvh.compact = !e.bvh.compact; }), "[bvh]"));
    EXPECT_TRUE(mentions(refused([](SceneDesc& e) { e.bvh.primitives = BvhSettings::Primitives::Triangles; }), "[bvh]"));
    EXPECT_TRUE(mentions(refused([](SceneDesc& e) { e.origin[0] += 1e6; }), "origin"));
    // A mesh whose file now holds other geometry (one vertex moved).
    const std::vector<std::string> meshLines = refused([](SceneDesc& e) {
        auto moved = std::make_shared<TriangleMesh>(*e.meshes[0].mesh);
        const float* p = moved->positions();
        moved->setPosition(0, {p[0] + 0.25f, p[1], p[2]});
        e.meshes[0].mesh = moved;
    });
    ASSERT_EQ(meshLines.size(), 1u);
    EXPECT_NE(meshLines[0].find("mesh '" + d.meshes[0].name + "'"), std::string::npos) << meshLines[0];
}

std::vector<uint8_t> fileBytes(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string sceneText(const std::string& colour, const std::string& extra = "") {
    return "[image]\nwidth = 48\nheight = 32\n"
           "[[mesh]]\nname = \"box\"\nfile = \"" + (test::dataDir() / "meshes/box_quads.obj").string() + "\"\n"
           "[[mesh]]\nname = \"floor\"\nshape = \"quad\"\n"
           "[[material]]\nname = \"paint\"\ntype = \"lambert\"\ncolor = " + colour + "\n"
           "[[material]]\nname = \"ground\"\ntype = \"lambert\"\ncolor = [0.6, 0.6, 0.6]\n"
           "[[instance]]\nmesh = \"box\"\nmaterial = \"paint\"\n"
           "[[instance]]\nmesh = \"floor\"\nmaterial = \"ground\"\nscale = [8, 1, 8]\ntranslate = [0, -1, 0]\n"
           "[[light]]\ntype = \"point\"\nposition = [3, 6, 4]\nintensity = 40\n"
           "[[camera]]\nname = \"main\"\nposition = [3, 2.5, 4]\nlook_at = [0, 0, 0]\n" + extra;
}

// Issue 20: the edit also adds a section plane that cuts the box open towards the camera (a cap).
const char* kSection = "[[section]]\npoint = [0, 0, 0.3]\nnormal = [-1, 0, -1]\ncap_color = [0.9, 0.9, 0.1]\n";

TEST(RunWatch, AnEditedSceneFileReachesTheWallAsUpdates) {
    const auto dir = test::scratchDir();
    test::writeFile(dir / "scene.toml", sceneText("[0.8, 0.2, 0.1]"));
    test::writeFile(dir / "edited.toml", sceneText("[0.1, 0.3, 0.9]", kSection));
    test::writeFile(dir / "broken.toml", sceneText("[0.1, 0.3") );
    test::writeFile(dir / "run.toml", "scene = \"scene.toml\"\n[cluster]\nclients = 1\n"
                                      "[run]\nframes = 100000\nwrite_every = 1\nout = \"" + (dir / "frames").string() +
                                      "\"\norbit = 0\n");
    const std::string exe = RTWALL_EXE;
    const std::string d = dir.string();
    // Bounded waits (at most 60 s each); the run is stopped with Ctrl-C (SIGINT) at the end.
    test::writeFile(dir / "watch.sh", R"(D=$1; RTWALL=$2
wait_for() { for i in $(seq 1 600); do if eval "$1"; then return 0; fi; sleep 0.1; done; return 1; }
frames() { ls "$D/frames" 2>/dev/null | wc -l; }
"$RTWALL" run "$D/run.toml" --headless --watch > "$D/log" 2>&1 &
pid=$!
trap 'kill -KILL $pid 2>/dev/null' EXIT
wait_for '[ -e "$D/frames/frame_000002.png" ]' || echo "NO FRAMES"
cp "$D/frames/frame_000002.png" "$D/before.png"
cp "$D/broken.toml" "$D/tmp.toml" && mv "$D/tmp.toml" "$D/scene.toml"
wait_for 'grep -q "the running scene stays" "$D/log"' || echo "NO REFUSAL"
cp "$D/edited.toml" "$D/tmp.toml" && mv "$D/tmp.toml" "$D/scene.toml"
wait_for 'grep -q "changed: 1 materials" "$D/log"' || echo "NO CHANGE"
n=$(frames)
wait_for '[ $(frames) -ge $((n + 3)) ]' || echo "NO MORE FRAMES"
kill -INT $pid
wait_for '! kill -0 $pid 2>/dev/null' || echo "NO EXIT AFTER CTRL-C"
wait $pid
echo "exit $?"
cat "$D/log"
ls "$D/frames" | sort | tail -1 > "$D/last"
)");
    const test::CliResult r = test::runCli("bash", (dir / "watch.sh").string() + " " + d + " " + exe, 240);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(r.output.find("NO "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("exit 0"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("changed: 1 materials, 0 lights, 0 instance transforms, render settings same, camera same, 1 "
                            "section planes"),
              std::string::npos)
        << r.output;

    const std::vector<uint8_t> lastBytes = fileBytes(dir / "last");
    std::string last(lastBytes.begin(), lastBytes.end());
    while (!last.empty() && last.back() == '\n') last.pop_back();
    ASSERT_FALSE(last.empty());
    // One machine's renders of the file before and after the edit.
    ASSERT_EQ(test::runCli(exe, "render " + (dir / "edited.toml").string() + " --out " + (dir / "edited.png").string()).status, 0);
    test::writeFile(dir / "original.toml", sceneText("[0.8, 0.2, 0.1]"));
    ASSERT_EQ(test::runCli(exe, "render " + (dir / "original.toml").string() + " --out " + (dir / "original.png").string()).status, 0);
    EXPECT_EQ(fileBytes(dir / "before.png"), fileBytes(dir / "original.png"));
    EXPECT_EQ(fileBytes(dir / "frames" / last), fileBytes(dir / "edited.png")) << last;
    EXPECT_NE(fileBytes(dir / "original.png"), fileBytes(dir / "edited.png"));
    test::writeFile(dir / "uncut.toml", sceneText("[0.1, 0.3, 0.9]"));
    ASSERT_EQ(test::runCli(exe, "render " + (dir / "uncut.toml").string() + " --out " + (dir / "uncut.png").string()).status, 0);
    EXPECT_NE(fileBytes(dir / "uncut.png"), fileBytes(dir / "edited.png")) << "the plane cuts something";
}

}  // namespace
}  // namespace rtwall
