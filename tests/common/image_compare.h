// Bit-exact image comparison that says where two images first differ, so a failing test names
// a pixel instead of dumping two byte vectors.
#pragma once

#include <rtwall/image.h>

#include <cstddef>
#include <string>

namespace rtwall::test {

// Empty when a and b have the same size and the same bytes; otherwise the first difference:
// the sizes, or the first differing pixel (x, y) with both colours.
std::string imageDifference(const Image& a, const Image& b);

// How many bytes of a and b differ; images of different sizes count as wholly different (the
// larger byte count), so a test that expects no difference fails on a size mismatch too.
size_t differingBytes(const Image& a, const Image& b);

}  // namespace rtwall::test
