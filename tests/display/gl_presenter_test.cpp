// The real GLFW / OpenGL 3.3 path under Xvfb with Mesa's software renderer: the 2x2 wall shows
// a rendered frame, and each screen's pixels, read back, match the headless presenter's image.
// The test starts its own Xvfb (xvfb_server.h).
#include "cli_util.h"
#include "display_test_util.h"
#include "xvfb_server.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <rtwall/engine.h>
#include <rtwall/mpcdi.h>

#include <cstdlib>
#include <cstring>

namespace rtwall {
namespace {

const auto* const gXvfb = ::testing::AddGlobalTestEnvironment(new test::XvfbServer);

WallFrame renderedFrame(int width, int height, uint32_t number, float cameraX, bool stereo = false) {
    SceneDesc desc = loadSceneFile(test::sourceDir() / "configs/demo.toml");
    desc.settings.width = width;
    desc.settings.height = height;
    desc.settings.threads = 2;
    desc.settings.shading = ShadingMode::EyeLight;  // fast: the test is about presenting
    desc.cameras.front().position.x += cameraX;
    Scene scene(desc);
    WallFrame f;
    f.number = number;
    f.left = renderFrame(scene, Camera(desc.cameras.front(), width, height), desc.settings);
    if (stereo) {
        CameraDesc right = desc.cameras.front();
        right.position.x += 0.5f;
        f.right = renderFrame(scene, Camera(right, width, height), desc.settings);
    }
    f.tileSize = 32;
    const int tiles = ((width + 31) / 32) * ((height + 31) / 32);
    for (int t = 0; t < tiles; ++t) f.tileOwners.push_back(uint32_t(t % 3));
    return f;
}

int maxDifference(const Image& a, const Image& b) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    if (a.rgb.size() != b.rgb.size()) return 256;
    int worst = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) worst = std::max(worst, std::abs(int(a.rgb[i]) - int(b.rgb[i])));
    return worst;
}

void expectScreensMatchHeadless(const std::filesystem::path& config, UploadMethod upload, const PresentOptions& options,
                                int tolerance) {
    const WallConfig wall = loadWallConfig(config);
    std::string why;
    GlPresenter::Options o;
    o.upload = upload;
    auto gl = GlPresenter::open(wall, o, &why);
    ASSERT_TRUE(gl) << why;
    const auto dir = test::scratchDir();
    // Two frames, so the second really streams new pixels into the texture.
    for (uint32_t n = 1; n <= 2; ++n) {
        const WallFrame frame = renderedFrame(wall.width, wall.height, n, float(n) * 0.3f, wall.stereo.mode != StereoMode::None);
        std::vector<Image> shown;
        gl->present(frame, options, &shown);
        ASSERT_EQ(shown.size(), wall.screens.size());
        for (size_t s = 0; s < wall.screens.size(); ++s) {
            const Image expected = presentScreen(wall, s, frame, options);
            const int diff = maxDifference(shown[s], expected);
            EXPECT_LE(diff, tolerance) << "frame " << n << ", screen " << wall.screens[s].name << " ("
                                       << uploadMethodName(upload) << ", " << gl->renderer() << ")";
            if (diff > tolerance) {
                writePng(shown[s], dir / ("shown_" + wall.screens[s].name + ".png"));
                writePng(expected, dir / ("expected_" + wall.screens[s].name + ".png"));
            }
        }
    }
    EXPECT_EQ(gl->stats().frames, 2u);
}

TEST(GlPresenter, TheTwoByTwoWallShowsWhatTheHeadlessPresenterWrites) {
    // Pure crops: the same bytes.
    expectScreensMatchHeadless(test::sourceDir() / "configs/wall/projectors-2x2.toml", UploadMethod::TexSubImage, {}, 0);
}

TEST(GlPresenter, TheStatusOverlaySitsOnTheFirstScreen) {
    const Image status = textImage("rtwall 12.5 fps | 0.84 MB/frame lz4\nclient 1: 300 tiles 85% busy", 2);
    PresentOptions o;
    o.overlay = &status;
    expectScreensMatchHeadless(test::sourceDir() / "configs/wall/projectors-2x2.toml", UploadMethod::TexSubImage, o, 0);
}

