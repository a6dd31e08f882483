// The rtwall command line as a user meets it: exit codes, one-line errors, outputs.
#include "test_util.h"
#include "cli_util.h"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cctype>
#include <cstdio>

namespace rtwall {
namespace {

using Result = test::CliResult;

Result run(const std::string& args) { return test::runCli(RTWALL_EXE, args, 120); }

void expectOneLineError(const Result& r, const std::string& mustContain) {
    EXPECT_TRUE(r.status == 1 || r.status == 2) << "status " << r.status << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(mustContain), std::string::npos) << r.output;
}

TEST(Cli, HelpOnEveryCommand) {
    for (const char* c : {"--help", "render --help", "info --help", "bench --help", "bench kernel --help", "run --help",
                          "client --help"}) {
        const Result r = run(c);
        EXPECT_EQ(r.status, 0) << c;
        EXPECT_NE(r.output.find("Usage"), std::string::npos) << c << ": " << r.output;
    }
}

TEST(Cli, RendersTheDemoScene) {
    const auto out = test::scratchDir() / "demo.png";
    const Result r = run("render " + (test::sourceDir() / "configs/demo.toml").string() + " --out " + out.string() +
                         " --width 64 --height 48 --threads 2 --kernel single --camera top");
    ASSERT_EQ(r.status, 0) << r.output;
    const Image img = readPng(out);
    EXPECT_EQ(img.width, 64);
    EXPECT_EQ(img.height, 48);
}

TEST(Cli, RendersAMeshFileDirectly) {
    const auto out = test::scratchDir() / "knot.png";
    const Result r = run("render " + (test::sourceDir() / "configs/meshes/knot.ply").string() + " --out " +
                         out.string() + " --width 40 --height 30");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(out));
}

TEST(Cli, InfoJsonOnAMesh) {
    const Result r = run("info --json " + (test::sourceDir() / "configs/meshes/knot.ply").string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("\"triangles\" : 17280"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"vertices\" : 8640"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"bounds\""), std::string::npos) << r.output;
}

// Issue 20: rtwall info lists a scene's section planes (slot, point in the file's coordinates,
// normal, cap colour); rtwall render takes them from the scene file.
TEST(Cli, InfoListsSectionPlanes) {
    const Result r = run("info --json " + (test::sourceDir() / "configs/section.toml").string());
    ASSERT_EQ(r.status, 0) << r.output;
    size_t slots = 0;
    for (size_t at = r.output.find("\"slot\""); at != std::string::npos; at = r.output.find("\"slot\"", at + 1)) ++slots;
    EXPECT_EQ(slots, 2u) << r.output;
    EXPECT_NE(r.output.find("\"cap_color\""), std::string::npos) << r.output;
    const auto out = test::scratchDir() / "section.png";
    const Result render = run("render " + (test::sourceDir() / "configs/section.toml").string() +
                              " --width 80 --height 60 --out " + out.string());
    EXPECT_EQ(render.status, 0) << render.output;
}

// Issue 15: how the polygons became triangles, in rtwall info (text and JSON); a PLY header line
// that is no keyword is one warning line on stderr.
TEST(Cli, InfoCountsHowPolygonsWereTriangulated) {
    const std::string file = (std::filesystem::path(RTWALL_TEST_DATA_DIR) / "meshes" / "polygons.obj").string();
    const Result json = run("info --json " + file);
    ASSERT_EQ(json.status, 0) << json.output;
    for (const char* field : {"\"polygons_triangulated\" : 9", "\"polygons_fanned\" : 1", "\"polygons_ear_clipped\" : 6",
                              "\"polygons_degenerate\" : 1", "\"polygons_self_intersecting\" : 1", "\"degenerate_triangles\" : 2"})
        EXPECT_NE(json.output.find(field), std::string::npos) << field << "\n" << json.output;
    const Result text = run("info " + file);
    ASSERT_EQ(text.status, 0) << text.output;
    EXPECT_NE(text.output.find("polygons_ear_clipped = 6"), std::string::npos) << text.output;
    const std::string blender = (std::filesystem::path(RTWALL_TEST_DATA_DIR) / "meshes" / "blender_247.ply").string();
    const Result warned = run("info " + blender);
    ASSERT_EQ(warned.status, 0) << warned.output;
    EXPECT_NE(warned.output.find("warning: " + blender + ":line 3: "), std::string::npos) << warned.output;
    const size_t first = warned.output.find("warning:");
    EXPECT_EQ(warned.output.find("warning:", first + 1), std::string::npos) << "one warning only\n" << warned.output;
}

