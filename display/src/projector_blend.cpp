// ProjectorBlendStage (rtwall/display.h, issue 30): a calibrated wall's alpha and beta maps on
// its screens' pixels, on the CPU (apply, the reference) and in GL (projector_blend.frag).
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <rtwall/display.h>
#include <rtwall/mpcdi.h>

#include "gl_reproject.h"

#include <algorithm>
#include <cmath>

namespace rtwall {

namespace {

float decode(float s) { return s <= 0.04045f ? s / 12.92f : std::pow((s + 0.055f) / 1.055f, 2.4f); }
float encode(float l) { return l <= 0.0031308f ? l * 12.92f : 1.055f * std::pow(l, 1.0f / 2.4f) - 0.055f; }

// A map's values at its pixel (i, j), linear (its embedded gamma undone), three components.
void linearAt(const MpcdiMap& m, int i, int j, float out[3]) {
    const size_t k = (size_t(j) * size_t(m.width) + size_t(i)) * size_t(m.components);
    for (int c = 0; c < 3; ++c) {
        const float v = m.values[k + size_t(m.components == 3 ? c : 0)];
        out[c] = m.gammaEmbedded == 1.0 ? v : std::pow(v, float(m.gammaEmbedded));
    }
}

}  // namespace

struct ProjectorBlendStage::Gl {
    GLuint program = 0;
    struct Screen {
        GLuint shown = 0, alpha = 0, beta = 0, vao = 0;
    };
    std::vector<Screen> screens;
};

ProjectorBlendStage::ProjectorBlendStage(const WallConfig& wall, const MpcdiFile& file) : screens_(wall.screens.size()) {
    for (int v = 0; v < 256; ++v) toLinear_[size_t(v)] = decode(float(v) / 255.0f);
    if (!wall.warp) return;
    for (const auto& [id, screenName] : wall.warp->buffers) {
        const MpcdiBuffer* b = file.buffer(id);
        const auto it = std::find_if(wall.screens.begin(), wall.screens.end(), [&](const ScreenConfig& s) { return s.name == screenName; });
        if (!b || it == wall.screens.end()) continue;
        const ScreenConfig& sc = *it;
        Maps& maps = screens_[size_t(it - wall.screens.begin())];
        for (const MpcdiRegion& r : b->regions) {
            if (!r.alpha && !r.beta) continue;
            if (maps.alpha.empty()) {
                maps.width = sc.outputWidth;
                maps.height = sc.outputHeight;
                maps.alpha.assign(size_t(maps.width) * size_t(maps.height) * 3, 1.0f);
                maps.beta.assign(maps.alpha.size(), 0.0f);
            }
            // The region's pixels in the buffer, which has the screen's pixels (checkWarp); a
            // map has the region's resolution, one value per projector pixel.
            const int x0 = int(std::lround(r.x * b->xResolution)), y0 = int(std::lround(regionTop(*wall.warp, r) * b->yResolution));
            for (int j = 0; j < r.yResolution; ++j)
                for (int i = 0; i < r.xResolution; ++i) {
                    const int x = x0 + i, y = y0 + j;
                    if (x < 0 || y < 0 || x >= maps.width || y >= maps.height) continue;
                    const size_t k = (size_t(y) * size_t(maps.width) + size_t(x)) * 3;
                    if (r.alpha && r.alpha->width == r.xResolution && r.alpha->height == r.yResolution) linearAt(*r.alpha, i, j, &maps.alpha[k]);
                    if (r.beta && r.beta->width == r.xResolution && r.beta->height == r.yResolution) linearAt(*r.beta, i, j, &maps.beta[k]);
                }
        }
    }
}

ProjectorBlendStage::~ProjectorBlendStage() = default;

bool ProjectorBlendStage::blends(size_t screen) const { return screen < screens_.size() && !screens_[screen].alpha.empty(); }

void ProjectorBlendStage::apply(const WallConfig&, size_t screen, int, Image& pixels) const {
    if (!blends(screen)) return;
    const Maps& m = screens_[screen];
    if (pixels.width != m.width || pixels.height != m.height) return;
    for (size_t k = 0; k < pixels.rgb.size(); ++k) {
        const float a = m.alpha[k], b = m.beta[k];
        if (a == 1.0f && b == 0.0f) continue;
        const float o = std::clamp(encode(b + (1.0f - b) * a * toLinear_[pixels.rgb[k]]), 0.0f, 1.0f);
        pixels.rgb[k] = uint8_t(std::lround(o * 255.0f));
    }
}

void ProjectorBlendStage::drawGl(const WallConfig& wall, size_t screen) {
    if (!blends(screen)) return;
    const Maps& m = screens_[screen];
    if (!gl_) {
        gl_ = std::make_unique<Gl>();
        gl_->program = linkProgram(presentVertexShader(), warpShader("projector_blend.frag"));
        gl_->screens.resize(screens_.size());
    }
    Gl::Screen& g = gl_->screens[screen];
    const auto texture = [](GLuint& t, GLenum internal, int w, int h, GLenum format, GLenum type, const void* data) {
        glGenTextures(1, &t);
        glBindTexture(GL_TEXTURE_2D, t);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTexImage2D(GL_TEXTURE_2D, 0, GLint(internal), w, h, 0, format, type, data);
    };
    if (!g.vao) {  // in this screen's context: vertex arrays are not shared
        texture(g.shown, GL_RGB8, m.width, m.height, GL_RGB, GL_UNSIGNED_BYTE, nullptr);
        texture(g.alpha, GL_RGB32F, m.width, m.height, GL_RGB, GL_FLOAT, m.alpha.data());
        texture(g.beta, GL_RGB32F, m.width, m.height, GL_RGB, GL_FLOAT, m.beta.data());
        glGenVertexArrays(1, &g.vao);
    }
    const ScreenConfig& sc = wall.screens.at(screen);
    const bool quad = sc.eye == Eye::Both && wall.stereo.mode == StereoMode::QuadBuffer;
    glUseProgram(gl_->program);
    glUniform1i(glGetUniformLocation(gl_->program, "shown"), 0);
    glUniform1i(glGetUniformLocation(gl_->program, "alphaMap"), 1);
    glUniform1i(glGetUniformLocation(gl_->program, "betaMap"), 2);
    glUniform1i(glGetUniformLocation(gl_->program, "screenHeight"), m.height);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindVertexArray(g.vao);
    glDisable(GL_BLEND);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, g.alpha);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, g.beta);
    // Each back buffer of a quad-buffered screen is its own eye's pixels: blended one by one.
    const GLenum buffers[2] = {GLenum(quad ? GL_BACK_LEFT : GL_BACK), GL_BACK_RIGHT};
    for (int e = 0; e < (quad ? 2 : 1); ++e) {
        glReadBuffer(buffers[e]);
        glDrawBuffer(buffers[e]);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, g.shown);
        glCopyTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, 0, 0, m.width, m.height);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glDrawBuffer(GL_BACK);
    glReadBuffer(GL_BACK);
    glActiveTexture(GL_TEXTURE0);
    glBindVertexArray(0);
    glUseProgram(0);
}

void ProjectorBlendStage::releaseGl() {
    if (!gl_) return;
    glDeleteProgram(gl_->program);
    for (Gl::Screen& g : gl_->screens) {
        glDeleteTextures(1, &g.shown);
        glDeleteTextures(1, &g.alpha);
        glDeleteTextures(1, &g.beta);
    }
    gl_.reset();  // the windows' vertex arrays go with their contexts
}

}  // namespace rtwall
