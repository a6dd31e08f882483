// Helpers for the display tests (without the engine, unlike tests/test_util.h).
#pragma once

#include <rtwall/display.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace rtwall::test {

inline std::filesystem::path sourceDir() { return RTWALL_SOURCE_DIR; }

inline std::filesystem::path displayScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::filesystem::path dir = std::filesystem::path(RTWALL_BINARY_DIR) / "test-scratch" /
                                (std::string(info->test_suite_name()) + "." + info->name());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

inline std::filesystem::path writeText(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

// The InputError a wall config gives (empty, and a test failure, if it loads).
inline std::string wallError(const std::string& text, const std::string& name = "wall.toml") {
    try {
        parseWallConfig(text, name);
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an error for:\n" << text;
    return {};
}

}  // namespace rtwall::test