TEST(Cli, RenderThroughLocalClientsGivesTheSameBytes) {
    const auto dir = test::scratchDir();
    const std::string scene = (test::sourceDir() / "configs/demo.toml").string();
    const Result one = run("render " + scene + " --out " + (dir / "one.png").string() + " --width 64 --height 48");
    const Result two = run("render " + scene + " --out " + (dir / "two.png").string() +
                           " --width 64 --height 48 --clients 2 --tile 8 --codec zstd");
    ASSERT_EQ(one.status, 0) << one.output;
    ASSERT_EQ(two.status, 0) << two.output;
    EXPECT_EQ(readPng(dir / "one.png").rgb, readPng(dir / "two.png").rgb);
}

// The embedded default drives the reference wall (1600x1200, 2x2 projectors): headless here, it
// writes the frame and each projector's image. (Its operating point calibrates for about half a
// minute first, so this run turns it off: the demo itself, .ci/run, runs it.)
TEST(Cli, RunWithTheEmbeddedDefaultAndWithAConfig) {
    const auto dir = test::scratchDir();
    const Result a = run("run --headless --frames 3 --write-every 3 --target-fps 0 --out " + dir.string());
    ASSERT_EQ(a.status, 0) << a.output;
    EXPECT_NE(a.output.find("1600x1200"), std::string::npos) << a.output;
    EXPECT_EQ(readPng(dir / "frame_000003.png").width, 1600) << a.output;
    for (const char* screen : {"c0r0", "c1r0", "c0r1", "c1r1"})
        EXPECT_EQ(readPng(dir / ("frame_000003_" + std::string(screen) + ".png")).width, 800) << screen << "\n" << a.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "frame_000001_c0r0.png")) << "projector images every 3rd frame, with the frames";
    EXPECT_NE(a.output.find("median"), std::string::npos) << a.output;
    const Result b = run("run " + (test::sourceDir() / "configs/run/demo.toml").string() + " --frames 2 --write-every 0");
    EXPECT_EQ(b.status, 0) << b.output;
}

TEST(Cli, BadRunConfigNamesFileLineAndKey) {
    const auto file = test::writeFile(test::scratchDir() / "run.toml", "scene = \"builtin:knots\"\n[cluster]\nclients = 2\ncodec = \"png\"\n");
    expectOneLineError(run("run " + file.string()), file.string() + ":4: [cluster]: key 'codec'");
    const auto typo = test::writeFile(test::scratchDir() / "typo.toml", "[run]\nframs = 3\n");
    expectOneLineError(run("run " + typo.string()), "unknown key 'frams'");
}

TEST(Cli, RunFollowsACameraPath) {
    const auto dir = test::scratchDir();
    const Result r = run("run " + (test::sourceDir() / "configs/run/demo.toml").string() + " --camera-path " +
                         (test::sourceDir() / "configs/run/flyby.toml").string() +
                         " --frames 3 --write-every 1 --out " + dir.string());
    ASSERT_EQ(r.status, 0) << r.output;
    // Asynchronous: frame 2 was begun before the camera of frame 2 was set, so it shows in 3.
    EXPECT_NE(readPng(dir / "frame_000001.png").rgb, readPng(dir / "frame_000003.png").rgb) << "the camera moved";
    const auto bad = test::writeFile(dir / "path.toml", "[[key]]\nframe = 5\nposition = [0,0,1]\nlook_at = [0,0,0]\n"
                                                        "[[key]]\nframe = 2\nposition = [0,0,2]\nlook_at = [0,0,0]\n");
    expectOneLineError(run("run --camera-path " + bad.string() + " --frames 1"), bad.string() + ":6");
}

