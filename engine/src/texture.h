// Textures: colour patterns and alpha masks evaluated at an object-space position.
#pragma once

#include <rtwall/engine.h>
#include <rtwall/vec.h>

#include <memory>
#include <string>
#include <vector>

namespace rtwall {

// Linear RGB image for texturing, decoded once from PNG or JPEG.
struct TextureImage {
    int width = 0, height = 0;
    std::vector<float> rgb;  // linear, 3 per texel
    std::vector<float> alpha;  // [0, 1], 1 per texel; empty where the image has no alpha channel (opaque)
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
// Uv, Auto and Object fall back to PlanarXZ here (they need the mesh: see Texture::color).
void textureCoordinates(TextureMapping mapping, const Float3& objectPos, float scale, float& u, float& v);

// Whether a mapping reads the mesh's texture coordinates: Uv always, Auto where the mesh has them
// (textures, alpha masks and bumps alike).
inline bool readsMeshUVs(TextureMapping mapping, bool meshHasUVs) {
    return mapping == TextureMapping::Uv || (mapping == TextureMapping::Auto && meshHasUVs);
}

// A mesh's texture coordinates at barycentrics (u, v) of triangle `prim` (the mesh has UVs).
void meshUVAt(const TriangleMesh& mesh, uint32_t prim, float u, float v, float out[2]);

// The tangent frame of triangle `prim` from its texture coordinates: dP/du and dP/dv in object
// space, the derivatives of position along u and along v. False when the triangle's (u, v) are
// degenerate (zero area in texture space): there is no frame.
bool uvTangents(const TriangleMesh& mesh, uint32_t prim, Float3& dPdu, Float3& dPdv);

// The surface gradient (object space, in the triangle's plane) of a height field h(u, v) with
// derivatives dh/du, dh/dv: dh/du grad(u) + dh/dv grad(v), with grad(u), grad(v) the dual basis
// of dP/du, dP/dv in the plane.
Float3 uvSurfaceGradient(const Float3& dPdu, const Float3& dPdv, float dhdu, float dhdv);

class Texture {
public:
    // `base` is the material colour the pattern modulates (or replaces, for images).
    Texture(const TextureDesc& desc, const Color& base);
    // `uv`: the mesh's texture coordinates at the point, or null when the mesh has none (the
    // Uv mapping then reads (0, 0); scenes refuse that combination when they load).
    Color color(const Float3& objectPos, const float* uv) const;
    // A mask's value: the red channel, or with AlphaChannel::Alpha an image's alpha channel (1 for
    // an image without one and for the patterns, which have none).
    float alpha(const Float3& objectPos, const float* uv, AlphaChannel channel) const;
    bool active() const { return desc_.kind != TextureKind::None; }

private:
    // The (u, v) the pattern or image is looked up at, and the pattern's position p.
    void coordinates(const Float3& objectPos, const float* uv, float& u, float& v, Float3& p) const;

    TextureDesc desc_;
    Color base_;
    std::shared_ptr<const TextureImage> image_;
};

}  // namespace rtwall