// A per-screen stage (issue 26) in both presenters: it paints one rectangle of the second
// screen, and the GL presenter shows exactly what presentScreen makes with it.
class PaintStage final : public ScreenStage {
public:
    void apply(const WallConfig&, size_t screen, int, Image& pixels) const override {
        if (screen != 1) return;
        for (int y = kY0; y < kY1; ++y)
            for (int x = kX0; x < kX1; ++x) std::memcpy(pixels.pixel(x, y), kColour, 3);
    }
    void drawGl(const WallConfig& wall, size_t screen) override {
        if (screen != 1) return;
        const int height = wall.screens[screen].outputHeight;  // GL's rows count from the bottom
        glEnable(GL_SCISSOR_TEST);
        glScissor(kX0, height - kY1, kX1 - kX0, kY1 - kY0);
        glClearColor(kColour[0] / 255.0f, kColour[1] / 255.0f, kColour[2] / 255.0f, 1.0f);
        glClear(GL_COLOR_BUFFER_BIT);
        glDisable(GL_SCISSOR_TEST);
    }

private:
    static constexpr int kX0 = 5, kY0 = 3, kX1 = 45, kY1 = 20;
    static constexpr uint8_t kColour[3] = {10, 200, 30};
};

TEST(GlPresenter, AnInsertedStageShowsWhatTheCpuStageMakes) {
    PaintStage paint;
    const Image status = textImage("stage", 2);
    PresentOptions o;
    o.stages = {&paint};
    o.overlay = &status;
    expectScreensMatchHeadless(test::sourceDir() / "configs/wall/projectors-2x2.toml", UploadMethod::TexSubImage, o, 0);
}

// A calibrated wall's blend (issue 30): the GL stage (projector_blend.frag) against the CPU
// reference on the curved example's three projectors, alpha and beta maps everywhere. Within
// one code: the GPU's pow and its float-to-8-bit conversion may round the other way.
TEST(GlPresenter, TheProjectorBlendMatchesTheCpuReference) {
    const auto dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
    const WallConfig wall = loadWallConfig(dir / "c.toml");
    ProjectorBlendStage blend(wall, readMpcdi(wall.warp->mpcdi));
    PresentOptions o;
    o.stages = {&blend};
    expectScreensMatchHeadless(dir / "c.toml", UploadMethod::TexSubImage, o, 1);
    const WallFrame f = renderedFrame(wall.width, wall.height, 1, 0.0f);
    for (size_t s = 0; s < 3; ++s) EXPECT_NE(presentScreen(wall, s, f, o).rgb, presentScreen(wall, s, f).rgb) << "not blended";
}

// RGB and 16-bit maps (tools/mpcdi_testgen.py depths: every pixel's and channel's value its
// own) through the GL stage against the CPU reference: each channel by its own alpha and beta.
TEST(GlPresenter, RgbAndSixteenBitBlendMapsMatchTheCpuReference) {
    const auto dir = test::scratchDir();
    for (const std::string depths : {"--alpha 3x16 --beta 3x8", "--alpha 1x16 --beta 3x16", "--alpha 3x8 --beta 1x8"}) {
        SCOPED_TRACE(depths);
        test::mpcdiTestgen("depths " + (dir / "d.mpcdi").string() + " --res 64x48 " + depths);
        test::writeFile(dir / "d.toml", "[wall]\nwidth = 64\nheight = 48\n[[screen]]\nname = \"s\"\nviewport = [0, 0, 64, 48]\n"
                                        "[warp]\nmpcdi = \"d.mpcdi\"\nbuffers = { p = \"s\" }\n");
        const WallConfig wall = loadWallConfig(dir / "d.toml");
        ASSERT_TRUE(checkWall(dir / "d.toml").empty());
        ProjectorBlendStage blend(wall, readMpcdi(wall.warp->mpcdi));
        PresentOptions o;
        o.stages = {&blend};
        expectScreensMatchHeadless(dir / "d.toml", UploadMethod::TexSubImage, o, 1);
        // The maps' values differ per channel (a GL path that read one channel for all three
        // would be off by far more than a code), and they do change the picture.
        const WallFrame f = renderedFrame(64, 48, 1, 0.0f);
        EXPECT_NE(presentScreen(wall, 0, f, o).rgb, presentScreen(wall, 0, f).rgb) << "not blended";
    }
}

// The post-warp (issue 30's comparison mode) in GL against the CPU reference, with the blend
// after it, on the curved example: within one code.
TEST(GlPresenter, ThePostWarpMatchesTheCpuReference) {
    const auto dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
    const WallConfig wall = loadWallConfig(dir / "c.toml");
    const MpcdiFile file = readMpcdi(wall.warp->mpcdi);
    PostWarpStage post(wall, file);
    ProjectorBlendStage blend(wall, file);
    PresentOptions o;
    o.stages = {&post, &blend};
    expectScreensMatchHeadless(dir / "c.toml", UploadMethod::TexSubImage, o, 1);
    PresentOptions blendOnly;
    blendOnly.stages = {&blend};
    const WallFrame f = renderedFrame(wall.width, wall.height, 1, 0.0f);
    for (size_t s = 0; s < 3; ++s) EXPECT_NE(presentScreen(wall, s, f, o).rgb, presentScreen(wall, s, f, blendOnly).rgb) << "not warped";
}

