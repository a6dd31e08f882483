// The command line for CAD scenes: rtwall info on every VTK format, rtwall gen, and one-line
// errors for bad files, bad scenes and bad arguments.
#include "test_util.h"
#include "cli_util.h"
#include "child_process.h"

#include <rtwall/image.h>

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <regex>
#include <thread>

namespace rtwall {
namespace {

using Result = test::CliResult;

Result run(const std::string& args) { return test::runCli(RTWALL_EXE, args, 300); }

void expectOneLineError(const Result& r, int status, const std::string& mustContain) {
    EXPECT_EQ(r.status, status) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(mustContain), std::string::npos) << r.output;
}

const std::filesystem::path kMeshes = std::filesystem::path(RTWALL_TEST_DATA_DIR) / "meshes";

TEST(CliCad, InfoOnEveryVtkFormat) {
    for (const char* f : {"box_ascii.vtk", "box_binary.vtk", "box_strips.vtk", "box_hex_ascii.vtk", "box_ascii.vtp",
                          "box_base64.vtp", "box_raw.vtp", "box_zlib.vtp", "box_lz4.vtp", "box_hex_zlib.vtu", "box_far.vtp"}) {
        const Result r = run("info --json " + (kMeshes / f).string());
        ASSERT_EQ(r.status, 0) << f << ": " << r.output;
        EXPECT_NE(r.output.find("\"triangles\" : 12"), std::string::npos) << f << ": " << r.output;
    }
    const Result far = run("info --json " + (kMeshes / "box_far.vtp").string());
    EXPECT_NE(far.output.find("148377"), std::string::npos) << far.output;  // the origin
}

// VRML through VTK, and its colours, as rtwall info reports them.
TEST(CliCad, InfoOnVrml) {
    const Result r = run("info --json " + (kMeshes / "box_color_transform.wrl").string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("\"format\" : \"wrl\""), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"triangles\" : 12"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"colors\" : true"), std::string::npos) << r.output;
    expectOneLineError(run("info " + (kMeshes / "bad_truncated.wrl").string()), 1, "bad_truncated.wrl:line 8: VRML: parse error");
}

// A camera path is in world coordinates, like the scene file: for a scene at (1e6, -2e5, 3e5)
// (rebased on load) a one-key path at the scene camera's world pose renders the very frame the
// scene camera does. Read as rebased coordinates it would look 1e6 units away, at nothing.
TEST(CliCad, CameraPathIsInWorldCoordinates) {
    const auto dir = test::scratchDir();
    test::writeFile(dir / "far.toml", test::sceneText("far_ball"));
    auto config = [&](const std::string& name) {
        return test::writeFile(dir / (name + ".toml"), "scene = \"far.toml\"\ncamera = \"main\"\n[cluster]\nclients = 1\nasync = false\n"
                                                       "[run]\nframes = 1\nwrite_every = 1\norbit = 0\nout = \"" + (dir / name).string() + "\"\n");
    };
    const auto path = test::writeFile(dir / "path.toml", "[[key]]\nframe = 0\nposition = [1000001.75, -199997.25, 300007.5]\n"
                                                          "look_at = [1000000.5, -200000.25, 300000.125]\nfov = 40\n");
    const Result still = run("run --headless " + config("still").string());
    ASSERT_EQ(still.status, 0) << still.output;
    const Result replay = run("run --headless " + config("replay").string() + " --camera-path " + path.string());
    ASSERT_EQ(replay.status, 0) << replay.output;
    const Image a = readPng(dir / "still" / "frame_000001.png"), b = readPng(dir / "replay" / "frame_000001.png");
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    EXPECT_EQ(a.rgb, b.rgb);
    size_t lit = 0;
    for (uint8_t v : a.rgb) lit += v > 40;
    EXPECT_GT(lit, a.rgb.size() / 20) << "the ball is in view";
}

TEST(CliCad, BadFilesGiveOneLine) {
    expectOneLineError(run("info " + (kMeshes / "bad_points_huge.vtk").string()), 1, "bad_points_huge.vtk:line 5");
    expectOneLineError(run("info " + (kMeshes / "bad_garbage.vtp").string()), 1, "bad_garbage.vtp");
    expectOneLineError(run("render " + (kMeshes / "bad_truncated_binary.vtk").string() + " --out x.png"), 1, "truncated");
}

TEST(CliCad, GenBadArguments) {
    expectOneLineError(run("gen nope --out x"), 2, "nope");
    expectOneLineError(run("gen powerplant"), 2, "--out");
    expectOneLineError(run("gen powerplant --out x --triangles 5"), 2, "--triangles");
    expectOneLineError(run("gen sunflowers --out /proc/no/such/dir"), 1, "gen:");
}

