// The command line for CAD scenes: rtwall info on every VTK format, rtwall gen, and one-line
// errors for bad files, bad scenes and bad arguments.
#include "test_util.h"
#include "cli_util.h"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>

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

}  // namespace
}  // namespace rtwall
