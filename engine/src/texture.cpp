#include "texture.h"

#include "scene_files.h"
#include "shading.h"

#include <rtwall/image.h>

#include <png.h>
#include <turbojpeg.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <numbers>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rtwall {

namespace {

std::shared_ptr<TextureImage> fromSrgb8(int width, int height, const uint8_t* rgb) {
    auto img = std::make_shared<TextureImage>();
    img->width = width;
    img->height = height;
    img->rgb.resize(size_t(width) * height * 3);
    for (size_t i = 0; i < img->rgb.size(); ++i) img->rgb[i] = srgb8ToLinear(rgb[i]);
    return img;
}

std::shared_ptr<const TextureImage> loadJpeg(const std::string& file, const std::vector<unsigned char>& bytes) {
    tjhandle tj = tjInitDecompress();
    if (!tj) throw InputError(file + ": cannot start the JPEG decoder");
    int w = 0, h = 0, sub = 0, cs = 0;
    if (tjDecompressHeader3(tj, bytes.data(), (unsigned long)bytes.size(), &w, &h, &sub, &cs) != 0 || w <= 0 ||
        h <= 0 || w > 16384 || h > 16384) {
        const std::string why = tjGetErrorStr2(tj);
        tjDestroy(tj);
        throw InputError(file + ": not a readable JPEG (" + why + ")");
    }
    std::vector<uint8_t> rgb(size_t(w) * h * 3);
    if (tjDecompress2(tj, bytes.data(), (unsigned long)bytes.size(), rgb.data(), w, w * 3, h, TJPF_RGB, 0) != 0) {
        const std::string why = tjGetErrorStr2(tj);
        tjDestroy(tj);
        throw InputError(file + ": corrupt JPEG (" + why + ")");
    }
    tjDestroy(tj);
    return fromSrgb8(w, h, rgb.data());
}

std::shared_ptr<const TextureImage> loadPng(const std::string& file, const std::vector<unsigned char>& bytes) {
    // libpng's simplified API, as rtwall::readPng uses for files.
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&png, bytes.data(), bytes.size()))
        throw InputError(file + ": cannot read PNG: " + png.message);
    // With an alpha channel where the file has one (8-bit RGBA from libpng's simplified API is not
    // premultiplied): glTF's MASK and BLEND materials read it.
    const bool hasAlpha = (png.format & PNG_FORMAT_FLAG_ALPHA) != 0;
    png.format = hasAlpha ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
    if (png.width == 0 || png.height == 0 || png.width > 16384 || png.height > 16384) {
        png_image_free(&png);
        throw InputError(file + ": PNG size " + std::to_string(png.width) + "x" + std::to_string(png.height) +
                         " is out of range");
    }
    std::vector<uint8_t> pixels(PNG_IMAGE_SIZE(png));
    if (!png_image_finish_read(&png, nullptr, pixels.data(), 0, nullptr)) {
        const std::string why = png.message;
        png_image_free(&png);
        throw InputError(file + ": cannot read PNG: " + why);
    }
    if (!hasAlpha) return fromSrgb8(int(png.width), int(png.height), pixels.data());
    const size_t texels = size_t(png.width) * png.height;
    std::vector<uint8_t> rgb(3 * texels);
    std::vector<float> alpha(texels);
    for (size_t i = 0; i < texels; ++i) {
        std::copy_n(pixels.data() + 4 * i, 3, rgb.data() + 3 * i);
        alpha[i] = pixels[4 * i + 3] / 255.0f;  // alpha is linear
    }
    auto img = fromSrgb8(int(png.width), int(png.height), rgb.data());
    img->alpha = std::move(alpha);
    return img;
}