TEST(CliCad, GeneratedSceneLoadsRendersAndReportsInstances) {
    const auto dir = test::scratchDir() / "sun";
    std::filesystem::remove_all(dir);
    const Result g = run("gen sunflowers --out " + dir.string() + " --instances 70 --triangles 1000 --trees 1 --tree-triangles 2000");
    ASSERT_EQ(g.status, 0) << g.output;
    const Result info = run("info --json " + (dir / "scene.toml").string());
    ASSERT_EQ(info.status, 0) << info.output;
    EXPECT_NE(info.output.find("\"instances\" : 282"), std::string::npos) << info.output;  // 70 plants x 4 + ground + tree
    const Result r = run("render " + (dir / "scene.toml").string() + " --out " + (dir / "f.png").string() +
                         " --width 48 --height 32 --threads 2");
    EXPECT_EQ(r.status, 0) << r.output;
}

TEST(CliCad, BadGroupNamesFileAndLine) {
    const auto file = test::writeFile(test::scratchDir() / "g.toml",
                                      "[[mesh]]\nname = \"b\"\nshape = \"box\"\n[[instance]]\ngroup = \"missing\"\n");
    expectOneLineError(run("render " + file.string() + " --out x.png"), 1, file.string() + ":5:");
}

// glTF assemblies (issue 20): rtwall info lists the part tree, a render works, and a broken
// file is one line naming it and a non-zero exit, from info and from render.
TEST(CliCad, GltfInfoListsThePartTreeAndBadFilesGiveOneLine) {
    const auto dir = test::scratchDir();
    const std::string cmd = "python3 " + (test::sourceDir() / "tools" / "gltf_testgen.py").string() + " --malformed --out " + dir.string();
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const Result text = run("info " + (dir / "embedded.gltf").string());
    ASSERT_EQ(text.status, 0) << text.output;
    EXPECT_NE(text.output.find("\nroot\n"), std::string::npos) << text.output;
    EXPECT_NE(text.output.find("\n  group\n    box_c  [box]\n"), std::string::npos) << text.output;
    EXPECT_NE(text.output.find("\n  pipes  [pipe/0, pipe/1]\n"), std::string::npos) << text.output;
    EXPECT_NE(text.output.find("instances = 11"), std::string::npos) << text.output;
    const Result json = run("info --json " + (dir / "binary.glb").string());
    ASSERT_EQ(json.status, 0) << json.output;
    EXPECT_NE(json.output.find("\"path\" : \"root/group/box_c\""), std::string::npos) << json.output;
    EXPECT_NE(json.output.find("\"format\" : \"glb\""), std::string::npos) << json.output;
    const Result r = run("render " + (dir / "external.gltf").string() + " --out " + (dir / "f.png").string() +
                         " --width 48 --height 32 --threads 2");
    EXPECT_EQ(r.status, 0) << r.output;

    expectOneLineError(run("info " + (dir / "truncated.glb").string()), 1, "truncated.glb: ");
    expectOneLineError(run("info " + (dir / "missing_buffer.gltf").string()), 1, "missing.bin");
    expectOneLineError(run("render " + (dir / "bad_json.gltf").string() + " --out x.png"), 1, "bad_json.gltf: ");
    expectOneLineError(run("render " + (dir / "huge_count.gltf").string() + " --out x.png"), 1, "2147483648 elements");
}

// The six numbers of the JSON "bounds" of `json` (lo then hi), parsed as doubles.
std::vector<double> boundsOf(const std::string& json) {
    std::vector<double> v;
    const size_t at = json.find("\"bounds\" : [");
    if (at == std::string::npos) return v;
    const std::regex number("-?[0-9]+(\\.[0-9]+)?([eE][-+]?[0-9]+)?");
    const std::string rest = json.substr(at + 12);
    for (auto it = std::sregex_iterator(rest.begin(), rest.end(), number); it != std::sregex_iterator() && v.size() < 6; ++it)
        v.push_back(std::stod(it->str()));
    return v;
}

