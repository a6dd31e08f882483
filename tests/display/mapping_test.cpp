// The wall-to-screen mapping on the CPU, against values worked out by hand.
#include "display_test_util.h"

#include <rtwall/tune.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace rtwall {
namespace {

WallFrame gradientFrame(int w, int h, int tileSize = 0) {
    WallFrame f;
    f.left.width = w;
    f.left.height = h;
    f.left.rgb.resize(size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            uint8_t* p = f.left.pixel(x, y);
            p[0] = uint8_t(x * 7 + y);
            p[1] = uint8_t(y * 3);
            p[2] = uint8_t(x ^ y);
        }
    f.tileSize = tileSize;
    return f;
}

TEST(Mapping, TwoByTwoScreensCropTheirQuarter) {
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/projectors-2x2.toml");
    const ScreenSample a = mapPixel(w.screens[1], w.stereo.mode, 0, 0);
    EXPECT_EQ(a.wallX, 800);
    EXPECT_EQ(a.wallY, 0);
    EXPECT_EQ(a.weight, 1.0f);
    const ScreenSample b = mapPixel(w.screens[3], w.stereo.mode, 799, 599);
    EXPECT_EQ(b.wallX, 1599);
    EXPECT_EQ(b.wallY, 1199);
    // With no blending or correction, each screen is exactly its quarter of the wall.
    const WallFrame f = gradientFrame(1600, 1200);
    for (size_t s = 0; s < 4; ++s) {
        const Image img = presentScreen(w, s, f);
        const PixelRect& v = w.screens[s].viewport;
        for (int y = 0; y < 600; y += 7)
            for (int x = 0; x < 800; x += 5)
                ASSERT_EQ(0, std::memcmp(img.pixel(x, y), f.left.pixel(v.x + x, v.y + y), 3)) << s << " " << x << "," << y;
    }
}

TEST(Mapping, BezelPixelsAreRenderedButNotShown) {
    const WallConfig w = parseWallConfig(
        "[wall]\n[grid]\ncolumns = 2\nrows = 1\nscreen_width = 100\nscreen_height = 50\nbezel = [10, 10, 0, 0]\n", "w.toml");
    EXPECT_EQ(w.width, 220);  // 100 + 10 + 10 (the mullion) + 100
    EXPECT_EQ(mapPixel(w.screens[0], StereoMode::None, 99, 0).wallX, 99);
    EXPECT_EQ(mapPixel(w.screens[1], StereoMode::None, 0, 0).wallX, 120);
    // No screen pixel shows wall columns 100..119.
    for (const ScreenConfig& s : w.screens)
        for (int x = 0; x < s.outputWidth; ++x) {
            const int wx = mapPixel(s, StereoMode::None, x, 0).wallX;
            EXPECT_TRUE(wx < 100 || wx >= 120) << wx;
        }
}

TEST(Mapping, ScaledScreensSampleTheNearestWallPixel) {
    ScreenConfig s;
    s.viewport = {10, 20, 100, 50};
    s.outputWidth = 200;  // every wall pixel twice
    s.outputHeight = 25;  // every other row
    EXPECT_EQ(mapPixel(s, StereoMode::None, 0, 0).wallX, 10);
    EXPECT_EQ(mapPixel(s, StereoMode::None, 1, 0).wallX, 10);
    EXPECT_EQ(mapPixel(s, StereoMode::None, 2, 0).wallX, 11);
    EXPECT_EQ(mapPixel(s, StereoMode::None, 199, 0).wallX, 109);
    EXPECT_EQ(mapPixel(s, StereoMode::None, 0, 0).wallY, 21);  // centre of output row 0 is wall row 1
    EXPECT_EQ(mapPixel(s, StereoMode::None, 0, 24).wallY, 69);
}

TEST(Mapping, BlendRampsOfAnOverlapAddUpToOneInLight) {
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/projector-pair-blend.toml");
    const ScreenConfig &a = w.screens[0], &b = w.screens[1];
    ASSERT_EQ(a.viewport.x + a.viewport.width - b.viewport.x, 128);
    for (int wx = 0; wx < w.width; ++wx) {
        double light = 0;
        if (wx < a.viewport.x + a.viewport.width) light += std::pow(mapPixel(a, w.stereo.mode, wx - a.viewport.x, 100).weight, 2.2);
        if (wx >= b.viewport.x) light += std::pow(mapPixel(b, w.stereo.mode, wx - b.viewport.x, 100).weight, 2.2);
        EXPECT_NEAR(light, 1.0, 1e-4) << "wall column " << wx;
    }
    // Hand-worked: the first overlap column is 0.5/128 of the way into b's ramp.
    EXPECT_NEAR(mapPixel(b, w.stereo.mode, 0, 0).weight, std::pow(0.5 / 128, 1 / 2.2), 1e-6);
    EXPECT_EQ(mapPixel(b, w.stereo.mode, 128, 0).weight, 1.0f);
    EXPECT_FLOAT_EQ(blendRamp(4, 0.5f), 0.125f);
    EXPECT_FLOAT_EQ(blendRamp(4, 9.0f), 1.0f);
    EXPECT_FLOAT_EQ(blendRamp(0, 0.0f), 1.0f);
}

TEST(Mapping, GammaAndBrightnessCorrection) {
    ScreenConfig s;
    EXPECT_EQ(correctColour(200, 1.0f, s), 200);
    s.brightness = 0.5;
    EXPECT_EQ(correctColour(200, 1.0f, s), 100);
    s.brightness = 1.0;
    s.gamma = 2.0;  // out = in^(1/2): 64/255 -> 0.50098 -> 128
    EXPECT_EQ(correctColour(64, 1.0f, s), 128);
    s.gamma = 1.0;
    s.brightness = 2.0;
    EXPECT_EQ(correctColour(200, 1.0f, s), 255);  // clamped
    EXPECT_EQ(correctColour(100, 0.5f, ScreenConfig{}), 50);
}

TEST(Mapping, SideBySideStereoSplitsTheScreen) {
    ScreenConfig s;
    s.viewport = {0, 0, 100, 100};
    s.outputWidth = 200;
    s.outputHeight = 100;
    s.eye = Eye::Both;
    const ScreenSample l = mapPixel(s, StereoMode::SideBySide, 0, 0), r = mapPixel(s, StereoMode::SideBySide, 100, 0);
    EXPECT_EQ(l.eye, 0);
    EXPECT_EQ(r.eye, 1);
    EXPECT_EQ(l.wallX, 0);
    EXPECT_EQ(r.wallX, 0);
    EXPECT_EQ(mapPixel(s, StereoMode::SideBySide, 199, 0).wallX, 99);
    s.eye = Eye::Right;
    EXPECT_EQ(mapPixel(s, StereoMode::Passive, 0, 0).eye, 1);
}

TEST(Mapping, FalseColourTintsEachTileWithItsClient) {
    const WallConfig w = singleScreenWall(64, 32);
    WallFrame f = gradientFrame(64, 32, 32);
    f.tileOwners = {0, 1};
    PresentOptions o;
    o.falseColour = true;
    const Image img = presentScreen(w, 0, f, o);
    const auto c0 = ownerColour(0), c1 = ownerColour(1);
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(img.pixel(5, 5)[k], (f.left.pixel(5, 5)[k] + c0[size_t(k)]) / 2.0, 0.51);
        EXPECT_NEAR(img.pixel(40, 5)[k], (f.left.pixel(40, 5)[k] + c1[size_t(k)]) / 2.0, 0.51);
    }
    EXPECT_NE(ownerColour(0), ownerColour(1));
    EXPECT_EQ(ownerColour(UINT32_MAX), (std::array<uint8_t, 3>{128, 128, 128}));
}

