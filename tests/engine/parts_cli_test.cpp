// `rtwall render --hide/--isolate/--highlight` (issue 20), through the executable: on top of the
// scene file's [parts], a hidden mesh is gone from the PNG as if the scene never had it, on one
// machine and through local client processes alike; a pattern that matches nothing is one line.
#include "cli_util.h"
#include "step_assembly.h"
#include "test_util.h"

#include "generators.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

namespace rtwall {
namespace {

const std::string kScene = test::sceneText("floor_box");

TEST(PartsCli, HideOnTheCommandLineIsTheSceneWithoutIt) {
    const auto dir = test::scratchDir();
    test::writeFile(dir / "s.toml", kScene + "[parts]\nhighlight = [\"floor\"]\n");
    std::string without = kScene;
    without.erase(without.find("[[instance]]\nmesh = \"box\""), std::string("[[instance]]\nmesh = \"box\"\nscale = 0.5\ntranslate = [0, 0.5, 0]\n").size());
    test::writeFile(dir / "w.toml", without + "[parts]\nhighlight = [\"floor\"]\n");
    const std::string exe = RTWALL_EXE;
    for (const std::string& extra : {std::string(), std::string(" --clients 2")}) {
        SCOPED_TRACE(extra);
        auto a = test::runCli(exe, "render " + (dir / "s.toml").string() + " --out " + (dir / "a.png").string() + " --hide box" + extra);
        ASSERT_EQ(a.status, 0) << a.output;
        auto b = test::runCli(exe, "render " + (dir / "w.toml").string() + " --out " + (dir / "b.png").string() + extra);
        ASSERT_EQ(b.status, 0) << b.output;
        auto c = test::runCli(exe, "render " + (dir / "s.toml").string() + " --out " + (dir / "c.png").string() + extra);
        ASSERT_EQ(c.status, 0) << c.output;
        EXPECT_EQ(readPng(dir / "a.png").rgb, readPng(dir / "b.png").rgb);
        EXPECT_NE(readPng(dir / "a.png").rgb, readPng(dir / "c.png").rgb) << "the box shows without --hide";
    }
    auto bad = test::runCli(exe, "render " + (dir / "s.toml").string() + " --out " + (dir / "x.png").string() + " --isolate 'no*'");
    EXPECT_EQ(bad.status, 1) << bad.output;
    EXPECT_NE(bad.output.find("isolate 'no*': no part or mesh matches it"), std::string::npos) << bad.output;
}

// `rtwall info` of a scene file lists the part tree of its assemblies, with what [parts] hides
// and highlights: the names a reviewer gives --hide.
TEST(PartsCli, InfoListsTheScenesPartTree) {
    const auto dir = test::scratchDir();
    gen::genStep({.out = dir, .instances = 14});
    test::writeFile(dir / "s.toml", "[[mesh]]\nname = \"plant\"\nfile = \"assembly.step\"\n[[instance]]\nmesh = \"plant\"\n"
                                    "[parts]\nhide = [\"plant/module 2/bolt 1\"]\nhighlight = [\"bracket*\"]\n");
    const auto r = test::runCli(RTWALL_EXE, "info " + (dir / "s.toml").string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("instances_hidden = 1\n"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("instances_highlighted = 4\n"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("plant\n  module 1\n    plate  [1 instance]\n    bolt 1  [1 instance]\n"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("  module 2\n    plate  [1 instance]\n    bolt 1  [1 instance, 1 hidden]\n"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("    bracket 2  [1 instance, 1 highlighted]\n"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace rtwall
