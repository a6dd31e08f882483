#include <rtwall/image_box.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rtwall {

BoxGrid boxGrid(int srcWidth, int srcHeight, int width) {
    if (srcWidth < 1 || srcHeight < 1 || width < 1)
        throw std::invalid_argument("boxGrid: a " + std::to_string(width) + "-pixel picture of a " + std::to_string(srcWidth) +
                                    "x" + std::to_string(srcHeight) + " image");
    BoxGrid g{srcWidth, srcHeight, std::min(width, srcWidth), 0};
    g.height = std::max(1, int(int64_t(srcHeight) * g.width / srcWidth));
    // The largest cell: ceil(srcWidth / width) x ceil(srcHeight / height) pixels.
    const int64_t cw = (int64_t(srcWidth) + g.width - 1) / g.width, ch = (int64_t(srcHeight) + g.height - 1) / g.height;
    if (cw * ch > (int64_t(1) << 24))
        throw std::invalid_argument("boxGrid: cells of " + std::to_string(cw) + "x" + std::to_string(ch) +
                                    " pixels (at most 2^24 a cell)");
    return g;
}

void addBoxSums(const Image& image, const BoxGrid& g, const uint8_t* owners, uint8_t me, uint32_t* sums) {
    if (image.width != g.srcWidth || image.height != g.srcHeight)
        throw std::invalid_argument("addBoxSums: a " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                    " image for a grid of a " + std::to_string(g.srcWidth) + "x" +
                                    std::to_string(g.srcHeight) + " one");
    // Each column's cell: the partition of boxGrid, one division per column, not per pixel.
    std::vector<uint32_t> column(size_t(g.srcWidth));
    for (int x = 0, cell = 0; x < g.srcWidth; ++x) {
        while (int64_t(cell + 1) * g.srcWidth / g.width <= x) ++cell;
        column[size_t(x)] = uint32_t(cell);
    }
    for (int y = 0, row = 0; y < g.srcHeight; ++y) {
        while (int64_t(row + 1) * g.srcHeight / g.height <= y) ++row;
        uint32_t* line = sums + size_t(row) * size_t(g.width) * 4;
        const uint8_t* p = image.pixel(0, y);
        const uint8_t* own = owners ? owners + size_t(y) * size_t(g.srcWidth) : nullptr;
        for (int x = 0; x < g.srcWidth; ++x, p += 3) {
            if (own && own[x] != me) continue;
            uint32_t* s = line + size_t(column[size_t(x)]) * 4;
            s[0] += p[0];
            s[1] += p[1];
            s[2] += p[2];
            s[3] += 1;
        }
    }
}

Image boxMeans(const BoxGrid& g, const uint32_t* sums) {
    Image out;
    out.width = g.width;
    out.height = g.height;
    out.rgb.assign(g.cells() * 3, 0);
    for (size_t c = 0; c < g.cells(); ++c) {
        const uint32_t* s = sums + c * 4;
        if (s[3] == 0) continue;
        for (int k = 0; k < 3; ++k) out.rgb[c * 3 + size_t(k)] = uint8_t((uint64_t(s[k]) + s[3] / 2) / s[3]);
    }
    return out;
}

Image boxPicture(const Image& image, int width) {
    const BoxGrid g = boxGrid(image.width, image.height, width);
    std::vector<uint32_t> sums(g.cells() * 4, 0);
    addBoxSums(image, g, nullptr, 0, sums.data());
    return boxMeans(g, sums.data());
}

}  // namespace rtwall