TEST(Mapping, HeadlessPresenterWritesEveryNthFramePerScreen) {
    const auto dir = test::scratchDir();
    WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/projectors-2x2.toml");
    w.writeEvery = 2;
    HeadlessPresenter p(w, dir);
    WallFrame f = gradientFrame(1600, 1200);
    for (uint32_t n = 1; n <= 4; ++n) {
        f.number = n;
        p.present(f);
    }
    ASSERT_EQ(p.written().size(), 8u);  // frames 2 and 4, four screens each
    EXPECT_EQ(p.written()[0].filename(), "frame_000002_c0r0.png");
    const Image img = readPng(dir / "frame_000004_c1r1.png");
    EXPECT_EQ(img.rgb, presentScreen(w, 3, f).rgb);
}

// The video path pipes every wall frame, as raw RGB, into the ffmpeg program. A stand-in
// `ffmpeg` on PATH records its arguments and what it was sent, so the test checks exactly what
// a real ffmpeg would get (CI has no ffmpeg installed).
TEST(Mapping, HeadlessPresenterPipesEveryFrameToFfmpeg) {
    const auto dir = test::scratchDir();
    const auto bin = dir / "bin";
    std::filesystem::create_directories(bin);
    {
        std::ofstream script(bin / "ffmpeg");
        script << "#!/bin/sh\necho \"$@\" > '" << (dir / "ffmpeg.args").string() << "'\ncat > '"
               << (dir / "ffmpeg.stdin").string() << "'\n";
    }
    std::filesystem::permissions(bin / "ffmpeg", std::filesystem::perms::owner_all);
    const std::string oldPath = std::getenv("PATH") ? std::getenv("PATH") : "";
    setenv("PATH", (bin.string() + ":" + oldPath).c_str(), 1);
    WallConfig w = singleScreenWall(64, 48);
    w.video = "wall.mp4";
    w.writeEvery = 0;
    WallFrame f = gradientFrame(64, 48);
    {
        HeadlessPresenter p(w, dir);
        for (uint32_t n = 1; n <= 3; ++n) {
            f.number = n;
            p.present(f);
        }
    }  // closing the presenter closes the pipe and waits for ffmpeg
    setenv("PATH", oldPath.c_str(), 1);
    std::ifstream in(dir / "ffmpeg.stdin", std::ios::binary);
    const std::vector<char> sent((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_EQ(sent.size(), 3 * f.left.rgb.size());
    EXPECT_EQ(0, std::memcmp(sent.data() + 2 * f.left.rgb.size(), f.left.rgb.data(), f.left.rgb.size()));
    std::ifstream argsFile(dir / "ffmpeg.args");
    std::string args;
    std::getline(argsFile, args);
    EXPECT_NE(args.find("-pix_fmt rgb24 -s 64x48"), std::string::npos) << args;
    EXPECT_NE(args.find((dir / "wall.mp4").string()), std::string::npos) << args;
}

TEST(Mapping, StatusTextAndItsOverlay) {
    const Image one = textImage("1", 1);
    EXPECT_EQ(one.width, 7);   // a 2-pixel border, 3 columns, a gap, a border
    EXPECT_EQ(one.height, 9);
    EXPECT_EQ(one.pixel(3, 2)[0], 235);  // the top of the 1 is its middle column
    EXPECT_EQ(one.pixel(2, 2)[0], 24);
    EXPECT_EQ(one.pixel(2, 3)[0], 235);  // the flag
    const Image two = textImage("ab\nC", 2);
    EXPECT_EQ(two.width, (2 * 4 + 3) * 2);
    EXPECT_EQ(two.height, (2 * 6 + 3) * 2);
    EXPECT_EQ(textImage("a", 1).rgb, textImage("A", 1).rgb);
    // Pasted on the first screen only, kOverlayMargin from its top-left.
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/projectors-2x2.toml");
    const WallFrame f = gradientFrame(1600, 1200);
    PresentOptions o;
    o.overlay = &one;
    const Image first = presentScreen(w, 0, f, o);
    EXPECT_EQ(first.pixel(kOverlayMargin + 3, kOverlayMargin + 2)[1], 235);
    EXPECT_EQ(first.pixel(kOverlayMargin - 1, kOverlayMargin)[1], f.left.pixel(kOverlayMargin - 1, kOverlayMargin)[1]);
    EXPECT_EQ(presentScreen(w, 1, f, o).rgb, presentScreen(w, 1, f).rgb);
}

// A per-screen stage inserted after the mapping (issue 26): it paints one rectangle of one
// screen; every other pixel of every screen is what the wall showed without it, and the overlay
// still goes on top.
class PaintStage final : public ScreenStage {
public:
    void apply(const WallConfig&, size_t index, int, Image& pixels) const override {
        if (index != screen) return;
        for (int y = 2; y < 12; ++y)
            for (int x = 4; x < 24; ++x) std::memcpy(pixels.pixel(x, y), colour, 3);
    }
    void drawGl(const WallConfig&, size_t) override { throw std::logic_error("a CPU stage"); }
    size_t screen = 1;
    uint8_t colour[3] = {10, 200, 30};
};

TEST(Mapping, AnInsertedStageChangesExactlyItsPixels) {
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/projectors-2x2.toml");
    const WallFrame f = gradientFrame(1600, 1200);
    PaintStage paint;
    PresentOptions o;
    o.stages = {&paint};
    for (size_t s = 0; s < w.screens.size(); ++s) {
        const Image plain = presentScreen(w, s, f), staged = presentScreen(w, s, f, o);
        ASSERT_EQ(plain.rgb.size(), staged.rgb.size());
        for (int y = 0; y < plain.height; ++y)
            for (int x = 0; x < plain.width; ++x) {
                const bool painted = s == 1 && x >= 4 && x < 24 && y >= 2 && y < 12;
                const uint8_t* expected = painted ? paint.colour : plain.pixel(x, y);
                ASSERT_EQ(std::memcmp(staged.pixel(x, y), expected, 3), 0) << "screen " << s << " pixel " << x << "," << y;
            }
    }
    // The overlay is drawn after the stages: it covers what they painted.
    const Image one = textImage("1", 1);
    o.overlay = &one;
    paint.screen = 0;
    const Image first = presentScreen(w, 0, f, o);
    EXPECT_EQ(std::memcmp(first.pixel(kOverlayMargin + 3, kOverlayMargin + 2), one.pixel(3, 2), 3), 0);
    EXPECT_EQ(std::memcmp(first.pixel(4, 2), paint.colour, 3), 0);
}

TEST(Mapping, AFrameLargerThanTheWallOrWithUnlikeEyesIsRefused) {
    const WallConfig w = singleScreenWall(64, 32);
    EXPECT_THROW(presentScreen(w, 0, gradientFrame(65, 32)), std::invalid_argument);
    EXPECT_THROW(presentScreen(w, 0, gradientFrame(64, 33)), std::invalid_argument);
    WallFrame eyes = gradientFrame(64, 32);
    eyes.right = gradientFrame(32, 32).left;
    EXPECT_THROW(presentScreen(w, 0, eyes), std::invalid_argument);
    EXPECT_THROW(presentScreen(w, 0, WallFrame{}), std::invalid_argument);
}

// A frame rendered at a fraction of the wall's resolution (the scale control) is shown upscaled:
// exactly the bilinear resampling of tune's resizeBilinear, and the tile-owner view uses the
// frame's tiles (a wall pixel takes the tile of the frame pixel it scales to).
TEST(Mapping, ASmallerFrameIsShownUpscaled) {
    const WallConfig w = loadWallConfig(test::sourceDir() / "configs/wall/projectors-2x2.toml");
    WallFrame half = gradientFrame(800, 600);
    WallFrame full = half;
    full.left = resizeBilinear(half.left, 1600, 1200);
    for (size_t s = 0; s < w.screens.size(); ++s) EXPECT_EQ(presentScreen(w, s, half).rgb, presentScreen(w, s, full).rgb) << s;
    half.tileSize = 100;  // 8 x 6 tiles of the frame: 200 wall pixels each
    for (uint32_t t = 0; t < 48; ++t) half.tileOwners.push_back(t % 5);
    full.tileSize = 200;
    full.tileOwners = half.tileOwners;
    PresentOptions o;
    o.falseColour = true;
    for (size_t s = 0; s < w.screens.size(); ++s) EXPECT_EQ(presentScreen(w, s, half, o).rgb, presentScreen(w, s, full, o).rgb) << s;
}

}  // namespace
}  // namespace rtwall
