// Bit-exact image comparison that says where two images first differ, so a failing test names
// a pixel instead of dumping two byte vectors.
#pragma once

#include <rtwall/image.h>

#include <string>

namespace rtwall::test {

// Empty when a and b have the same size and the same bytes; otherwise the first difference:
// the sizes, or the first differing pixel (x, y) with both colours.
std::string imageDifference(const Image& a, const Image& b);

}  // namespace rtwall::test
