// The shading commands as a user meets them: `rtwall gen` writes demos that render (also
// through local client processes, to the same bytes), and bad shading arguments end with one line.
#include "test_util.h"
#include "cli_util.h"

#include <rtwall/image.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <sys/wait.h>

namespace rtwall {
namespace {

using Result = test::CliResult;

Result run(const std::string& args) { return test::runCli(RTWALL_EXE, args, 300); }

TEST(CliShading, GeneratedDemosRenderAndTheClusterGivesTheSameBytes) {
    const auto dir = test::scratchDir();
    ASSERT_EQ(run("gen office --out " + (dir / "office").string()).status, 0);
    ASSERT_EQ(run("gen headlight --out " + (dir / "headlight").string()).status, 0);
    const std::string office = (dir / "office/office.toml").string();
    Result r = run("render " + office + " --width 64 --height 48 --gi --frames 2 --out " + (dir / "a.png").string());
    ASSERT_EQ(r.status, 0) << r.output;
    r = run("render " + office + " --width 64 --height 48 --gi --frames 2 --clients 2 --out " + (dir / "b.png").string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(readPng(dir / "a.png").rgb, readPng(dir / "b.png").rgb);
    r = run("render " + (dir / "headlight/headlight.toml").string() +
            " --width 32 --height 24 --prune 0.05 --view depth --out " + (dir / "h.png").string());
    EXPECT_EQ(r.status, 0) << r.output;
}

TEST(CliShading, BadArgumentsEndWithOneLine) {
    for (const char* args : {"render x.toml --out y.png --view xray", "render x.toml --out y.png --prune 2",
                             "render x.toml --out y.png --samples 0", "gen garden --out /tmp/x", "gen office"}) {
        const Result r = run(args);
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
    }
}

}  // namespace
}  // namespace rtwall
