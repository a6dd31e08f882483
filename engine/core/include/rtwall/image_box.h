// A box-filtered picture of an image, `width` pixels across: every source pixel counts once, in
// the one cell that covers it (the operator console's thumbnail, issue 31). Kept as per-cell
// sums so that parts of one image held on several machines (display nodes, each with the pixels
// of its screens) add up to exactly the picture of the whole: the sums of disjoint pixel sets
// add, and the means are taken once, at the end.
#pragma once

#include <rtwall/image.h>

#include <cstdint>
#include <vector>

namespace rtwall {

// Cells of a srcWidth x srcHeight image: width = min(width, srcWidth) across, as many rows as
// keep the aspect (at least one). Cell x covers source columns [x * srcWidth / width,
// (x + 1) * srcWidth / width), rows alike: a partition, no pixel in two cells.
struct BoxGrid {
    int srcWidth = 0, srcHeight = 0, width = 0, height = 0;
    size_t cells() const { return size_t(width) * size_t(height); }
    bool operator==(const BoxGrid&) const = default;
};
// Throws std::invalid_argument for an empty source or width < 1, and where one cell would hold
// more than 2^24 pixels (its sums must fit 32 bits).
BoxGrid boxGrid(int srcWidth, int srcHeight, int width);

// Adds into `sums` (4 per cell: red, green, blue, pixels) every pixel of `image` (the grid's
// source size) whose entry in `owners` (one byte per pixel, row-major) is `me`; with owners
// null, every pixel.
void addBoxSums(const Image& image, const BoxGrid& grid, const uint8_t* owners, uint8_t me, uint32_t* sums);

// Each cell's mean, rounded to nearest; a cell without pixels is black.
Image boxMeans(const BoxGrid& grid, const uint32_t* sums);

// The whole image's picture: boxMeans of addBoxSums over every pixel.
Image boxPicture(const Image& image, int width);

}  // namespace rtwall
