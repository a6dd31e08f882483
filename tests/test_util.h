// Helpers shared by the test programs.
#pragma once

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

namespace rtwall::test {

inline std::filesystem::path dataDir() { return RTWALL_TEST_DATA_DIR; }
inline std::filesystem::path sourceDir() { return RTWALL_SOURCE_DIR; }

// A fresh scratch directory `name-PID` under the build tree, for what a test program writes once
// per process (ctest runs the tests of one program in parallel processes).
inline std::filesystem::path processScratchDir(const std::string& name) {
    const std::filesystem::path d =
        std::filesystem::path(RTWALL_BINARY_DIR) / "test-scratch" / (name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    return d;
}

// A camera at `position` looking at `lookAt`.
inline CameraDesc cameraAt(Float3 position, Float3 lookAt, float fovY = 45.0f, Float3 up = {0, 1, 0}) {
    return CameraDesc{.position = position, .lookAt = lookAt, .up = up, .fovY = fovY, .window = {}};
}

// The image size and tile size of `settings`.
inline void setImage(RenderSettings& settings, int width, int height, int tileSize) {
    settings.width = width;
    settings.height = height;
    settings.tileSize = tileSize;
}

// The |z| above which one of `tests` independent two-sided z-tests fails, for an overall level
// `alpha` (Sidak correction): the normal quantile by bisection on erfc (about 3.9 for 144 tests
// at 0.01).
inline double sidakThreshold(double alpha, size_t tests) {
    const double perTest = 1.0 - std::pow(1.0 - alpha, 1.0 / double(tests));
    double lo = 0, hi = 10;
    for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (std::erfc(mid / std::sqrt(2.0)) > perTest ? lo : hi) = mid;
    }
    return lo;
}

// configs/demo.toml at width x height; `supersample` 0 keeps the file's.
inline SceneDesc demoScene(int width, int height, int supersample = 0) {
    SceneDesc desc = loadSceneFile(sourceDir() / "configs/demo.toml");
    desc.settings.width = width;
    desc.settings.height = height;
    if (supersample > 0) desc.settings.supersample = supersample;
    return desc;
}

// The text of tests/data/scenes/NAME.toml: a small scene the tests share.
inline std::string sceneText(const std::string& name) {
    const std::filesystem::path file = dataDir() / "scenes" / (name + ".toml");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw std::runtime_error(file.string() + ": cannot read");
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// A fresh scratch directory per test, under the build tree.
inline std::filesystem::path scratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::filesystem::path dir = std::filesystem::path(RTWALL_BINARY_DIR) / "test-scratch" /
                                (std::string(info->test_suite_name()) + "." + info->name());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

inline std::filesystem::path writeFile(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

// Runs f, expects an InputError, returns its message.
template <class F> std::string inputErrorOf(F&& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an InputError";
    return {};
}

}  // namespace rtwall::test