// Issue 17: every command loads scenes the same way: .TOML is a scene file, KNOT.PLY and
// MODEL.OBJ mesh files, as their lower-case twins.
TEST(Cli, UpperCaseExtensionsAreTheSameFiles) {
    const auto dir = test::scratchDir();
    std::filesystem::copy_file(test::sourceDir() / "configs/meshes/knot.ply", dir / "KNOT.PLY");
    std::filesystem::copy_file(test::sourceDir() / "configs/meshes/knot.ply", dir / "knot.ply");
    std::filesystem::copy_file(test::dataDir() / "meshes/box_normals.obj", dir / "MODEL.OBJ");
    std::filesystem::copy_file(test::dataDir() / "meshes/box_normals.obj", dir / "model.obj");
    const std::string scene = "[[mesh]]\nname = \"knot\"\nfile = \"KNOT.PLY\"\n[[instance]]\nmesh = \"knot\"\n";
    test::writeFile(dir / "SCENE.TOML", scene);
    test::writeFile(dir / "scene.toml", scene);
    for (const char* name : {"SCENE.TOML", "KNOT.PLY", "MODEL.OBJ"}) {
        std::string lower = name;
        for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
        for (const std::string& n : {std::string(name), lower}) {
            const Result r = run("render " + (dir / n).string() + " --width 32 --height 24 --out " + (dir / (n + ".png")).string());
            ASSERT_EQ(r.status, 0) << n << ": " << r.output;
        }
        EXPECT_EQ(readPng(dir / (std::string(name) + ".png")).rgb, readPng(dir / (lower + ".png")).rgb) << name;
        const Result ref = run("reference " + (dir / name).string() + " --width 16 --height 12 --supersample 1 --out " +
                               (dir / "ref.png").string());
        EXPECT_EQ(ref.status, 0) << name << ": " << ref.output;
    }
    const Result info = run("info --json " + (dir / "SCENE.TOML").string());
    ASSERT_EQ(info.status, 0) << info.output;
    EXPECT_NE(info.output.find("\"instanced_triangles\" : 17280"), std::string::npos) << info.output;
    const Result mesh = run("info --json " + (dir / "KNOT.PLY").string());
    ASSERT_EQ(mesh.status, 0) << mesh.output;
    EXPECT_NE(mesh.output.find("\"triangles\" : 17280"), std::string::npos) << mesh.output;
}

TEST(Cli, ClientRejectsABadEndpoint) { expectOneLineError(run("client --connect localhost:1"), "tcp://HOST:PORT"); }

TEST(Cli, MissingSceneFile) { expectOneLineError(run("render /no/such.toml --out x.png"), "/no/such.toml"); }

TEST(Cli, MissingMeshFile) { expectOneLineError(run("info /no/such.obj"), "/no/such.obj"); }

TEST(Cli, UnknownCamera) {
    expectOneLineError(run("render " + (test::sourceDir() / "configs/demo.toml").string() +
                           " --out /tmp/x.png --camera nope"),
                       "no camera named 'nope'");
}

TEST(Cli, BadArguments) {
    expectOneLineError(run("render"), "error");
    expectOneLineError(run("render a.toml --out x.png --width -3"), "width");
    expectOneLineError(run("render a.toml --out x.png --kernel simd"), "kernel");
    expectOneLineError(run("frobnicate"), "error");
    expectOneLineError(run("render a.toml --out x.png --threads lots"), "threads");
}

// The options a replay command uses (issue 17), given bad values.
TEST(Cli, ReplayOptionsRejectBadValues) {
    const std::string knot = "render " + (test::sourceDir() / "configs/meshes/knot.ply").string() + " --out /tmp/x.png ";
    expectOneLineError(run(knot + "--camera-position 1,2"), "--camera-position '1,2': expected 3 numbers");
    expectOneLineError(run(knot + "--camera-look-at 1,2,x"), "--camera-look-at '1,2,x': expected 3 numbers");
    expectOneLineError(run(knot + "--camera-up 0,0,0"), "up is parallel");
    expectOneLineError(run(knot + "--camera-window 0,0,0,1,0,0,2,0,0"), "the window has no area");
    expectOneLineError(run(knot + "--background 1,1,1,1"), "--background '1,1,1,1': expected 3 numbers");
    expectOneLineError(run(knot + "--frame 2 --frames 3"), "excludes");
    expectOneLineError(run(knot + "--region 0,0,8,8 --frames 3"), "--region renders one frame");
    expectOneLineError(run(knot + "--gi --no-gi"), "excludes");
    expectOneLineError(run(knot + "--shadows maybe"), "shadows");
    expectOneLineError(run(knot + "--frame 2 --clients 1"), "--frame and --clients cannot be combined");
}

TEST(Cli, MalformedSceneNamesFileAndLine) {
    const auto file = test::writeFile(test::scratchDir() / "bad.toml", "[image]\nwidth = 10\nwidht = 3\n");
    expectOneLineError(run("render " + file.string() + " --out /tmp/x.png"), file.string() + ":3");
}

TEST(Cli, UnwritableOutput) {
    expectOneLineError(run("render " + (test::sourceDir() / "configs/meshes/knot.ply").string() +
                           " --out /proc/none/x.png --width 8 --height 8"),
                       "/proc/none/x.png");
}

}  // namespace
}  // namespace rtwall