// A side-by-side screen's post-warp in GL: each eye's half warped alone (the shader finds its
// pane), against the CPU reference within one code.
TEST(GlPresenter, ThePostWarpOfASideBySideScreenMatchesTheCpuReference) {
    const auto dir = test::scratchDir();
    test::mpcdiTestgen("identity " + (dir / "s.mpcdi").string() + " --buffer a=128x48 --shift 5,-3");
    const auto file = test::writeFile(dir / "sbs.toml", "[wall]\nwidth = 64\nheight = 48\n[stereo]\nmode = \"side_by_side\"\n"
                                                        "[[screen]]\nname = \"A\"\nviewport = [0, 0, 64, 48]\nresolution = [128, 48]\n"
                                                        "[warp]\nmpcdi = \"s.mpcdi\"\nbuffers = { a = \"A\" }\nmode = \"post\"\n");
    const WallConfig wall = loadWallConfig(file);
    PostWarpStage post(wall, readMpcdi(wall.warp->mpcdi));
    PresentOptions o;
    o.stages = {&post};
    expectScreensMatchHeadless(file, UploadMethod::TexSubImage, o, 1);
    const WallFrame f = renderedFrame(64, 48, 1, 0.0f, true);
    EXPECT_NE(presentScreen(wall, 0, f, o).rgb, presentScreen(wall, 0, f).rgb) << "not warped";
}

TEST(GlPresenter, PixelBufferUploadShowsTheSame) {
    expectScreensMatchHeadless(test::sourceDir() / "configs/wall/projectors-2x2.toml", UploadMethod::Pbo, {}, 0);
}

TEST(GlPresenter, BlendingGammaAndFalseColourMatchTheCpuReference) {
    // pow() on the GPU and the CPU may differ in the last bits: one level of slack.
    PresentOptions o;
    o.falseColour = true;
    expectScreensMatchHeadless(test::sourceDir() / "configs/wall/projector-pair-blend.toml", UploadMethod::Pbo, o, 1);
}

TEST(GlPresenter, StereoScreensShowTheirEyes) {
    expectScreensMatchHeadless(test::sourceDir() / "configs/wall/stereo-passive.toml", UploadMethod::TexSubImage, {}, 0);
    const auto dir = test::scratchDir();
    const auto sbs = test::writeFile(dir / "sbs.toml", "[wall]\nwidth = 320\nheight = 240\n[stereo]\nmode = \"side_by_side\"\n"
                                                       "[[screen]]\nviewport = [0, 0, 320, 240]\nresolution = [640, 240]\n");
    expectScreensMatchHeadless(sbs, UploadMethod::TexSubImage, {}, 0);
}

// A config's own shader is what the window draws: here present.frag with its output inverted,
// so every pixel must differ from the CPU reference by exactly that.
TEST(GlPresenter, AConfigShaderReplacesTheShippedOne) {
    const auto dir = test::scratchDir();
    std::string text = presentFragmentShader().text;
    const std::string last = "colour = vec4(clamp(c * brightness * w, 0.0, 1.0), 1.0);";
    ASSERT_NE(text.find(last), std::string::npos);
    text.replace(text.find(last), last.size(), "colour = vec4(1.0 - clamp(c * brightness * w, 0.0, 1.0), 1.0);");
    test::writeFile(dir / "invert.frag", text);
    const auto file = test::writeFile(dir / "w.toml", "[wall]\nwidth = 160\nheight = 120\n[[screen]]\nviewport = [0, 0, 160, 120]\nshader = \"invert.frag\"\n");
    ASSERT_TRUE(checkWall(file).empty());
    const WallConfig wall = loadWallConfig(file);
    std::string why;
    auto gl = GlPresenter::open(wall, {}, &why);
    ASSERT_TRUE(gl) << why;
    const WallFrame frame = renderedFrame(160, 120, 1, 0.0f);
    std::vector<Image> shown;
    gl->present(frame, {}, &shown);
    Image expected = presentScreen(wall, 0, frame);
    EXPECT_GT(maxDifference(shown[0], expected), 100) << "the shipped shader was used";
    for (uint8_t& v : expected.rgb) v = uint8_t(255 - v);
    EXPECT_EQ(maxDifference(shown[0], expected), 0);
}