// Ken Perlin's reference permutation.
constexpr std::array<uint8_t, 256> kPerm = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103, 30,  69,  142,
    8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,  197, 62,  94,  252, 219, 203,
    117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174, 20,  125, 136, 171, 168, 68,  175, 74,  165,
    71,  134, 139, 48,  27,  166, 77,  146, 158, 231, 83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,
    55,  46,  245, 40,  244, 102, 143, 54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,
    18,  169, 200, 196, 135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250,
    124, 123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,  182, 189,
    28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,
    129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,
    242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,  51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,
    181, 199, 106, 157, 184, 84,  204, 176, 115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114,
    67,  29,  24,  72,  243, 141, 128, 195, 78,  66,  215, 61,  156, 180};

inline int perm(int i) { return kPerm[i & 255]; }
inline float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
inline float lerp(float t, float a, float b) { return a + t * (b - a); }
inline float grad(int hash, float x, float y, float z) {
    const int h = hash & 15;
    const float u = h < 8 ? x : y, v = h < 4 ? y : (h == 12 || h == 14 ? x : z);
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

// The lattice cell of p: p's offset in it (x, y, z), the fades of that offset (u, v, w), and the
// hashes of its corners, as the noise and its gradient both start.
struct NoiseCell {
    float x, y, z, u, v, w;
    int AA, AB, BA, BB;
};
inline NoiseCell noiseCell(const Float3& p) {
    const float fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
    const int X = int(int64_t(fx) & 255), Y = int(int64_t(fy) & 255), Z = int(int64_t(fz) & 255);
    const float x = p.x - fx, y = p.y - fy, z = p.z - fz;
    const int A = perm(X) + Y, B = perm(X + 1) + Y;
    return {x, y, z, fade(x), fade(y), fade(z), perm(A) + Z, perm(A + 1) + Z, perm(B) + Z, perm(B + 1) + Z};
}

Color mix(const Color& a, const Color& b, float t) { return a * (1.0f - t) + b * t; }

}  // namespace

std::shared_ptr<const TextureImage> loadTextureImage(const std::string& file) {
    // Decoded from memory whether the bytes come from the disk or from the scene's files (a
    // render client's copy of the master's file), so both give the same texels.
    const std::shared_ptr<const std::vector<uint8_t>> data = readSceneFile(file, "texture");
    const std::vector<unsigned char>& bytes = *data;
    if (bytes.size() >= 8 && bytes[0] == 0x89 && bytes[1] == 'P' && bytes[2] == 'N' && bytes[3] == 'G') return loadPng(file, bytes);
    if (bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF) return loadJpeg(file, bytes);
    throw InputError(file + ": a texture must be a PNG or a JPEG image");
}

float perlinNoise(const Float3& p) {
    const auto [x, y, z, u, v, w, AA, AB, BA, BB] = noiseCell(p);
    return lerp(w,
                lerp(v, lerp(u, grad(perm(AA), x, y, z), grad(perm(BA), x - 1, y, z)),
                     lerp(u, grad(perm(AB), x, y - 1, z), grad(perm(BB), x - 1, y - 1, z))),
                lerp(v, lerp(u, grad(perm(AA + 1), x, y, z - 1), grad(perm(BA + 1), x - 1, y, z - 1)),
                     lerp(u, grad(perm(AB + 1), x, y - 1, z - 1), grad(perm(BB + 1), x - 1, y - 1, z - 1))));
}

namespace {
// The gradient vectors that grad(hash, ...) takes the dot product with, one per hash & 15, as a
// table: the branchy construction per corner was most of perlinNoiseGrad's time, and bump
// mapping calls it eight times per octave at every hit on a bumped surface.
struct GradTable {
    Float3 g[16];
    constexpr GradTable() : g{} {
        for (int h = 0; h < 16; ++h) {
            float c[3] = {0, 0, 0};
            const int ui = h < 8 ? 0 : 1, vi = h < 4 ? 1 : (h == 12 || h == 14 ? 0 : 2);
            c[ui] += (h & 1) ? -1.0f : 1.0f;
            c[vi] += (h & 2) ? -1.0f : 1.0f;
            g[h] = Float3{c[0], c[1], c[2]};
        }
    }
};
constexpr GradTable kGradTable;
inline const Float3& gradVector(int hash) { return kGradTable.g[hash & 15]; }
inline float fadeDerivative(float t) { return 30.0f * t * t * (t * (t - 2.0f) + 1.0f); }
}  // namespace

