// RGB8 images and their PNG input/output. Lives in the lowest library (core) so that the display
// (which must not link the engine) and the engine's textures read and write images the same way.
#pragma once

#include <rtwall/input_error.h>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace rtwall {

struct Image {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;  // sRGB8, row-major, no padding
    uint8_t* pixel(int x, int y) { return rgb.data() + (size_t(y) * width + x) * 3; }
    const uint8_t* pixel(int x, int y) const { return rgb.data() + (size_t(y) * width + x) * 3; }
};

void writePng(const Image& image, const std::filesystem::path& file);  // throws InputError
Image readPng(const std::filesystem::path& file);                      // throws InputError
std::vector<uint8_t> encodePng(const Image& image);                    // the bytes writePng writes; throws InputError

}  // namespace rtwall
