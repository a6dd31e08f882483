// The speed-against-accuracy commands as a user meets them: rtwall compare, bench codecs,
// simulate and run --front: outputs, exit codes and one-line errors.
#include "test_util.h"
#include "cli_util.h"

#include <rtwall/tune.h>

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>

namespace rtwall {
namespace {

using Result = test::CliResult;

Result run(const std::string& args) { return test::runCli(RTWALL_EXE, args, 120); }

void expectOneLineError(const Result& r, const std::string& mustContain) {
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(mustContain), std::string::npos) << r.output;
}

// test::scratchDir() empties the test's directory: call it once per test.
std::string png(const std::filesystem::path& dir, const std::string& name, int w, int h, uint8_t v) {
    Image img{w, h, std::vector<uint8_t>(size_t(w) * h * 3, v)};
    const auto path = dir / name;
    writePng(img, path);
    return path.string();
}

TEST(SpeedCli, CompareReportsKnownValuesAndWritesTheDifference) {
    const auto dir = test::scratchDir();
    const std::string a = png(dir, "cmp_a.png", 32, 32, 100), b = png(dir, "cmp_b.png", 32, 32, 104);
    const std::string diff = (dir / "cmp_diff.png").string();
    const Result r = run("compare " + a + " " + b + " --json --diff " + diff);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("\"rmse\" : 4.0"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"max_error\" : 4"), std::string::npos) << r.output;
    EXPECT_EQ(readPng(diff).width, 32);
    // FLIP as the library computes it for the same pair (uniform greys: the colour term alone).
    const size_t at = r.output.find("\"flip\" : ");
    ASSERT_NE(at, std::string::npos) << r.output;
    const double flip = std::stod(r.output.substr(at + 9));
    EXPECT_NEAR(flip, flipMean(readPng(a), readPng(b)), 1e-9);
    EXPECT_GT(flip, 0.0);
    EXPECT_LT(flip, 0.5);
}

TEST(SpeedCli, CompareFailsWithOneLineForBadInputs) {
    const auto dir = test::scratchDir();
    const std::string a = png(dir, "cmp_small.png", 32, 32, 0), b = png(dir, "cmp_other.png", 40, 32, 0);
    expectOneLineError(run("compare " + a + " " + b), "is 32x32 but");
    expectOneLineError(run("compare " + a + " /nonexistent/x.png"), "/nonexistent/x.png");
    const auto notPng = dir / "not.png";
    std::ofstream(notPng) << "hello";
    expectOneLineError(run("compare " + notPng.string() + " " + a), "not.png");
    const std::string tiny = png(dir, "cmp_tiny.png", 8, 8, 0);
    expectOneLineError(run("compare " + tiny + " " + tiny), "11x11");
}

TEST(SpeedCli, BenchCodecsLosslessIsExactAndJpegIsNot) {
    const std::string a = png(test::scratchDir(), "codecs.png", 64, 64, 77);
    const Result r = run("bench codecs " + a + " --codecs lz4,jpeg:50 --tile 32 --json");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("\"identical\" : true"), std::string::npos) << r.output;
    expectOneLineError(run("bench codecs " + a + " --codecs lz4:3"), "only jpeg");
}

TEST(SpeedCli, SimulateAndRunFrontsReportMistakesWithTheirFile) {
    expectOneLineError(run("simulate --profile /nonexistent/profile.toml"), "/nonexistent/profile.toml");
    const auto front = test::scratchDir() / "front.toml";  // once in this test
    std::ofstream(front) << "[[point]]\nname = \"x\"\nframe_s = 0.01\nerror = 1\ncontrols = { warp_drive = 3 }\n";
    expectOneLineError(run("run --frames 1 --clients 1 --target-fps 10 --front " + front.string()), "warp_drive");
}

}  // namespace
}  // namespace rtwall