float perlinNoiseGrad(const Float3& p, Float3& gradient) {
    const auto [x, y, z, u, v, w, AA, AB, BA, BB] = noiseCell(p);
    // Corner gradients g and their dot products n with the offset to the corner; the noise is
    // the trilinear blend n = k0 + k1 u + k2 v + k3 w + k4 uv + k5 vw + k6 wu + k7 uvw.
    const Float3 ga = gradVector(perm(AA)), gb = gradVector(perm(BA)), gc = gradVector(perm(AB)),
                 gd = gradVector(perm(BB)), ge = gradVector(perm(AA + 1)), gf = gradVector(perm(BA + 1)),
                 gg = gradVector(perm(AB + 1)), gh = gradVector(perm(BB + 1));
    const float a = dot(ga, {x, y, z}), b = dot(gb, {x - 1, y, z}), c = dot(gc, {x, y - 1, z}),
                d = dot(gd, {x - 1, y - 1, z}), e = dot(ge, {x, y, z - 1}), f = dot(gf, {x - 1, y, z - 1}),
                g = dot(gg, {x, y - 1, z - 1}), h = dot(gh, {x - 1, y - 1, z - 1});
    const float k1 = b - a, k2 = c - a, k3 = e - a, k4 = a - b - c + d, k5 = a - c - e + g, k6 = a - b - e + f,
                k7 = -a + b + c - d + e - f - g + h;
    const Float3 G1 = gb - ga, G2 = gc - ga, G3 = ge - ga, G4 = ga - gb - gc + gd, G5 = ga - gc - ge + gg,
                 G6 = ga - gb - ge + gf, G7 = gb + gc + ge + gh - ga - gd - gf - gg;
    const Float3 blended = ga + G1 * u + G2 * v + G3 * w + G4 * (u * v) + G5 * (v * w) + G6 * (w * u) + G7 * (u * v * w);
    gradient = blended + Float3{fadeDerivative(x) * (k1 + k4 * v + k6 * w + k7 * v * w),
                                fadeDerivative(y) * (k2 + k4 * u + k5 * w + k7 * u * w),
                                fadeDerivative(z) * (k3 + k5 * v + k6 * u + k7 * u * v)};
    return a + k1 * u + k2 * v + k3 * w + k4 * u * v + k5 * v * w + k6 * w * u + k7 * u * v * w;
}

#if defined(__SSE2__)
namespace {
// perlinNoiseGrad for four points at once (the octaves of one bump lookup), in SSE2 lanes that
// do exactly the scalar code's operations in its order, so the results are bit-identical to it
// (no FMA at this target; tested against the scalar code). The hashing stays scalar per lane.
struct Lanes {
    __m128 x, y, z;
};
inline __m128 fade4(__m128 t) {
    const __m128 inner = _mm_add_ps(_mm_mul_ps(t, _mm_sub_ps(_mm_mul_ps(t, _mm_set1_ps(6.0f)), _mm_set1_ps(15.0f))),
                                    _mm_set1_ps(10.0f));
    return _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(t, t), t), inner);
}
inline __m128 fadeDerivative4(__m128 t) {
    const __m128 inner = _mm_add_ps(_mm_mul_ps(t, _mm_sub_ps(t, _mm_set1_ps(2.0f))), _mm_set1_ps(1.0f));
    return _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(30.0f), t), t), inner);
}
// floor for |v| < 2^31 (callers check): truncate, then step down where that rounded up.
inline __m128 floor4(__m128 v) {
    const __m128 t = _mm_cvtepi32_ps(_mm_cvttps_epi32(v));
    return _mm_sub_ps(t, _mm_and_ps(_mm_cmpgt_ps(t, v), _mm_set1_ps(1.0f)));
}
inline Lanes gather(const int* hash) {
    const Float3 &g0 = gradVector(hash[0]), &g1 = gradVector(hash[1]), &g2 = gradVector(hash[2]), &g3 = gradVector(hash[3]);
    return {_mm_setr_ps(g0.x, g1.x, g2.x, g3.x), _mm_setr_ps(g0.y, g1.y, g2.y, g3.y), _mm_setr_ps(g0.z, g1.z, g2.z, g3.z)};
}
// dot(g, {x, y, z}) as the scalar dot: (g.x x + g.y y) + g.z z.
inline __m128 dot4(const Lanes& g, __m128 x, __m128 y, __m128 z) {
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(g.x, x), _mm_mul_ps(g.y, y)), _mm_mul_ps(g.z, z));
}
inline __m128 add(__m128 a, __m128 b) { return _mm_add_ps(a, b); }
inline __m128 sub(__m128 a, __m128 b) { return _mm_sub_ps(a, b); }
inline __m128 mul(__m128 a, __m128 b) { return _mm_mul_ps(a, b); }