// rtwall info --json of an assembly (issue 29): its world bounds (what a scene placing it once
// with no transform says too, through another path), the instances each part places, and what
// the lean storage costs per unique triangle and per instance.
TEST(CliCad, AssemblyInfoHasWorldBoundsInstancesPerPartAndBytes) {
    const auto dir = test::scratchDir();
    const std::string cmd = "python3 " + (test::sourceDir() / "tools" / "gltf_testgen.py").string() + " --out " + dir.string();
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const Result a = run("info --json " + (dir / "binary.glb").string());
    ASSERT_EQ(a.status, 0) << a.output;
    const auto scene = test::writeFile(dir / "s.toml", "[[mesh]]\nname = \"g\"\nfile = \"binary.glb\"\n[[instance]]\nmesh = \"g\"\n");
    const Result s = run("info --json " + scene.string());
    ASSERT_EQ(s.status, 0) << s.output;
    const std::vector<double> ab = boundsOf(a.output), sb = boundsOf(s.output);
    ASSERT_EQ(ab.size(), 6u) << a.output;
    ASSERT_EQ(sb.size(), 6u) << s.output;
    for (size_t i = 0; i < 6; ++i) EXPECT_NEAR(ab[i], sb[i], 1e-5 * (1 + std::abs(sb[i]))) << i;
    EXPECT_LT(ab[0], ab[3]);
    // 11 instances in all, each counted at its part.
    size_t placed = 0;
    const std::regex perPart("\"instances\" : ([0-9]+),?\n");
    for (auto it = std::sregex_iterator(a.output.begin(), a.output.end(), perPart); it != std::sregex_iterator(); ++it)
        placed += std::stoul((*it)[1].str());
    EXPECT_EQ(placed, 22u) << "11 at the parts and 11 in the total";
    EXPECT_NE(a.output.find("\"bytes_per_instance\" : 112"), std::string::npos) << a.output;
    EXPECT_NE(a.output.find("\"bytes_per_unique_triangle\" : "), std::string::npos) << a.output;
}

// STEP (issue 20): rtwall gen step writes an assembly through OpenCASCADE; rtwall info lists its
// tree with part names, and writes and then uses the assembly cache; a bad file is one line.
TEST(CliCad, StepGenInfoCacheAndBadFile) {
    const auto dir = test::scratchDir();
    const Result g = run("gen step --out " + dir.string() + " --instances 14");
    ASSERT_EQ(g.status, 0) << g.output;
    const std::string step = (dir / "assembly.step").string();
    const Result text = run("info " + step);
    ASSERT_EQ(text.status, 0) << text.output;
    EXPECT_NE(text.output.find("\nplant\n  module 1\n    plate  [plate]\n    bolt 1  [bolt]\n"), std::string::npos) << text.output;
    EXPECT_NE(text.output.find("instances = 14"), std::string::npos) << text.output;
    const Result first = run("info --json --cache " + step);
    ASSERT_EQ(first.status, 0) << first.output;
    EXPECT_NE(first.output.find("\"cache\" : \"written\""), std::string::npos) << first.output;
    EXPECT_NE(first.output.find("\"reader\" : \"direct\""), std::string::npos) << first.output;
    const Result xde = run("info --json --step-xde " + step);
    EXPECT_NE(xde.output.find("\"reader\" : \"xde: asked for"), std::string::npos) << xde.output;
    EXPECT_NE(xde.output.find("\"instances\" : 14"), std::string::npos) << xde.output;
    const Result second = run("info --json --cache " + step);
    EXPECT_NE(second.output.find("\"cache\" : \"hit\""), std::string::npos) << second.output;
    EXPECT_NE(second.output.find("\"path\" : \"plant/module 2/bracket 2\""), std::string::npos) << second.output;
    const Result r = run("render " + step + " --cache --out " + (dir / "f.png").string() + " --width 48 --height 32 --threads 2");
    EXPECT_EQ(r.status, 0) << r.output;

    const auto bad = test::writeFile(dir / "bad.step", "ISO-10303-21;\nHEADER;\nthis is not a header\n");
    expectOneLineError(run("info " + bad.string()), 1, bad.string() + ": ");
    expectOneLineError(run("render " + bad.string() + " --out x.png"), 1, bad.string() + ": ");
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// Ctrl-C while the importing child says nothing (parsing a large file, here stopped outright):
// the parent still asks its progress function every 0.1 s, so rtwall info ends "interrupted"
// (status 130) and takes the child with it. Before, it waited for the child's next report, or
// for the stall limit (minutes).
TEST(CliCad, CtrlCStopsAStepImportThatReportsNothing) {
    const auto dir = test::scratchDir();
    const Result g = run("gen step --rows --out " + dir.string() + " --instances 70000");
    ASSERT_EQ(g.status, 0) << g.output;
    test::ChildProcess info({RTWALL_EXE, "info", "--json", (dir / "assembly.step").string()});
    std::vector<pid_t> importer;
    for (int i = 0; i < 20000 && importer.empty() && test::alive(info.pid()); ++i) {
        importer = test::childrenOf(info.pid());
        if (importer.empty()) std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
    ASSERT_EQ(importer.size(), 1u) << "no importing child seen: " << info.output();
    ASSERT_EQ(::kill(importer[0], SIGSTOP), 0);
    info.signal(SIGINT);
    const auto status = info.wait(20000);
    ::kill(importer[0], SIGCONT);
    ASSERT_TRUE(status) << "rtwall info waited for a child that reports nothing";
    EXPECT_EQ(*status, 130) << info.output();
    EXPECT_NE(info.output().find("interrupted"), std::string::npos) << info.output();
    EXPECT_FALSE(test::alive(importer[0])) << "the importing child was left behind";
}

}  // namespace
}  // namespace rtwall