TEST(GlPresenter, ABrokenConfigShaderIsRefusedBeforeAnyWindowOpens) {
    const auto dir = test::scratchDir();
    test::writeFile(dir / "bad.frag", "#version 330 core\nout vec4 colour;\nvoid main() { colour = nope; }\n");
    const auto file = test::writeFile(dir / "w.toml", "[wall]\nwidth = 64\nheight = 64\n[[screen]]\nviewport = [0, 0, 64, 64]\nshader = \"bad.frag\"\n");
    const auto problems = checkWall(file);
    ASSERT_FALSE(problems.empty());
    EXPECT_NE(problems[0].find("bad.frag:3: 'nope' : undeclared identifier"), std::string::npos) << problems[0];
    // The wall does not open with it either: the driver refuses it too.
    std::string why;
    EXPECT_THROW(GlPresenter::open(loadWallConfig(file), {}, &why), InputError);
}

// A frame rendered at a fraction of the wall's resolution (the `scale` control) is shown
// upscaled, bilinearly, by the GPU's filtering: within two levels of the CPU reference, which
// resamples in integer steps; the tile-owner view uses the frame's tiles.
TEST(GlPresenter, AFrameAtHalfTheWallsResolutionIsShownUpscaled) {
    const WallConfig wall = loadWallConfig(test::sourceDir() / "configs/wall/projectors-2x2.toml");
    std::string why;
    auto gl = GlPresenter::open(wall, {}, &why);
    ASSERT_TRUE(gl) << why;
    for (bool falseColour : {false, true}) {
        WallFrame frame = renderedFrame(wall.width / 2, wall.height / 2, 1, 0.0f);
        PresentOptions options;
        options.falseColour = falseColour;
        std::vector<Image> shown;
        gl->present(frame, options, &shown);
        ASSERT_EQ(shown.size(), wall.screens.size());
        for (size_t s = 0; s < wall.screens.size(); ++s) {
            const Image expected = presentScreen(wall, s, frame, options);
            EXPECT_EQ(expected.width, 800);
            EXPECT_LE(maxDifference(shown[s], expected), 2) << "screen " << wall.screens[s].name << ", false colour " << falseColour;
        }
    }
    // And back to a full-size frame: the textures follow the frame's size.
    const WallFrame full = renderedFrame(wall.width, wall.height, 2, 0.0f);
    std::vector<Image> shown;
    gl->present(full, {}, &shown);
    EXPECT_EQ(maxDifference(shown[0], presentScreen(wall, 0, full, {})), 0);
    // Larger than the wall is a mistake, said as one.
    WallFrame tooBig = full;
    tooBig.left = Image{wall.width + 1, wall.height, std::vector<uint8_t>(size_t(wall.width + 1) * wall.height * 3)};
    EXPECT_THROW(gl->present(tooBig, {}), std::invalid_argument);
}

// `rtwall run` of the demo on the shipped 2x2 projector wall with `options`, three frames, the
// third written to `dir`.
test::CliResult runDemoOnTheWall(const std::filesystem::path& dir, const std::string& options) {
    return test::runCli(RTWALL_EXE, "run " + (test::sourceDir() / "configs/run/demo.toml").string() + " --wall " +
                                        (test::sourceDir() / "configs/wall/projectors-2x2.toml").string() + " " + options +
                                        " --frames 3 --write-every 3 --out " + dir.string(),
                        300);
}

// Issue 17: `rtwall run --target-fps` in a window stopped with an error when the controller took
// an operating point with a scale below 1 (the presenter refused a frame smaller than the wall).
TEST(GlPresenter, RunInAWindowAtAScaledOperatingPoint) {
    const auto dir = test::scratchDir();
    const auto front = test::writeFile(dir / "front.toml", R"([[point]]
name = "half resolution"
frame_s = 0.0001
error = 0.2
[point.controls]
scale = 0.5
tile = 32
)");
    const test::CliResult r = runDemoOnTheWall(dir, "--target-fps 1 --front " + front.string());
    const std::string& output = r.output;
    EXPECT_EQ(r.status, 0) << output;
    EXPECT_NE(output.find("4 windows"), std::string::npos) << output;
    EXPECT_NE(output.find("starting at 'half resolution'"), std::string::npos) << output;
    EXPECT_EQ(readPng(dir / "frame_000003.png").width, 1600) << output;
}

// `rtwall run` opens the wall by itself when there is a display (this test's Xvfb).
TEST(GlPresenter, RunShowsTheWallInWindowsWhereThereIsADisplay) {
    const auto dir = test::scratchDir();
    const test::CliResult r = runDemoOnTheWall(dir, "");
    const std::string& output = r.output;
    EXPECT_EQ(r.status, 0) << output;
    EXPECT_NE(output.find("4 windows"), std::string::npos) << output;
    EXPECT_TRUE(std::filesystem::exists(dir / "frame_000003.png")) << output;
    EXPECT_FALSE(std::filesystem::exists(dir / "frame_000003_c0r0.png")) << "per-screen files only without a display";
}

}  // namespace
}  // namespace rtwall
