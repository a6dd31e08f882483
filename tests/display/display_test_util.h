// Helpers for the display tests (without the engine, unlike tests/test_util.h); scratch folders
// and written files are tests/scratch.h's.
#pragma once

#include "../scratch.h"

#include <rtwall/display.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace rtwall::test {

// The InputError a wall config gives (empty, and a test failure, if it loads).
// Whether a session's log (RunConfig::log into `lines`) has a line containing `text`.
inline bool logged(const std::vector<std::string>& lines, const std::string& text) {
    for (const std::string& l : lines)
        if (l.find(text) != std::string::npos) return true;
    return false;
}

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
