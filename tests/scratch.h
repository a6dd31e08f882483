// Where tests read and write: the source and data folders, scratch folders under the build tree,
// and written files. Free of the libraries, so every test program (the display's without the
// engine, too) uses the same ones.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

namespace rtwall::test {

inline std::filesystem::path dataDir() { return RTWALL_TEST_DATA_DIR; }
inline std::filesystem::path sourceDir() { return RTWALL_SOURCE_DIR; }

// The text of tests/data/scenes/NAME.toml: a small scene the tests share.
inline std::string sceneText(const std::string& name) {
    const std::filesystem::path file = dataDir() / "scenes" / (name + ".toml");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw std::runtime_error(file.string() + ": cannot read");
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// A fresh scratch directory `name-PID` under the build tree, for what a test program writes once
// per process (ctest runs the tests of one program in parallel processes).
inline std::filesystem::path processScratchDir(const std::string& name) {
    const std::filesystem::path d =
        std::filesystem::path(RTWALL_BINARY_DIR) / "test-scratch" / (name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    return d;
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

// Runs tools/mpcdi_testgen.py (issue 30's independent MPCDI writer) with `args`: a test failure
// naming the command when it fails.
inline void mpcdiTestgen(const std::string& args) {
    const std::string cmd = "python3 " + (sourceDir() / "tools" / "mpcdi_testgen.py").string() + " " + args;
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

inline std::filesystem::path writeFile(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

}  // namespace rtwall::test
