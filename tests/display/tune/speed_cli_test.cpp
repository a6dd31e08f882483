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
#include <regex>

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

// rtwall reference --frames: the error it estimates for itself from two independent halves of its
// frames (path tracing: each frame jitters its samples) against its error measured with a
// reference of 16x the samples and other seeds. Statistical: 32x24 pixels x 3 channels of
// office GI noise; the big reference's own error (1/16 of the variance) lowers the measured
// PSNR by 0.26 dB. The mean of 1, 2, 4 and 8 frames is written on the way; the last is the output.
TEST(SpeedCli, ReferenceEstimatesItsOwnErrorFromTwoHalves) {
    const auto dir = test::scratchDir();
    ASSERT_EQ(run("gen office --out " + (dir / "office").string()).status, 0);
    const std::string scene = (dir / "office" / "office.toml").string();
    const std::string common = " --width 32 --height 24 --supersample 1 --gi-spp 2 --json";
    const std::string a = (dir / "a.png").string(), b = (dir / "b.png").string(), prefix = (dir / "acc").string();
    const Result small = run("reference " + scene + " --out " + a + " --frames 8 --progress-out " + prefix + common);
    ASSERT_EQ(small.status, 0) << small.output;
    const Result big = run("reference " + scene + " --out " + b + " --frames 128 --first-frame 16777216" + common);
    ASSERT_EQ(big.status, 0) << big.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(small.output, m, std::regex("\"own_psnr_db_estimate\" : ([0-9.]+)"))) << small.output;
    const double estimate = std::stod(m[1]);
    const double measured = compareImages(readPng(a), readPng(b)).psnrDb;
    EXPECT_GT(measured, 10.0);
    EXPECT_LT(measured, 40.0);  // noisy enough that the estimate means something
    EXPECT_NEAR(estimate, measured, 1.5);
    for (int k : {1, 2, 4}) EXPECT_EQ(readPng(prefix + "-" + std::to_string(k) + ".png").width, 32) << k;
    EXPECT_EQ(readPng(prefix + "-8.png").rgb, readPng(a).rgb);
    // A scene without path tracing renders the same frame every time: its halves are identical.
    const Result still = run("reference builtin:knots --triangles 2000 --out " + (dir / "k.png").string() +
                             " --width 32 --height 24 --supersample 1 --frames 2 --json");
    ASSERT_EQ(still.status, 0) << still.output;
    ASSERT_TRUE(std::regex_search(still.output, m, std::regex("\"halves_psnr_db\" : ([0-9.]+)"))) << still.output;
    EXPECT_GE(std::stod(m[1]), 99.0);
}

// bench tiles --denoise (the sweep's denoise control): the view the camera arrives at after an
// orbit of 8 frames, filtered, is scored beside the raw frame, and svgf at one GI sample a pixel
// is far closer to the converged reference than the raw frame; a scene without GI is refused.
TEST(SpeedCli, BenchTilesScoresTheDenoisedViewOfAnOrbit) {
    const auto dir = test::scratchDir();
    ASSERT_EQ(run("gen office --out " + (dir / "office").string()).status, 0);
    const std::string scene = (dir / "office" / "office.toml").string(), ref = (dir / "ref.png").string();
    const std::string size = " --width 64 --height 48";
    ASSERT_EQ(run("reference " + scene + " --out " + ref + size + " --supersample 1 --gi-spp 16 --frames 32 --json").status, 0);
    const Result r = run("bench tiles " + scene + size + " --gi-spp 1 --codecs raw --denoise 2 --reference " + ref + " --json");
    ASSERT_EQ(r.status, 0) << r.output;
    std::vector<double> db;
    const std::regex psnr("\"psnr_db\" : ([0-9.e+-]+)");
    for (std::sregex_iterator m(r.output.begin(), r.output.end(), psnr), e; m != e; ++m) db.push_back(std::stod((*m)[1]));
    ASSERT_EQ(db.size(), 2u) << r.output;  // the raw codec's, then the denoised view's
    EXPECT_NE(r.output.find("\"denoise\" : \"svgf\""), std::string::npos) << r.output;
    EXPECT_GT(db[1], db[0] + 4.0) << r.output;
    expectOneLineError(run("bench tiles builtin:knots --triangles 2000" + size + " --codecs raw --denoise 2"),
                       "--denoise filters path-traced frames");
    expectOneLineError(run("bench tiles " + scene + size + " --gi-spp 1 --codecs raw --denoise 1.5"),
                       "control 'denoise' = 1.500000 is not a whole number (0 off, 1 temporal, 2 svgf)");
}

TEST(SpeedCli, SimulateAndRunFrontsReportMistakesWithTheirFile) {
    expectOneLineError(run("simulate --profile /nonexistent/profile.toml"), "/nonexistent/profile.toml");
    const auto front = test::scratchDir() / "front.toml";  // once in this test
    std::ofstream(front) << "[[point]]\nname = \"x\"\nframe_s = 0.01\nerror = 1\ncontrols = { warp_drive = 3 }\n";
    expectOneLineError(run("run --frames 1 --clients 1 --target-fps 10 --front " + front.string()), "warp_drive");
}

// bench shading on the alpha-masked sunflower field (generated small): the unpruned reference
// row is exact, pruning changes little where no ray spawns children (the field has no mirrors or
// glass: only shadow rays of dim contributions play the roulette; 75 dB at 0.05), and 4 GI samples per pixel are closer to the many-sample mean than 1 (variance a quarter:
// about 6 dB; asserted 3 dB over 19,200 pixels).
TEST(SpeedCli, BenchShadingCoversTheSunflowerField) {
    const auto dir = test::scratchDir();
    const Result r = run("bench shading --json --width 160 --height 120 --rounds 1 --scenes sunflowers --thresholds 0.05 "
                         "--gi-samples 1,4 --reference-frames 8 --sunflower-plants 200 --sunflower-trees 0 --dir " +
                         dir.string());
    ASSERT_EQ(r.status, 0) << r.output;
    const size_t gi = r.output.find("\"gi_spp\"");
    ASSERT_NE(gi, std::string::npos) << r.output;
    const size_t giEnd = r.output.find(']', gi);
    std::vector<double> giDb, pruneDb;
    const std::regex db("\"psnr_db\" : ([0-9.e+-]+)");
    const std::string giText = r.output.substr(gi, giEnd - gi);
    for (std::sregex_iterator m(giText.begin(), giText.end(), db), e; m != e; ++m) giDb.push_back(std::stod((*m)[1]));
    const size_t prune = r.output.find("\"prune\"");
    ASSERT_NE(prune, std::string::npos) << r.output;
    const std::string pruneText = r.output.substr(prune, r.output.find(']', prune) - prune);
    for (std::sregex_iterator m(pruneText.begin(), pruneText.end(), db), e; m != e; ++m) pruneDb.push_back(std::stod((*m)[1]));
    ASSERT_EQ(giDb.size(), 2u) << r.output;
    EXPECT_GT(giDb[1], giDb[0] + 3.0) << r.output;
    ASSERT_EQ(pruneDb.size(), 2u) << r.output;
    EXPECT_EQ(pruneDb[0], 999.0);  // the reference row
    EXPECT_GT(pruneDb[1], 50.0) << r.output;  // only dim shadow rays are pruned
    EXPECT_NE(r.output.find("\"sunflower_plants\" : 200"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace rtwall
