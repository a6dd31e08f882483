// The shading demo scenes, for `rtwall gen` and `rtwall bench shading`.
#pragma once

#include <filesystem>
#include <string>

namespace rtwall::cli {

// Writes the demo `name` ("office" or "headlight") into `dir`; returns the scene file.
std::filesystem::path writeShadingDemo(const std::string& name, const std::filesystem::path& dir);

}  // namespace rtwall::cli
