// Textures: colour patterns and alpha masks evaluated at an object-space position.
#pragma once

#include "vec.h"

#include <rtwall/engine.h>

#include <memory>
#include <string>
#include <vector>

namespace rtwall {

// Linear RGB image for texturing, decoded once from PNG or JPEG.
struct TextureImage {
    int width = 0, height = 0;
    std::vector<float> rgb;  // linear, 3 per texel
};

// Reads a PNG or JPEG (chosen by content, not extension). Throws InputError "file: what".
std::shared_ptr<const TextureImage> loadTextureImage(const std::string& file);

// Improved Perlin noise (fixed permutation, so every machine gets the same pattern), in [-1, 1].
float perlinNoise(const Float3& p);
// Sum of |noise| over octaves: the classic turbulence for marble and bumps.
float turbulence(const Float3& p, int octaves);
// The same with the analytic gradient (for bump mapping: one evaluation instead of six for
// central differences). Where |noise| has its kink the gradient is that of the side the
// noise's sign picks.
float perlinNoiseGrad(const Float3& p, Float3& gradient);
float turbulenceGrad(const Float3& p, int octaves, Float3& gradient);

// Texture coordinates of an object-space position for a mapping (before wrapping into [0, 1)):
// planar projections divide by the scale; spherical and cylindrical are around the object-space
// origin with y as the axis, u in turns from +z towards +x, v from the -y pole (spherical, in
// half turns) or along y in object units (cylindrical); both divided by the scale.
void textureCoordinates(TextureMapping mapping, const Float3& objectPos, float scale, float& u, float& v);

class Texture {
public:
    // `base` is the material colour the pattern modulates (or replaces, for images).
    Texture(const TextureDesc& desc, const Color& base);
    Color color(const Float3& objectPos) const;
    float alpha(const Float3& objectPos) const { return color(objectPos).x; }  // masks use the red channel
    bool active() const { return desc_.kind != TextureKind::None; }

private:
    TextureDesc desc_;
    Color base_;
    std::shared_ptr<const TextureImage> image_;
};

}  // namespace rtwall
