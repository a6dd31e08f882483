// A calibrated wall's blend on the CPU (ProjectorBlendStage::apply, issue 30): unit blends change
// no bit; on the curved example (tools/mpcdi_testgen.py, an independent writer) the three
// projectors' light on white sums to one across the screen, overlaps included; the arithmetic
// is the stated one (linear light, alpha's embedded gamma undone, beta as black level).
#include "scratch.h"

#include <rtwall/display.h>
#include <rtwall/mpcdi.h>

#include <gtest/gtest.h>

#include <fstream>

#include <cmath>
#include <cstdlib>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

double decode(uint8_t v) {
    const double s = v / 255.0;
    return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
}


Image filled(int w, int h, uint8_t v) {
    Image im;
    im.width = w;
    im.height = h;
    im.rgb.assign(size_t(w) * size_t(h) * 3, v);
    return im;
}

TEST(ProjectorBlend, WithoutMapsNoPixelChanges) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("identity " + (dir / "id.mpcdi").string() + " --buffer a=40x30");
    const WallConfig w = parseWallConfig("[wall]\nwidth = 40\nheight = 30\n[[screen]]\nname = \"A\"\nviewport = [0, 0, 40, 30]\n"
                                         "[warp]\nmpcdi = \"id.mpcdi\"\nbuffers = { a = \"A\" }\n",
                                         dir / "w.toml");
    const ProjectorBlendStage stage(w, readMpcdi(w.warp->mpcdi));
    EXPECT_FALSE(stage.blends(0));
    Image im = filled(40, 30, 0);
    for (size_t i = 0; i < im.rgb.size(); ++i) im.rgb[i] = uint8_t(i * 7);
    const Image before = im;
    stage.apply(w, 0, 0, im);
    EXPECT_EQ(im.rgb, before.rgb);
}

// The angle about the cylinder's axis (vertical through (0, y, 3), radius 3 m) of a surface point.
double angleOf(Float3 p) { return std::atan2(double(p.x), 3.0 - double(p.z)); }

TEST(ProjectorBlend, TheCurvedWallsProjectorsSumToOneOnWhite) {
    const fs::path dir = test::scratchDir();
    // 256 pixels a projector: an overlap ramp spans about 38, so interpolating between two
    // pixels' angles errs by under 1e-3 (smoothstep's curvature); alpha's 8 bits at gamma 2.2
    // and the output's 8 bits err by up to 0.0086 a projector: 0.02 for two.
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 256x32 --wall " + (dir / "c.toml").string());
    const WallConfig wall = loadWallConfig(dir / "c.toml");
    const MpcdiFile file = readMpcdi(wall.warp->mpcdi);
    const ProjectorBlendStage stage(wall, file);
    const int W = 256, H = 32, row = H / 2;
    // Each projector's middle row on white: (angle, linear light) for its pixels on the screen.
    std::vector<std::vector<std::pair<double, double>>> light(3);
    for (size_t p = 0; p < 3; ++p) {
        ASSERT_TRUE(stage.blends(p));
        Image white = filled(W, H, 255);
        stage.apply(wall, p, 0, white);
        const MpcdiWarp& warp = file.buffers[p].regions[0].warp;
        ASSERT_EQ(warp.width, W);
        for (int i = 0; i < W; ++i) {
            const Float3 s = warp.samples[size_t(row) * W + size_t(i)];
            if (std::isnan(s.x)) continue;
            light[p].emplace_back(angleOf(s), decode(white.pixel(i, row)[0]));
        }
        ASSERT_GT(light[p].size(), size_t(W) / 2);
    }
    // Projector q's light at angle a: linear between the two pixels around it, 0 outside.
    const auto at = [&](size_t q, double a) {
        const auto& l = light[q];
        for (size_t i = 0; i + 1 < l.size(); ++i)
            if (l[i].first <= a && a <= l[i + 1].first) {
                const double t = (a - l[i].first) / (l[i + 1].first - l[i].first);
                return l[i].second + t * (l[i + 1].second - l[i].second);
            }
        return 0.0;
    };
    size_t overlaps = 0;
    double worst = 0;
    for (size_t p = 0; p < 3; ++p)
        for (size_t k = 1; k + 1 < light[p].size(); ++k) {  // not the edge pixels: nothing to interpolate past them
            const double a = light[p][k].first;
            double sum = light[p][k].second, others = 0;
            for (size_t q = 0; q < 3; ++q)
                if (q != p) others += at(q, a);
            sum += others;
            overlaps += others > 0.01;
            worst = std::max(worst, std::abs(sum - 1.0));
            EXPECT_NEAR(sum, 1.0, 0.02) << "projector " << p << " pixel " << k << " at " << a << " rad";
        }
    EXPECT_GT(overlaps, 40u) << "the overlaps were not reached";
    std::printf("worst sum error %.4f over %zu overlap pixels\n", worst, overlaps);
}

