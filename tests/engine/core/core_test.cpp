// The base types of rtwall_core (engine/core): PNG input/output, the strict TOML reader and the
// Float3 maths every library shares.
#include <rtwall/image.h>
#include <rtwall/input_error.h>
#include <rtwall/toml_reader.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace rtwall {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("rtwall_core_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    return dir / name;
}

std::string errorOf(const auto& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "no InputError";
}

TEST(CoreImage, PngRoundTripKeepsEveryByte) {
    Image a{3, 2, {}};
    for (int i = 0; i < 3 * 2 * 3; ++i) a.rgb.push_back(uint8_t(i * 13));
    const fs::path file = scratch("round.png");
    writePng(a, file);
    const Image b = readPng(file);
    EXPECT_EQ(b.width, 3);
    EXPECT_EQ(b.height, 2);
    EXPECT_EQ(b.rgb, a.rgb);
    EXPECT_EQ(b.pixel(2, 1)[2], a.pixel(2, 1)[2]);
}

TEST(CoreImage, ABadPngIsAnInputErrorNamingTheFile) {
    const fs::path file = scratch("bad.png");
    std::ofstream(file) << "not a png";
    EXPECT_NE(errorOf([&] { readPng(file); }).find(file.string()), std::string::npos);
}

TEST(CoreTomlReader, UnknownKeyIsReportedWithItsLine) {
    const fs::path file = scratch("typo.toml");
    std::ofstream(file) << "size = 2\n\ncolour = [1, 2, 3]\n";
    const toml::table t = toml_reader::parseFile(file);
    toml_reader::Reader r(file, t, "");
    EXPECT_EQ(r.number("size", 1, 0, 10), 2);
    EXPECT_EQ(errorOf([&] { r.finish(); }), file.string() + ":3: unknown key 'colour'");
}

TEST(CoreTomlReader, Vec3OutOfRangeAndWrongTypeAreErrors) {
    const fs::path file = scratch("vec.toml");
    std::ofstream(file) << "at = [1, 2, 3]\nbad = [1, \"x\", 3]\n";
    const toml::table t = toml_reader::parseFile(file);
    toml_reader::Reader r(file, t, "");
    EXPECT_EQ(r.vec3("at", {}), (Float3{1, 2, 3}));
    EXPECT_NE(errorOf([&] { r.vec3("bad", {}); }).find(file.string() + ":2: "), std::string::npos);
}

TEST(CoreVec, CrossDotAndNormalize) {
    const Float3 x{1, 0, 0}, y{0, 1, 0};
    EXPECT_EQ(cross(x, y), (Float3{0, 0, 1}));
    EXPECT_EQ(dot(x + y, y), 1.0f);
    EXPECT_EQ(length(Float3{3, 4, 0}), 5.0f);
    EXPECT_EQ(normalize(Float3{0, 0, 2}), (Float3{0, 0, 1}));
    EXPECT_EQ(normalize(Float3{}), Float3{});  // a zero vector stays zero rather than NaN
}

}  // namespace
}  // namespace rtwall
