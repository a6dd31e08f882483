// GLX_NV_swap_group / GLX_NV_swap_barrier (WallConfig::swapGroup, swapBarrier): the windows of
// one PC swap together, and with a barrier the PCs of a genlocked wall too. Its own file: the
// GLX header (with GL/gl.h) must not meet the core-profile header of gl_presenter.cpp.
#pragma once

#include <string>
#include <vector>

struct GLFWwindow;

namespace rtwall::detail {

// Joins `windows` to swap group `group` (> 0) and, with barrier > 0, binds the group to that
// barrier, where the driver has the extension. Returns the one line that says what happened
// (joined, absent, refused); never throws.
std::string joinSwapGroup(const std::vector<GLFWwindow*>& windows, int group, int barrier);

}  // namespace rtwall::detail
