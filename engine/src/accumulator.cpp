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

void Accumulator::addLinear(const float* rgb, int width, int height) {
    const size_t n = size_t(width) * size_t(height) * 3;
    if (width != width_ || height != height_ || frames_ == 0) {
        width_ = width;
        height_ = height;
        sum_.assign(n, 0.0);
        frames_ = 0;
    }
    // Row-sized chunks through the bulk conversions: no allocation, no per-value library call.
    uint16_t half[1024];
    float rounded[1024];
    for (size_t i = 0; i < n; i += 1024) {
        const size_t m = std::min<size_t>(1024, n - i);
        halfFromFloat(rgb + i, m, half);
        floatFromHalf(half, m, rounded);
        for (size_t k = 0; k < m; ++k) sum_[i + k] += double(rounded[k]);
    }
    ++frames_;
}

void linearToSrgb8(const float* linear, size_t count, uint8_t* out) {
    for (size_t i = 0; i < count; ++i) out[i] = linearToSrgb8(linear[i]);
}

void srgb8ToLinear(const uint8_t* srgb, size_t count, float* out) {
    for (size_t i = 0; i < count; ++i) out[i] = srgb8ToLinear(srgb[i]);
}

bool samplesRandomly(const SceneDesc& scene) {
    for (const Light& l : scene.lights)
        if (l.type == LightType::Area) return true;  // a random point on the light per shading point
    std::vector<bool> used(scene.materials.size(), false);
    for (const InstanceDesc& in : scene.instances)
        if (in.material < used.size()) used[in.material] = true;
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        const Material& m = scene.materials[i];
        if (!used[i]) continue;
        if (m.type == MaterialType::Metal && m.roughness > 0.0f) return true;  // a sampled glossy lobe
        if (m.type == MaterialType::Volume) return true;                        // a jittered first step
        if (m.alphaMode == AlphaMode::Hashed && (m.alpha.kind != TextureKind::None || m.opacity < 1.0f))
            return true;  // a coin per ray and hit: frames of jittered rays average to the blend
    }
    return false;
}

bool rendersStochastically(const RenderSettings& s, bool randomContent) {
    if (s.view != ViewMode::Shaded || s.shading != ShadingMode::Full) return false;
    return s.gi || randomContent;
}

bool rendersStochastically(const SceneDesc& scene) {
    return rendersStochastically(scene.settings, samplesRandomly(scene));
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
