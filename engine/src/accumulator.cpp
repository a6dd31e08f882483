#include "shading.h"

#include <rtwall/engine.h>

namespace rtwall {

void Accumulator::add(const Image& frame) {
    if (frame.width != width_ || frame.height != height_ || frames_ == 0) {
        width_ = frame.width;
        height_ = frame.height;
        sum_.assign(frame.rgb.size(), 0.0);
        frames_ = 0;
    }
    for (size_t i = 0; i < frame.rgb.size(); ++i) sum_[i] += double(srgb8ToLinear(frame.rgb[i]));
    ++frames_;
}

Image Accumulator::resolve() const {
    Image img;
    img.width = width_;
    img.height = height_;
    img.rgb.resize(sum_.size());
    const double inv = frames_ > 0 ? 1.0 / frames_ : 0.0;
    for (size_t i = 0; i < sum_.size(); ++i) img.rgb[i] = linearToSrgb8(float(sum_[i] * inv));
    return img;
}

}  // namespace rtwall