void perlinNoiseGrad4(const Lanes& p, float noise[4], float gx[4], float gy[4], float gz[4]) {
    const __m128 fx = floor4(p.x), fy = floor4(p.y), fz = floor4(p.z);
    alignas(16) float fxs[4], fys[4], fzs[4];
    _mm_store_ps(fxs, fx);
    _mm_store_ps(fys, fy);
    _mm_store_ps(fzs, fz);
    int ha[4], hb[4], hc[4], hd[4], he[4], hf[4], hg[4], hh[4];
    for (int k = 0; k < 4; ++k) {
        const int X = int(int64_t(fxs[k]) & 255), Y = int(int64_t(fys[k]) & 255), Z = int(int64_t(fzs[k]) & 255);
        const int A = perm(X) + Y, AA = perm(A) + Z, AB = perm(A + 1) + Z;
        const int B = perm(X + 1) + Y, BA = perm(B) + Z, BB = perm(B + 1) + Z;
        ha[k] = perm(AA), hb[k] = perm(BA), hc[k] = perm(AB), hd[k] = perm(BB);
        he[k] = perm(AA + 1), hf[k] = perm(BA + 1), hg[k] = perm(AB + 1), hh[k] = perm(BB + 1);
    }
    const __m128 x = sub(p.x, fx), y = sub(p.y, fy), z = sub(p.z, fz);
    const __m128 one = _mm_set1_ps(1.0f);
    const __m128 x1 = sub(x, one), y1 = sub(y, one), z1 = sub(z, one);
    const __m128 u = fade4(x), v = fade4(y), w = fade4(z);
    const Lanes ga = gather(ha), gb = gather(hb), gc = gather(hc), gd = gather(hd), ge = gather(he), gf = gather(hf),
                gg = gather(hg), gh = gather(hh);
    const __m128 a = dot4(ga, x, y, z), b = dot4(gb, x1, y, z), c = dot4(gc, x, y1, z), d = dot4(gd, x1, y1, z),
                 e = dot4(ge, x, y, z1), f = dot4(gf, x1, y, z1), g = dot4(gg, x, y1, z1), h = dot4(gh, x1, y1, z1);
    const __m128 k1 = sub(b, a), k2 = sub(c, a), k3 = sub(e, a), k4 = add(sub(sub(a, b), c), d),
                 k5 = add(sub(sub(a, c), e), g), k6 = add(sub(sub(a, b), e), f),
                 k7 = add(sub(sub(add(sub(add(add(_mm_xor_ps(a, _mm_set1_ps(-0.0f)), b), c), d), e), f), g), h);
    const __m128 uv = mul(u, v), vw = mul(v, w), wu = mul(w, u), uvw = mul(mul(u, v), w);
    auto blend = [&](__m128 Ga, __m128 Gb, __m128 Gc, __m128 Gd, __m128 Ge, __m128 Gf, __m128 Gg, __m128 Gh) {
        const __m128 G1 = sub(Gb, Ga), G2 = sub(Gc, Ga), G3 = sub(Ge, Ga), G4 = add(sub(sub(Ga, Gb), Gc), Gd),
                     G5 = add(sub(sub(Ga, Gc), Ge), Gg), G6 = add(sub(sub(Ga, Gb), Ge), Gf),
                     G7 = sub(sub(sub(sub(add(add(add(Gb, Gc), Ge), Gh), Ga), Gd), Gf), Gg);
        return add(add(add(add(add(add(add(Ga, mul(G1, u)), mul(G2, v)), mul(G3, w)), mul(G4, uv)), mul(G5, vw)),
                       mul(G6, wu)),
                   mul(G7, uvw));
    };
    const __m128 bx = blend(ga.x, gb.x, gc.x, gd.x, ge.x, gf.x, gg.x, gh.x);
    const __m128 by = blend(ga.y, gb.y, gc.y, gd.y, ge.y, gf.y, gg.y, gh.y);
    const __m128 bz = blend(ga.z, gb.z, gc.z, gd.z, ge.z, gf.z, gg.z, gh.z);
    const __m128 dx = mul(fadeDerivative4(x), add(add(add(k1, mul(k4, v)), mul(k6, w)), mul(mul(k7, v), w)));
    const __m128 dy = mul(fadeDerivative4(y), add(add(add(k2, mul(k4, u)), mul(k5, w)), mul(mul(k7, u), w)));
    const __m128 dz = mul(fadeDerivative4(z), add(add(add(k3, mul(k5, v)), mul(k6, u)), mul(mul(k7, u), v)));
    _mm_storeu_ps(gx, add(bx, dx));
    _mm_storeu_ps(gy, add(by, dy));
    _mm_storeu_ps(gz, add(bz, dz));
    const __m128 n = add(add(add(add(add(add(add(a, mul(k1, u)), mul(k2, v)), mul(k3, w)), mul(mul(k4, u), v)),
                                 mul(mul(k5, v), w)),
                             mul(mul(k6, w), u)),
                         mul(mul(mul(k7, u), v), w));
    _mm_storeu_ps(noise, n);
}
}  // namespace
#endif

