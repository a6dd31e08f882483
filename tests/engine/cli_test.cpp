// The rtwall command line as a user meets it: exit codes, one-line errors, outputs.
#include "test_util.h"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>

namespace rtwall {
namespace {

struct Result {
    int status = -1;
    std::string output;  // stdout and stderr together
};

Result run(const std::string& args) {
    // `timeout` guards against a hang: a hung command fails the test instead of the suite.
    const std::string cmd = "timeout 120 " + std::string(RTWALL_EXE) + " " + args + " 2>&1";
    Result r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    const int st = pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    return r;
}

void expectOneLineError(const Result& r, const std::string& mustContain) {
    EXPECT_TRUE(r.status == 1 || r.status == 2) << "status " << r.status << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(mustContain), std::string::npos) << r.output;
}

TEST(Cli, HelpOnEveryCommand) {
    for (const char* c : {"--help", "render --help", "info --help", "bench --help", "bench kernel --help"}) {
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
