// The box-filtered picture (rtwall/image_box.h): each cell the rounded mean of exactly the
// pixels it covers, and the sums of an image split between owners add up to the whole's picture
// bit for bit (display nodes each sum their screens' pixels; the master adds them, issue 31).
#include <rtwall/image_box.h>

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

namespace rtwall {
namespace {

Image noise(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    Image im;
    im.width = w;
    im.height = h;
    im.rgb.resize(size_t(w) * h * 3);
    for (uint8_t& b : im.rgb) b = uint8_t(rng());
    return im;
}

// The cell's pixels by its own bounds, summed directly (the definition, not the column tables).
Image byDefinition(const Image& im, int width) {
    const BoxGrid g = boxGrid(im.width, im.height, width);
    Image out;
    out.width = g.width;
    out.height = g.height;
    out.rgb.resize(g.cells() * 3);
    for (int y = 0; y < g.height; ++y)
        for (int x = 0; x < g.width; ++x) {
            const int x0 = int(int64_t(x) * im.width / g.width), x1 = int(int64_t(x + 1) * im.width / g.width);
            const int y0 = int(int64_t(y) * im.height / g.height), y1 = int(int64_t(y + 1) * im.height / g.height);
            uint64_t s[3] = {0, 0, 0}, n = 0;
            for (int sy = y0; sy < y1; ++sy)
                for (int sx = x0; sx < x1; ++sx, ++n)
                    for (int c = 0; c < 3; ++c) s[c] += im.pixel(sx, sy)[c];
            EXPECT_GT(n, 0u);
            for (int c = 0; c < 3; ++c) out.pixel(x, y)[c] = uint8_t((s[c] + n / 2) / n);
        }
    return out;
}

TEST(ImageBox, EachCellIsTheRoundedMeanOfThePixelsItCovers) {
    for (const auto& [w, h, width] : {std::tuple{37, 23, 5}, {1600, 1200, 320}, {101, 7, 100}, {8, 8, 8}, {640, 480, 1000}, {3, 500, 2}}) {
        const Image im = noise(w, h, uint32_t(w * 31 + width));
        const Image pic = boxPicture(im, width);
        EXPECT_EQ(pic.width, std::min(width, w));
        EXPECT_EQ(pic.height, std::max(1, int(int64_t(h) * pic.width / w)));
        EXPECT_EQ(pic.rgb, byDefinition(im, width).rgb) << w << "x" << h << " at " << width;
    }
    // Full width: the picture is the image.
    const Image im = noise(64, 48, 7);
    EXPECT_EQ(boxPicture(im, 64).rgb, im.rgb);
}

TEST(ImageBox, SumsOfDisjointOwnersAddUpToTheWholePicture) {
    const Image im = noise(200, 150, 3);
    std::mt19937 rng(11);
    std::vector<uint8_t> owners(size_t(im.width) * im.height);
    for (uint8_t& o : owners) o = uint8_t(rng() % 4);  // 3: nobody's pixel
    const BoxGrid g = boxGrid(im.width, im.height, 33);
    std::vector<uint32_t> sums(g.cells() * 4, 0), all(g.cells() * 4, 0);
    for (uint8_t me = 0; me < 3; ++me) addBoxSums(im, g, owners.data(), me, sums.data());
    // Nobody's pixels are left out: the same as the picture of the owned pixels only.
    addBoxSums(im, g, owners.data(), 3, all.data());
    uint64_t owned = 0, unowned = 0;
    for (size_t c = 0; c < g.cells(); ++c) owned += sums[c * 4 + 3], unowned += all[c * 4 + 3];
    EXPECT_EQ(owned + unowned, uint64_t(im.width) * im.height);
    for (size_t i = 0; i < all.size(); ++i) all[i] += sums[i];
    EXPECT_EQ(boxMeans(g, all.data()).rgb, boxPicture(im, 33).rgb);
    // A cell none of whose pixels are owned is black.
    std::vector<uint32_t> none(g.cells() * 4, 0);
    const Image black = boxMeans(g, none.data());
    EXPECT_EQ(black.rgb, std::vector<uint8_t>(g.cells() * 3, 0));
}

TEST(ImageBox, RefusesEmptyImagesAndCellsTooLargeToSum) {
    EXPECT_THROW(boxGrid(0, 10, 5), std::invalid_argument);
    EXPECT_THROW(boxGrid(10, 10, 0), std::invalid_argument);
    EXPECT_THROW(boxGrid(16384, 16384, 1), std::invalid_argument);  // 2^28 pixels in one cell
    EXPECT_NO_THROW(boxGrid(4096, 4096, 1));                        // 2^24: the sums still fit
    const Image im = noise(10, 10, 1);
    std::vector<uint32_t> sums(100 * 4);
    EXPECT_THROW(addBoxSums(im, boxGrid(11, 10, 5), nullptr, 0, sums.data()), std::invalid_argument);
}

}  // namespace
}  // namespace rtwall