float turbulenceGrad(const Float3& p, int octaves, Float3& gradient) {
    float sum = 0.0f, amp = 1.0f, freq = 1.0f;
    gradient = {0, 0, 0};
    int i = 0;
#if defined(__SSE2__)
    // Four octaves per call of the lane version; the sums below stay in octave order, and the
    // scalar loop after it does the octaves left over (or all of them for far-out points).
    const float limit = 1.0e9f / float(1 << std::min(std::max(octaves, 1), 30));
    if (octaves >= 4 && maxAbsComponent(p) < limit) {
        for (; i + 4 <= octaves; i += 4) {
            float fr[4];
            for (int k = 0; k < 4; ++k) fr[k] = freq * float(1 << k);
            const Lanes q{_mm_mul_ps(_mm_set1_ps(p.x), _mm_loadu_ps(fr)), _mm_mul_ps(_mm_set1_ps(p.y), _mm_loadu_ps(fr)),
                          _mm_mul_ps(_mm_set1_ps(p.z), _mm_loadu_ps(fr))};
            float n[4], gx[4], gy[4], gz[4];
            perlinNoiseGrad4(q, n, gx, gy, gz);
            for (int k = 0; k < 4; ++k) {
                sum += amp * std::fabs(n[k]);
                gradient += Float3{gx[k], gy[k], gz[k]} * (n[k] < 0.0f ? -amp * freq : amp * freq);
                amp *= 0.5f;
                freq *= 2.0f;
            }
        }
    }
#endif
    for (; i < octaves; ++i) {
        Float3 gi;
        const float n = perlinNoiseGrad(p * freq, gi);
        sum += amp * std::fabs(n);
        gradient += gi * (n < 0.0f ? -amp * freq : amp * freq);
        amp *= 0.5f;
        freq *= 2.0f;
    }
    return sum;
}

