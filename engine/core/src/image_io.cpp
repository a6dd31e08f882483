// PNG input and output through libpng's simplified API.
#include <rtwall/image.h>

#include <png.h>

#include <cstdio>
#include <memory>

namespace rtwall {

void writePng(const Image& image, const std::filesystem::path& file) {
    if (!file.parent_path().empty()) {
        std::error_code ec;
        std::filesystem::create_directories(file.parent_path(), ec);
    }
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    png.width = png_uint_32(image.width);
    png.height = png_uint_32(image.height);
    png.format = PNG_FORMAT_RGB;
    // Written beside it and renamed into place: whoever reads the file (a test, a viewer watching
    // the frames folder) sees the whole picture or none, never a half-written one.
    std::filesystem::path part = file;
    part += ".part";
    if (!png_image_write_to_file(&png, part.c_str(), 0, image.rgb.data(), image.width * 3, nullptr)) {
        std::string why = png.message;
        png_image_free(&png);
        std::error_code ec;
        std::filesystem::remove(part, ec);
        throw InputError(file.string() + ": cannot write PNG: " + why);
    }
    std::error_code ec;
    std::filesystem::rename(part, file, ec);
    if (ec) {
        const std::string why = ec.message();
        std::filesystem::remove(part, ec);
        throw InputError(file.string() + ": cannot write PNG: " + why);
    }
}

std::vector<uint8_t> encodePng(const Image& image) {
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    png.width = png_uint_32(image.width);
    png.height = png_uint_32(image.height);
    png.format = PNG_FORMAT_RGB;
    png_alloc_size_t size = 0;
    // The first call sizes the buffer, the second fills it.
    if (!png_image_write_to_memory(&png, nullptr, &size, 0, image.rgb.data(), image.width * 3, nullptr) || size == 0) {
        std::string why = png.message;
        png_image_free(&png);
        throw InputError("cannot encode PNG: " + why);
    }
    std::vector<uint8_t> out(size);
    if (!png_image_write_to_memory(&png, out.data(), &size, 0, image.rgb.data(), image.width * 3, nullptr)) {
        std::string why = png.message;
        png_image_free(&png);
        throw InputError("cannot encode PNG: " + why);
    }
    out.resize(size);
    return out;
}

Image readPng(const std::filesystem::path& file) {
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&png, file.c_str()))
        throw InputError(file.string() + ": cannot read PNG: " + png.message);
    png.format = PNG_FORMAT_RGB;
    // Refuse absurd sizes before allocating (a 16k x 16k RGB image is already 768 MB).
    if (png.width == 0 || png.height == 0 || png.width > 16384 || png.height > 16384) {
        png_image_free(&png);
        throw InputError(file.string() + ": PNG size " + std::to_string(png.width) + "x" + std::to_string(png.height) +
                         " is out of range");
    }
    Image img;
    img.width = int(png.width);
    img.height = int(png.height);
    img.rgb.resize(PNG_IMAGE_SIZE(png));
    if (!png_image_finish_read(&png, nullptr, img.rgb.data(), 0, nullptr)) {
        std::string why = png.message;
        png_image_free(&png);
        throw InputError(file.string() + ": cannot read PNG: " + why);
    }
    return img;
}

}  // namespace rtwall
