// Internal to the speed commands (speed.cpp, tiles.cpp, simulate.cpp).
#pragma once

#include <rtwall/engine.h>
#include <rtwall/tune.h>

#include <toml++/toml.h>

#include <string>
#include <vector>

namespace rtwall::bench {

// "a,b,,c" -> {"a", "b", "c"}.
std::vector<std::string> splitList(const std::string& text);
// An ImageError as the JSON the speed commands print.
toml::table errorTable(const ImageError& e);
// The scene `name` (a builtin one of `triangles`) at width x height where those are given (not 0).
SceneDesc loadSized(const std::string& name, int64_t triangles, int width, int height);
// The scene camera `name` (the first when empty); an InputError naming the scene otherwise.
const CameraDesc& pickCamera(const SceneDesc& desc, const std::string& scene, const std::string& name);

}  // namespace rtwall::bench
