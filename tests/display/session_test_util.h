// What the wall session tests share (tests/test_util.h has the rest).
#pragma once

#include "image_compare.h"
#include "test_util.h"

#include <rtwall/wall.h>

#include <cstddef>

namespace rtwall::test {

// The bytes by which the session's last frame (its left eye) differs from the session's state
// rendered on one machine: 0 when the cluster showed exactly that state.
inline size_t bytesOffState(const WallSession& s) { return differingBytes(s.lastFrame().left, renderFirstCamera(s.scene())); }

}  // namespace rtwall::test