float turbulence(const Float3& p, int octaves) {
    float sum = 0.0f, amp = 1.0f;
    Float3 q = p;
    for (int i = 0; i < octaves; ++i) {
        sum += amp * std::fabs(perlinNoise(q));
        amp *= 0.5f;
        q = q * 2.0f;
    }
    return sum;
}

void textureCoordinates(TextureMapping mapping, const Float3& po, float scale, float& u, float& v) {
    const float inv = 1.0f / scale;
    switch (mapping) {
    case TextureMapping::PlanarXZ: u = po.x * inv, v = po.z * inv; return;
    case TextureMapping::PlanarXY: u = po.x * inv, v = po.y * inv; return;
    case TextureMapping::PlanarYZ: u = po.z * inv, v = po.y * inv; return;
    case TextureMapping::Spherical:
    case TextureMapping::Cylindrical: {
        // Longitude: 0 on +z, growing towards +x (counter-clockwise seen from +y), in turns.
        float turn = std::atan2(po.x, po.z) * float(0.5 / std::numbers::pi);
        if (turn < 0.0f) turn += 1.0f;
        u = turn * inv;
        if (mapping == TextureMapping::Cylindrical) {
            v = po.y * inv;
            return;
        }
        // Latitude: 0 at the -y pole, 1 at the +y pole (the top of an image is at v = 1).
        const float r = length(po);
        const float c = r > 0.0f ? std::clamp(po.y / r, -1.0f, 1.0f) : 0.0f;
        v = (1.0f - std::acos(c) * float(1.0 / std::numbers::pi)) * inv;
        return;
    }
    case TextureMapping::Uv:
    case TextureMapping::Auto:
    case TextureMapping::Object: break;
    }
    u = po.x * inv, v = po.z * inv;
}

void meshUVAt(const TriangleMesh& mesh, uint32_t prim, float u, float v, float out[2]) {
    const uint32_t* tri = mesh.indices() + 3 * size_t(prim);
    const float* t = mesh.uvs();
    const float w = 1.0f - u - v;
    for (int k = 0; k < 2; ++k)
        out[k] = t[2 * size_t(tri[0]) + k] * w + t[2 * size_t(tri[1]) + k] * u + t[2 * size_t(tri[2]) + k] * v;
}

bool uvTangents(const TriangleMesh& mesh, uint32_t prim, Float3& dPdu, Float3& dPdv) {
    const uint32_t* tri = mesh.indices() + 3 * size_t(prim);
    const float* t = mesh.uvs();
    const Float3 p0 = mesh.position(tri[0]);
    const Float3 e1 = mesh.position(tri[1]) - p0, e2 = mesh.position(tri[2]) - p0;
    const float du1 = t[2 * size_t(tri[1])] - t[2 * size_t(tri[0])], dv1 = t[2 * size_t(tri[1]) + 1] - t[2 * size_t(tri[0]) + 1];
    const float du2 = t[2 * size_t(tri[2])] - t[2 * size_t(tri[0])], dv2 = t[2 * size_t(tri[2]) + 1] - t[2 * size_t(tri[0]) + 1];
    // e1 = dPdu du1 + dPdv dv1, e2 = dPdu du2 + dPdv dv2, solved for dPdu and dPdv.
    const float det = du1 * dv2 - du2 * dv1;
    if (!(std::fabs(det) > 0.0f)) return false;
    const float inv = 1.0f / det;
    dPdu = (e1 * dv2 - e2 * dv1) * inv;
    dPdv = (e2 * du1 - e1 * du2) * inv;
    return isFinite(dPdu) && isFinite(dPdv);
}

Float3 uvSurfaceGradient(const Float3& dPdu, const Float3& dPdv, float dhdu, float dhdv) {
    // grad(u) . dPdu = 1, grad(u) . dPdv = 0 (and the same for v), both in the plane:
    // grad(u) = (dPdv x N) / |N|^2, grad(v) = (N x dPdu) / |N|^2 with N = dPdu x dPdv.
    const Float3 n = cross(dPdu, dPdv);
    const float nn = dot(n, n);
    if (!(nn > 0.0f)) return {0, 0, 0};
    return (cross(dPdv, n) * dhdu + cross(n, dPdu) * dhdv) * (1.0f / nn);
}