// out = beta + (1 - beta) alpha in, in linear light, alpha = stored^gammaEmbedded: checked
// against the maps as read, pixel by pixel, on a grey image.
TEST(ProjectorBlend, TheArithmeticIsLinearLightWithTheEmbeddedGammaUndone) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 32x24 --wall " + (dir / "c.toml").string());
    const WallConfig wall = loadWallConfig(dir / "c.toml");
    const MpcdiFile file = readMpcdi(wall.warp->mpcdi);
    const ProjectorBlendStage stage(wall, file);
    for (size_t p = 0; p < 3; ++p) {
        Image grey = filled(32, 24, 180);
        stage.apply(wall, p, 0, grey);
        const MpcdiRegion& r = file.buffers[p].regions[0];
        ASSERT_TRUE(r.alpha && r.beta);
        EXPECT_EQ(r.alpha->gammaEmbedded, 2.2);
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 32; ++x) {
                const size_t k = size_t(y) * 32 + size_t(x);
                const double a = std::pow(double(r.alpha->values[k]), 2.2), b = r.beta->values[k];
                const double want = b + (1 - b) * a * decode(180);
                const double s = want <= 0.0031308 ? want * 12.92 : 1.055 * std::pow(want, 1 / 2.4) - 0.055;
                const int code = int(std::lround(std::clamp(s, 0.0, 1.0) * 255));
                if (a == 1.0 && b == 0.0) EXPECT_EQ(grey.pixel(x, y)[0], 180);
                else EXPECT_NEAR(grey.pixel(x, y)[0], code, 1) << p << " " << x << "," << y;
            }
    }
}

// RGB and 16-bit maps (tools/mpcdi_testgen.py depths): each channel blended by its own alpha and
// beta, a grey map's value used for all three; a 2D calibration of one 6x4 screen.
TEST(ProjectorBlend, RgbAndSixteenBitMapsBlendEachChannelByItsOwnValues) {
    const fs::path dir = test::scratchDir();
    for (const std::string depths : {"--alpha 1x16 --beta 3x8", "--alpha 3x16 --beta 1x16"}) {
        test::mpcdiTestgen("depths " + (dir / "d.mpcdi").string() + " " + depths);
        std::ofstream(dir / "d.toml") << "[wall]\nwidth = 6\nheight = 4\n[[screen]]\nname = \"s\"\nviewport = [0, 0, 6, 4]\n"
                                         "[warp]\nmpcdi = \"d.mpcdi\"\nbuffers = { p = \"s\" }\n";
        const WallConfig wall = loadWallConfig(dir / "d.toml");
        const MpcdiFile file = readMpcdi(wall.warp->mpcdi);
        const ProjectorBlendStage stage(wall, file);
        Image grey = filled(6, 4, 180);
        stage.apply(wall, 0, 0, grey);
        const MpcdiRegion& r = file.buffers[0].regions[0];
        ASSERT_TRUE(r.alpha && r.beta);
        size_t channelsApart = 0;
        for (int y = 0; y < 4; ++y)
            for (int x = 0; x < 6; ++x)
                for (int c = 0; c < 3; ++c) {
                    const size_t k = size_t(y) * 6 + size_t(x);
                    auto at = [&](const MpcdiMap& m) { return double(m.values[m.components == 3 ? 3 * k + size_t(c) : k]); };
                    const double a = at(*r.alpha), b = at(*r.beta);  // gammaEmbedded 1
                    const double want = b + (1 - b) * a * decode(180);
                    const double v = want <= 0.0031308 ? want * 12.92 : 1.055 * std::pow(want, 1 / 2.4) - 0.055;
                    EXPECT_NEAR(grey.pixel(x, y)[c], std::lround(std::clamp(v, 0.0, 1.0) * 255), 1) << depths << " " << x << "," << y << " " << c;
                    channelsApart += c > 0 && grey.pixel(x, y)[c] != grey.pixel(x, y)[0];
                }
        EXPECT_GT(channelsApart, 10u) << depths << ": the channels were blended alike";
    }
}

}  // namespace
}  // namespace rtwall
