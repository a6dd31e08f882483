// Texture images (engine/src/texture.cpp), white-box: the decoder behind image textures.
#include "shading_scenes.h"
#include "test_util.h"

#include "texture.h"

#include <gtest/gtest.h>

#include <turbojpeg.h>

#include <algorithm>
#include <cmath>

namespace rtwall {
namespace {

// PNG and JPEG decode to the same linear values (JPEG within its loss), and a truncated JPEG is
// an InputError naming the file.
TEST(ImageTexture, PngAndJpegLoad) {
    const auto dir = test::scratchDir();
    const std::string png = test::writeTestTexture(dir);
    const Image src = readPng(png);
    tjhandle tj = tjInitCompress();
    unsigned char* jpeg = nullptr;
    unsigned long size = 0;
    ASSERT_EQ(tjCompress2(tj, src.rgb.data(), src.width, src.width * 3, src.height, TJPF_RGB, &jpeg, &size, TJSAMP_444,
                          100, 0),
              0);
    test::writeFile(dir / "t.jpg", std::string(reinterpret_cast<const char*>(jpeg), size));
    test::writeFile(dir / "cut.jpg", std::string(reinterpret_cast<const char*>(jpeg), size / 3));
    tjFree(jpeg);
    tjDestroy(tj);
    const auto a = loadTextureImage(png), b = loadTextureImage((dir / "t.jpg").string());
    ASSERT_EQ(a->width, b->width);
    ASSERT_EQ(a->height, b->height);
    double worst = 0;
    for (size_t i = 0; i < a->rgb.size(); ++i) worst = std::max(worst, double(std::fabs(a->rgb[i] - b->rgb[i])));
    EXPECT_LT(worst, 0.1);
    EXPECT_NE(test::inputErrorOf([&] { loadTextureImage((dir / "cut.jpg").string()); }).find("cut.jpg"), std::string::npos);
}

}  // namespace
}  // namespace rtwall
