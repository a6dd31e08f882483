// The feature codec (rtwall/feature_codec.h).
#include <rtwall/engine.h>
#include <rtwall/feature_codec.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rtwall {

namespace {

// Octahedral map of a unit vector (Cigolle et al., JCGT 2014) onto [0, 65535]^2; a zero (a
// miss) or non-finite vector maps to (0, 0), which decodes to a unit vector like any code.
void octEncode(const float* n, uint16_t& u, uint16_t& v) {
    const float l1 = std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]);
    if (!(l1 > 0.0f) || !std::isfinite(l1)) {
        u = v = 0;
        return;
    }
    float x = n[0] / l1, y = n[1] / l1;
    if (n[2] < 0.0f) {
        const float ox = x, oy = y;
        x = (1.0f - std::fabs(oy)) * (ox >= 0.0f ? 1.0f : -1.0f);
        y = (1.0f - std::fabs(ox)) * (oy >= 0.0f ? 1.0f : -1.0f);
    }
    auto code = [](float c) { return uint16_t(std::lround(std::clamp((c * 0.5f + 0.5f) * 65535.0f, 0.0f, 65535.0f))); };
    u = code(x);
    v = code(y);
}

void octDecode(uint16_t u, uint16_t v, float* n) {
    float x = float(u) / 65535.0f * 2.0f - 1.0f, y = float(v) / 65535.0f * 2.0f - 1.0f;
    const float z = 1.0f - std::fabs(x) - std::fabs(y);
    if (z < 0.0f) {
        const float ox = x, oy = y;
        x = (1.0f - std::fabs(oy)) * (ox >= 0.0f ? 1.0f : -1.0f);
        y = (1.0f - std::fabs(ox)) * (oy >= 0.0f ? 1.0f : -1.0f);
    }
    const float l = std::sqrt(x * x + y * y + z * z);
    n[0] = x / l, n[1] = y / l, n[2] = z / l;
}

// f(i, k) for each pixel of a width x height tile in rows of `stride`: i its index in the rows,
// k in the planar codes (row-major, no padding).
template <class F> void forEachPixel(int width, int height, size_t stride, F&& f) {
    size_t k = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x, ++k) f(size_t(y) * stride + size_t(x), k);
}

}  // namespace

void encodeFeatures(uint8_t bits, const float* albedo, const float* normal, const uint32_t* id, int width, int height,
                    size_t stride, uint8_t* out) {
    const size_t n = size_t(std::max(0, width)) * size_t(std::max(0, height));
    uint8_t* p = out;
    auto each = [&](auto&& f) { forEachPixel(width, height, stride, f); };
    if (bits & kFeatureAlbedo) {
        each([&](size_t i, size_t k) {
            uint8_t c[3];
            linearToSrgb8(albedo + 3 * i, 3, c);
            p[k] = c[0], p[n + k] = c[1], p[2 * n + k] = c[2];
        });
        p += 3 * n;
    }
    if (bits & kFeatureNormal) {
        each([&](size_t i, size_t k) {
            uint16_t u, v;
            octEncode(normal + 3 * i, u, v);
            p[k] = uint8_t(u), p[n + k] = uint8_t(u >> 8), p[2 * n + k] = uint8_t(v), p[3 * n + k] = uint8_t(v >> 8);
        });
        p += 4 * n;
    }
    if (bits & kFeatureId) {
        each([&](size_t i, size_t k) {
            for (int b = 0; b < 4; ++b) p[size_t(b) * n + k] = uint8_t(id[i] >> (8 * b));
        });
    }
}

void decodeFeatures(uint8_t bits, const uint8_t* in, size_t size, int width, int height, float* albedo, float* normal,
                    uint32_t* id, size_t stride) {
    const size_t n = size_t(std::max(0, width)) * size_t(std::max(0, height));
    if (size != encodedFeatureBytes(n, bits))
        throw std::invalid_argument("features of " + std::to_string(size) + " bytes for a " + std::to_string(width) + "x" +
                                    std::to_string(height) + " tile (" + std::to_string(encodedFeatureBytes(n, bits)) +
                                    " expected)");
    const uint8_t* p = in;
    auto each = [&](auto&& f) { forEachPixel(width, height, stride, f); };
    if (bits & kFeatureAlbedo) {
        each([&](size_t i, size_t k) {
            const uint8_t c[3] = {p[k], p[n + k], p[2 * n + k]};
            srgb8ToLinear(c, 3, albedo + 3 * i);
        });
        p += 3 * n;
    }
    if (bits & kFeatureNormal) {
        each([&](size_t i, size_t k) {
            octDecode(uint16_t(p[k] | p[n + k] << 8), uint16_t(p[2 * n + k] | p[3 * n + k] << 8), normal + 3 * i);
        });
        p += 4 * n;
    }
    if (bits & kFeatureId) {
        each([&](size_t i, size_t k) {
            id[i] = uint32_t(p[k]) | uint32_t(p[n + k]) << 8 | uint32_t(p[2 * n + k]) << 16 | uint32_t(p[3 * n + k]) << 24;
        });
    }
}

void quantiseFeatures(uint8_t bits, float* albedo, float* normal, size_t pixels) {
    for (size_t i = 0; i < pixels; ++i) {
        if (bits & kFeatureAlbedo) {
            uint8_t c[3];
            linearToSrgb8(albedo + 3 * i, 3, c);
            srgb8ToLinear(c, 3, albedo + 3 * i);
        }
        if (bits & kFeatureNormal) {
            uint16_t u, v;
            octEncode(normal + 3 * i, u, v);
            octDecode(u, v, normal + 3 * i);
        }
    }
}

}  // namespace rtwall
