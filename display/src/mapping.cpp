// The CPU reference of present.frag: which wall pixel each screen pixel shows, its blending
// weight and its colour correction. The GL presenter must agree with this to within rounding
// (tests/display/gl_presenter_test.cpp), so keep both in step.
#include <rtwall/display.h>
#include <rtwall/tune.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace rtwall {

float blendRamp(int widthPx, float distancePx) {
    if (widthPx <= 0) return 1.0f;
    return std::clamp(distancePx / float(widthPx), 0.0f, 1.0f);
}

ScreenSample mapPixel(const ScreenConfig& s, StereoMode mode, int outX, int outY) {
    ScreenSample r;
    int ow = s.outputWidth, x = outX;
    if (s.eye == Eye::Both && mode == StereoMode::SideBySide) {
        // The left eye fills the left half of the screen's pixels, the right eye the right half.
        const int half = ow / 2;
        if (outX >= half) {
            r.eye = 1;
            x = outX - half;
            ow -= half;
        } else {
            ow = half;
        }
    } else if (s.eye == Eye::Right) {
        r.eye = 1;
    }
    const PixelRect& v = s.viewport;
    // Nearest wall pixel to the output pixel's centre, in integers so the shader agrees exactly.
    r.wallX = v.x + int((int64_t(2 * x + 1) * v.width) / (2 * int64_t(ow)));
    r.wallY = v.y + int((int64_t(2 * outY + 1) * v.height) / (2 * int64_t(s.outputHeight)));
    const float dist[4] = {float(r.wallX - v.x) + 0.5f, float(v.x + v.width - r.wallX) - 0.5f, float(r.wallY - v.y) + 0.5f,
                           float(v.y + v.height - r.wallY) - 0.5f};
    float w = 1.0f;
    for (int e = 0; e < 4; ++e)
        if (s.blend[e] > 0) w *= std::pow(blendRamp(s.blend[e], dist[e]), float(1.0 / s.blendGamma[e]));
    r.weight = w;
    return r;
}

namespace {
float corrected(float x, float weight, const ScreenConfig& s) {
    if (s.gamma != 1.0) x = std::pow(x, float(1.0 / s.gamma));
    return std::clamp(x * float(s.brightness) * weight, 0.0f, 1.0f);
}
uint8_t quantise(float x) { return uint8_t(std::lround(x * 255.0f)); }
}  // namespace

uint8_t correctColour(uint8_t value, float weight, const ScreenConfig& screen) {
    return quantise(corrected(float(value) / 255.0f, weight, screen));
}

std::array<uint8_t, 3> ownerColour(uint32_t client) {
    static constexpr std::array<std::array<uint8_t, 3>, 8> palette{{{230, 25, 75},
                                                                    {60, 180, 75},
                                                                    {0, 130, 200},
                                                                    {255, 225, 25},
                                                                    {145, 30, 180},
                                                                    {70, 240, 240},
                                                                    {245, 130, 48},
                                                                    {240, 50, 230}}};
    if (client == UINT32_MAX) return {128, 128, 128};
    return palette[client % palette.size()];
}

void checkFrameSize(const WallConfig& wall, const WallFrame& frame, const char* who) {
    const Image& f = frame.left;
    if (f.width < 1 || f.height < 1 || f.width > wall.width || f.height > wall.height ||
        (!frame.right.rgb.empty() && (frame.right.width != f.width || frame.right.height != f.height)))
        throw std::invalid_argument(std::string(who) + ": the frame is " + std::to_string(f.width) + "x" +
                                    std::to_string(f.height) + " (right eye " + std::to_string(frame.right.width) + "x" +
                                    std::to_string(frame.right.height) + "), the wall " + std::to_string(wall.width) + "x" +
                                    std::to_string(wall.height) + ": a frame is at most the wall's size");
}

Image presentScreen(const WallConfig& wall, size_t index, const WallFrame& frame, const PresentOptions& options) {
    const ScreenConfig& s = wall.screens.at(index);
    checkFrameSize(wall, frame, "presentScreen");
    // A frame rendered at a fraction of the wall's resolution is shown upscaled (bilinear, pixel
    // centres aligned, edges clamped: what the GL presenter's linear filtering does).
    const bool scaled = frame.left.width != wall.width || frame.left.height != wall.height;
    const Image left = scaled ? resizeBilinear(frame.left, wall.width, wall.height) : Image{};
    const Image right = scaled && !frame.right.rgb.empty() ? resizeBilinear(frame.right, wall.width, wall.height) : Image{};
    const Image& wallLeft = scaled ? left : frame.left;
    const Image& wallRight = scaled ? right : frame.right;
    const bool haveRight = !frame.right.rgb.empty();
    const bool quad = s.eye == Eye::Both && wall.stereo.mode == StereoMode::QuadBuffer;
    // Tiles are the frame's: a wall pixel belongs to the tile of the frame pixel it scales to.
    const int tilesX = frame.tileSize > 0 ? (frame.left.width + frame.tileSize - 1) / frame.tileSize : 0;
    Image out;
    out.width = s.outputWidth;
    out.height = s.outputHeight;
    out.rgb.resize(size_t(out.width) * out.height * 3);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) {
            const ScreenSample m = mapPixel(s, wall.stereo.mode, x, y);
            const int eye = quad ? options.quadBufferEye : m.eye;
            const Image& src = eye == 1 && haveRight ? wallRight : wallLeft;
            const uint8_t* p = src.pixel(m.wallX, m.wallY);
            float c[3] = {p[0] / 255.0f, p[1] / 255.0f, p[2] / 255.0f};
            if (options.falseColour && tilesX > 0) {
                const int fx = m.wallX * frame.left.width / wall.width, fy = m.wallY * frame.left.height / wall.height;
                const size_t tile = size_t(fy / frame.tileSize) * tilesX + size_t(fx / frame.tileSize);
                const auto o = ownerColour(tile < frame.tileOwners.size() ? frame.tileOwners[tile] : UINT32_MAX);
                for (int k = 0; k < 3; ++k) c[k] = 0.5f * (c[k] + o[k] / 255.0f);
            }
            uint8_t* q = out.pixel(x, y);
            for (int k = 0; k < 3; ++k) q[k] = quantise(corrected(c[k], m.weight, s));
        }
    const int bufferEye = quad ? options.quadBufferEye : 0;
    for (ScreenStage* stage : options.stages) stage->apply(wall, index, bufferEye, out);
    if (options.overlay) OverlayStage(options.overlay).apply(wall, index, bufferEye, out);
    return out;
}

void OverlayStage::apply(const WallConfig&, size_t screen, int, Image& out) const {
    if (!overlay_ || screen != 0) return;
    // Pasted as is, after correction: the GL presenter copies it with glBlitFramebuffer.
    const Image& o = *overlay_;
    const int w = std::min(o.width, out.width - kOverlayMargin), h = std::min(o.height, out.height - kOverlayMargin);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) std::memcpy(out.pixel(kOverlayMargin + x, kOverlayMargin + y), o.pixel(x, y), 3);
}

}  // namespace rtwall
