// The post-warp on the screens (PostWarpStage, issue 30's comparison mode) on the CPU: a 2D
// identity calibration gives every screen's pixels back, a whole-pixel shift shifts them
// exactly (black past the edge), and 3D points on the screen's own frame give them back too,
// from any eye.
#include "scratch.h"

#include <rtwall/display.h>
#include <rtwall/mpcdi.h>

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

Image pattern(int w, int h) {
    Image im;
    im.width = w;
    im.height = h;
    im.rgb.resize(size_t(w) * size_t(h) * 3);
    for (size_t i = 0; i < im.rgb.size(); ++i) im.rgb[i] = uint8_t((i * 37) ^ (i >> 5));
    return im;
}

WallConfig twoScreens(const fs::path& dir, const std::string& mpcdi) {
    return parseWallConfig("[wall]\nwidth = 80\nheight = 30\n[[screen]]\nname = \"A\"\nviewport = [0, 0, 40, 30]\n"
                           "[[screen]]\nname = \"B\"\nviewport = [40, 0, 40, 30]\n"
                           "[warp]\nmpcdi = \"" + mpcdi + "\"\nbuffers = { a = \"A\", b = \"B\" }\nmode = \"post\"\n",
                           dir / "w.toml");
}

TEST(PostWarpStage, An2dIdentityGivesThePixelsBackAndAShiftShiftsThem) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("identity " + (dir / "id.mpcdi").string() + " --buffer a=40x30 --buffer b=40x30");
    test::mpcdiTestgen("identity " + (dir / "s.mpcdi").string() + " --buffer a=40x30 --buffer b=40x30 --shift 3,-2");
    const Image flat = pattern(40, 30);
    {
        const WallConfig w = twoScreens(dir, "id.mpcdi");
        PostWarpStage stage(w, readMpcdi(w.warp->mpcdi));
        for (size_t s = 0; s < 2; ++s) {
            Image im = flat;
            stage.apply(w, s, 0, im);
            EXPECT_EQ(im.rgb, flat.rgb) << "screen " << s;
        }
    }
    const WallConfig w = twoScreens(dir, "s.mpcdi");
    PostWarpStage stage(w, readMpcdi(w.warp->mpcdi));
    Image im = flat;
    stage.apply(w, 1, 0, im);
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x) {
            if (x + 3 < 40 && y - 2 >= 0) {
                EXPECT_EQ(std::memcmp(im.pixel(x, y), flat.pixel(x + 3, y - 2), 3), 0) << x << "," << y;
            } else if (x + 3 > 40 || y - 2 < -1) {  // the centre looks past the screen's edge
                EXPECT_EQ(im.pixel(x, y)[0] + im.pixel(x, y)[1] + im.pixel(x, y)[2], 0) << x << "," << y;
            }
        }
}

// A 3D calibration whose points lie on the screen's frame at its pixel centres: what the eye
// sees through them is the flat screen itself, from any eye.
TEST(PostWarpStage, SurfacePointsOnTheFrameGiveThePixelsBackFromAnyEye) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("identity " + (dir / "id.mpcdi").string() + " --buffer a=40x30 --buffer b=40x30");
    WallConfig w = twoScreens(dir, "id.mpcdi");
    MpcdiFile f = readMpcdi(w.warp->mpcdi);
    f.profile = MpcdiProfile::Advanced3d;
    for (size_t b = 0; b < 2; ++b) {
        const EyeWindow frame = screenFrame(w, b);
        MpcdiWarp& g = f.buffers[b].regions.at(0).warp;
        ASSERT_EQ(g.width, 40);
        for (int j = 0; j < g.height; ++j)
            for (int i = 0; i < g.width; ++i)
                g.samples[size_t(j) * 40 + size_t(i)] =
                    frame.lowerLeft + frame.right * ((i + 0.5f) / 40.0f) + frame.up * (1.0f - (j + 0.5f) / 30.0f);
        g.metresPerUnit = 1;
    }
    PostWarpStage stage(w, f);
    const Image flat = pattern(40, 30);
    for (const Float3 eye : {Float3{0, 0, 2}, Float3{-1.3f, 0.4f, 1.1f}}) {
        stage.setEyes(eye, eye);
        for (size_t s = 0; s < 2; ++s) {
            Image im = flat;
            stage.apply(w, s, 0, im);
            size_t differ = 0;
            for (size_t i = 0; i < im.rgb.size(); ++i) differ += std::abs(int(im.rgb[i]) - int(flat.rgb[i])) > 1;
            EXPECT_EQ(differ, 0u) << "screen " << s;
        }
    }
}