Texture::Texture(const TextureDesc& desc, const Color& base) : desc_(desc), base_(base) {
    if (desc_.kind == TextureKind::Image) image_ = loadTextureImage(desc_.file);
    if (!(desc_.scale > 0.0f)) desc_.scale = 1.0f;
}

void Texture::coordinates(const Float3& objectPos, const float* uv, float& u, float& v, Float3& p) const {
    if (readsMeshUVs(desc_.mapping, uv != nullptr)) {
        // The patterns see (u, 0, v) as their position, so marble and wood follow the UVs too.
        const float inv = 1.0f / desc_.scale;
        u = (uv ? uv[0] : 0.0f) * inv;
        v = (uv ? uv[1] : 0.0f) * inv;
        p = {u, 0.0f, v};
    } else {
        p = objectPos * (1.0f / desc_.scale);
        textureCoordinates(desc_.mapping, objectPos, desc_.scale, u, v);
    }
}

// Bilinear, repeating, of a plane of `channels` floats per texel; image row 0 is at v = 1 (the top).
template <int channels>
std::array<float, channels> sampleImage(const float* plane, int width, int height, float u, float v) {
    const float x = (u - std::floor(u)) * float(width) - 0.5f;
    const float y = (1.0f - (v - std::floor(v))) * float(height) - 0.5f;
    const float x0f = std::floor(x), y0f = std::floor(y);
    const float tx = x - x0f, ty = y - y0f;
    auto wrap = [](int i, int n) { return ((i % n) + n) % n; };
    const int x0 = wrap(int(x0f), width), x1 = wrap(int(x0f) + 1, width);
    const int y0 = wrap(int(y0f), height), y1 = wrap(int(y0f) + 1, height);
    auto at = [&](int xi, int yi, int c) { return plane[(size_t(yi) * width + xi) * channels + c]; };
    std::array<float, channels> out;
    for (int c = 0; c < channels; ++c) {
        const float top = at(x0, y0, c) * (1.0f - tx) + at(x1, y0, c) * tx;
        const float bottom = at(x0, y1, c) * (1.0f - tx) + at(x1, y1, c) * tx;
        out[size_t(c)] = top * (1.0f - ty) + bottom * ty;
    }
    return out;
}

float Texture::alpha(const Float3& objectPos, const float* uv, AlphaChannel channel) const {
    if (channel == AlphaChannel::Red) return color(objectPos, uv).x;
    if (desc_.kind != TextureKind::Image || image_->alpha.empty()) return 1.0f;
    float u, v;
    Float3 p;
    coordinates(objectPos, uv, u, v, p);
    return sampleImage<1>(image_->alpha.data(), image_->width, image_->height, u, v)[0];
}

Color Texture::color(const Float3& objectPos, const float* uv) const {
    Float3 p;
    float u, v;
    coordinates(objectPos, uv, u, v, p);
    switch (desc_.kind) {
    case TextureKind::None: return base_;
    case TextureKind::Checker: {
        const int parity = int(int64_t(std::floor(u)) + int64_t(std::floor(v))) & 1;
        return parity ? desc_.color2 : base_;
    }
    case TextureKind::Marble: {
        const float t = 0.5f + 0.5f * std::sin(4.0f * p.x + 6.0f * turbulence(p, 5));
        return mix(desc_.color2, base_, t);
    }
    case TextureKind::Wood: {
        const float r = std::sqrt(p.x * p.x + p.z * p.z) * 8.0f + 1.5f * perlinNoise(p * 2.0f);
        const float ring = r - std::floor(r);
        return mix(base_, desc_.color2, ring * ring);
    }
    case TextureKind::Image: {
        const auto c = sampleImage<3>(image_->rgb.data(), image_->width, image_->height, u, v);
        return Color{c[0], c[1], c[2]} * base_;
    }
    }
    return base_;
}

}  // namespace rtwall
