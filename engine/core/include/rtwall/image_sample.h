// Sampling an 8-bit image between its pixels, as a GL texture sampler does: the post-warp of
// issue 30 (rtwall/frame.h's postWarp and the wall's PostWarpStage) resamples with it.
#pragma once

#include <rtwall/image.h>

#include <cstdint>

namespace rtwall {

// The image at (x, y) in its pixels (pixel centres at +0.5): bilinear between pixel centres and
// clamped at the edges (GL_LINEAR with GL_CLAMP_TO_EDGE), rounded to 8 bits. False, and `out`
// untouched, where (x, y) lies off the image.
bool sampleBilinear(const Image& image, double x, double y, uint8_t out[3]);

}  // namespace rtwall
