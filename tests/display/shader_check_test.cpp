// Every shader is compiled with glslang (no GPU needed); a broken one is reported with its line.
#include "display_test_util.h"

namespace rtwall {
namespace {

TEST(Shaders, TheShippedShadersCompile) {
    EXPECT_TRUE(checkShader(presentVertexShader(), false).empty());
    EXPECT_TRUE(checkShader(presentFragmentShader(), true).empty());
    EXPECT_NE(presentFragmentShader().text.find("uniform ivec4 viewport"), std::string::npos);
}

// The GL re-projection's passes (issue 27): each compiles as GLSL 330 core, and `rtwall check`
// (checkWall) compiles them for every wall.
TEST(Shaders, TheWarpShadersCompile) {
    const std::vector<ShaderSource> warp = warpShaders();
    ASSERT_EQ(warp.size(), 10u);  // the re-projection's passes, the projector blend and post-warp
    for (const ShaderSource& s : warp) {
        EXPECT_TRUE(s.name.ends_with(".vert") || s.name.ends_with(".frag")) << s.name;
        const auto problems = checkShader(s, s.name.ends_with(".frag"));
        EXPECT_TRUE(problems.empty()) << s.name << ": " << (problems.empty() ? "" : problems[0]);
    }
    EXPECT_TRUE(checkWall(singleScreenWall(64, 48)).empty());
}

TEST(Shaders, ABrokenShaderGivesItsLine) {
    const std::string text = "#version 330 core\nout vec4 colour;\nvoid main() {\n    colour = vec4(undefinedThing, 1.0);\n}\n";
    const auto problems = checkShader({"broken.frag", text}, true);
    ASSERT_FALSE(problems.empty());
    EXPECT_EQ(problems[0].rfind("broken.frag:4: ", 0), 0u) << problems[0];
    EXPECT_NE(problems[0].find("undefinedThing"), std::string::npos) << problems[0];
    // A vertex stage feature in a fragment shader, a missing main and a wrong version.
    EXPECT_FALSE(checkShader({"v.frag", "#version 330 core\nvoid main() { gl_Position = vec4(0.0); }\n"}, true).empty());
    EXPECT_FALSE(checkShader({"nomain.frag", "#version 330 core\nout vec4 c;\n"}, true).empty());
    EXPECT_FALSE(checkShader({"syntax.vert", "#version 330 core\nvoid main() {\n  float x = ;\n}\n"}, false).empty());
    EXPECT_EQ(checkShader({"syntax.vert", "#version 330 core\nvoid main() {\n  float x = ;\n}\n"}, false)[0].rfind("syntax.vert:3:", 0), 0u);
}

TEST(Shaders, CheckingAWallCompilesTheShadersItNames) {
    const auto dir = test::scratchDir();
    test::writeFile(dir / "good.frag", presentFragmentShader().text);
    test::writeFile(dir / "bad.frag", "#version 330 core\nout vec4 colour;\n\nvoid main() {\n    colour = vec3(1.0);\n}\n");
    const std::string wall = "[wall]\nwidth = 100\nheight = 100\n[[screen]]\nname = \"a\"\nviewport = [0, 0, 50, 100]\nshader = \"good.frag\"\n"
                             "[[screen]]\nname = \"b\"\nviewport = [50, 0, 50, 100]\nshader = \"SHADER\"\n";
    std::string good = wall;
    good.replace(good.find("SHADER"), 6, "good.frag");
    EXPECT_TRUE(checkWall(test::writeFile(dir / "good.toml", good)).empty());
    std::string bad = wall;
    bad.replace(bad.find("SHADER"), 6, "bad.frag");
    const auto problems = checkWall(test::writeFile(dir / "bad.toml", bad));
    ASSERT_EQ(problems.size(), 1u) << ::testing::PrintToString(problems);
    EXPECT_NE(problems[0].find("bad.frag:5: "), std::string::npos) << problems[0];
}

}  // namespace
}  // namespace rtwall
