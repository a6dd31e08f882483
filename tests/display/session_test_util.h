// What the wall session tests share (tests/test_util.h has the rest).
#pragma once

#include "image_compare.h"
#include "test_util.h"

#include <rtwall/wall.h>

#ifndef GLFW_INCLUDE_NONE
#define GLFW_INCLUDE_NONE
#endif
#include <GLFW/glfw3.h>  // key codes and modifiers, as the wall's windows report them

#include <cstddef>
#include <utility>

namespace rtwall::test {

// The bytes by which the session's last frame (its left eye) differs from the session's state
// rendered on one machine: 0 when the cluster showed exactly that state.
inline size_t bytesOffState(const WallSession& s) { return differingBytes(s.lastFrame().left, renderFirstCamera(s.scene())); }

// Input as the wall's windows report it, for WallSession::inject: a key pressed since the last
// poll, and a Ctrl+click at a wall pixel (the button down).
inline InputState keyPress(int key, int mods = 0) {
    InputState in;
    in.keysPressed = {key};
    in.modsPressed = {mods};
    return in;
}
inline InputState ctrlClick(std::pair<double, double> at) {
    InputState in;
    in.leftPressed = in.leftDown = true;
    in.clickMods = GLFW_MOD_CONTROL;
    in.wallX = at.first;
    in.wallY = at.second;
    return in;
}

}  // namespace rtwall::test