// A side-by-side screen holds both eyes' images, each half its own pane: a whole-pixel shift
// shifts each half within itself, and a half's pixels that look past its edge are black, never
// the other eye's pixels.
TEST(PostWarpStage, ASideBySideScreenWarpsEachEyesHalfAlone) {
    const fs::path dir = test::scratchDir();
    // The buffer has the screen's 80x30 output pixels over a 40x30 viewport: a shift of 2
    // buffer columns is one wall (and half-screen) column.
    test::mpcdiTestgen("identity " + (dir / "s.mpcdi").string() + " --buffer a=80x30 --shift 2,-2");
    const WallConfig w = parseWallConfig("[wall]\nwidth = 40\nheight = 30\n[stereo]\nmode = \"side_by_side\"\n"
                                         "[[screen]]\nname = \"A\"\nviewport = [0, 0, 40, 30]\nresolution = [80, 30]\n"
                                         "[warp]\nmpcdi = \"s.mpcdi\"\nbuffers = { a = \"A\" }\nmode = \"post\"\n",
                                         dir / "w.toml");
    ASSERT_TRUE(checkWarp(w).size() <= 1u);  // the shifted edge looks past the frame: said, not fatal here
    PostWarpStage stage(w, readMpcdi(w.warp->mpcdi));
    const Image flat = pattern(80, 30);
    Image im = flat;
    stage.apply(w, 0, 0, im);
    for (int half = 0; half < 2; ++half)
        for (int y = 0; y < 30; ++y)
            for (int x = 0; x < 40; ++x) {
                const uint8_t* o = im.pixel(40 * half + x, y);
                if (x + 1 < 40 && y - 2 >= 0) {
                    EXPECT_EQ(std::memcmp(o, flat.pixel(40 * half + x + 1, y - 2), 3), 0) << half << ": " << x << "," << y;
                } else if (x + 1 > 40 || y - 2 < -1) {  // past its half's edge: black, not the other eye
                    EXPECT_EQ(o[0] + o[1] + o[2], 0) << half << ": " << x << "," << y;
                }
            }
    EXPECT_NE(im.rgb, flat.rgb);
}

// A quad-buffered screen's two buffers are warped each from its own eye: on the curved
// calibration each eye's buffer is what a mono wall shows for a viewer at that eye, to the bit,
// and the two differ.
TEST(PostWarpStage, EachBufferOfAQuadBufferedScreenIsWarpedFromItsEye) {
    const fs::path dir = test::scratchDir();
    test::mpcdiTestgen("cylinder " + (dir / "c.mpcdi").string() + " --res 64x48 --wall " + (dir / "c.toml").string());
    std::ifstream in(dir / "c.toml");
    std::string text((std::istreambuf_iterator<char>(in)), {});
    const WallConfig mono = parseWallConfig(text, dir / "c.toml");
    const size_t at = text.find("mode = \"none\"");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, 13, "mode = \"quad_buffer\"");
    const WallConfig quad = parseWallConfig(text, dir / "q.toml");
    const MpcdiFile file = readMpcdi(mono.warp->mpcdi);
    PostWarpStage stereo(quad, file), one(mono, file);
    const Float3 left{-0.3f, 0.1f, 2.6f}, right{0.35f, 0.0f, 2.7f};
    stereo.setEyes(left, right);
    const Image flat = pattern(64, 48);
    for (size_t s = 0; s < 3; ++s) {
        Image l = flat, r = flat;
        stereo.apply(quad, s, 0, l);
        stereo.apply(quad, s, 1, r);
        EXPECT_NE(l.rgb, r.rgb) << "screen " << s;
        for (int eye = 0; eye < 2; ++eye) {
            const Float3 e = eye == 0 ? left : right;
            one.setEyes(e, e);
            Image m = flat;
            one.apply(mono, s, 0, m);
            EXPECT_EQ(m.rgb, (eye == 0 ? l : r).rgb) << "screen " << s << ", eye " << eye;
        }
    }
}

}  // namespace
}  // namespace rtwall
