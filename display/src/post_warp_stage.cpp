// PostWarpStage (rtwall/display.h, issue 30): the rasteriser's post-warp of a calibrated wall,
// on the CPU (apply, the reference) and in GL (post_warp.frag), for the comparison with direct
// per-pixel rays (docs/mpcdi.md).
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <rtwall/display.h>
#include <rtwall/image_sample.h>
#include <rtwall/mpcdi.h>

#include "gl_reproject.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace rtwall {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

}  // namespace

struct PostWarpStage::Gl {
    GLuint program = 0;
    struct Screen {
        GLuint shown = 0, targets = 0, vao = 0;
    };
    std::vector<Screen> screens;
    std::vector<float> scratch;
};

PostWarpStage::PostWarpStage(const WallConfig& wall, const MpcdiFile& file) : screens_(wall.screens.size()) {
    // The config's viewer until setEyes says otherwise.
    const bool stereo = wall.stereo.mode != StereoMode::None;
    eyes_[0] = eyePosition(staticHead(wall.stereo), wall.stereo.eyeSeparation, stereo ? 0 : -1);
    eyes_[1] = eyePosition(staticHead(wall.stereo), wall.stereo.eyeSeparation, stereo ? 1 : -1);
    for (const WallWarp& ww : wallWarps(wall, file)) {
        const ScreenConfig& sc = wall.screens[ww.screen];
        Screen& s = screens_[ww.screen];
        s.width = sc.outputWidth;
        s.height = sc.outputHeight;
        const EyeWindow f = screenFrame(wall, ww.screen);
        s.lowerLeft = f.lowerLeft;
        s.right = f.right;
        s.up = f.up;
        // The eyes' images on the screen, as mapPixel packs them.
        const bool both = stereo && sc.eye == Eye::Both;
        s.quad = both && wall.stereo.mode == StereoMode::QuadBuffer;
        if (both && wall.stereo.mode == StereoMode::SideBySide) {
            s.panes = {Pane{.x0 = 0, .width = s.width / 2, .eye = 0}, Pane{.x0 = s.width / 2, .width = s.width - s.width / 2, .eye = 1}};
        } else if (s.quad) {
            s.panes = {Pane{.x0 = 0, .width = s.width, .eye = 0}, Pane{.x0 = 0, .width = s.width, .eye = 1}};
        } else {
            s.panes = {Pane{.x0 = 0, .width = s.width, .eye = sc.eye == Eye::Right ? 1 : 0}};
        }
        const PixelRect& vp = sc.viewport;
        for (Pane& p : s.panes) {
            p.samples.assign(size_t(p.width) * size_t(s.height), {kNaN, kNaN, kNaN});
            for (const ScreenWarp& r : ww.regions) {
                s.surface = r.warp->kind == PixelWarp::Kind::SurfacePoints;
                // Each pane pixel's centre in wall pixels; the warp there (its rectangle is in
                // wall pixels of the viewport).
                for (int y = 0; y < s.height; ++y)
                    for (int x = 0; x < p.width; ++x) {
                        const float wx = float(vp.x) + (float(x) + 0.5f) * float(vp.width) / float(p.width);
                        const float wy = float(vp.y) + (float(y) + 0.5f) * float(vp.height) / float(s.height);
                        if (wx < float(r.rect.x0) || wx >= float(r.rect.x1) || wy < float(r.rect.y0) || wy >= float(r.rect.y1)) continue;
                        const Float3 v = sampleWarp(*r.warp, r.rect, wx, wy);
                        Float3& out = p.samples[size_t(y) * size_t(p.width) + size_t(x)];
                        if (std::isnan(v.x) || std::isnan(v.y) || std::isnan(v.z)) continue;
                        if (s.surface) {
                            out = v;
                        } else {  // the flat wall position it looks at, in the pane's pixels
                            out = {(wx + v.x - float(vp.x)) * float(p.width) / float(vp.width),
                                   (wy + v.y - float(vp.y)) * float(s.height) / float(vp.height), 0.0f};
                        }
                    }
            }
        }
    }
}

PostWarpStage::~PostWarpStage() = default;

void PostWarpStage::setEyes(const Float3& left, const Float3& right) {
    eyes_[0] = left;
    eyes_[1] = right;
}

const std::vector<float>& PostWarpStage::targets(const Screen& s, const Pane& p) const {
    // 2D offsets are fixed; 3D points move with the eye: computed again only when it moved.
    const Float3 e = eyes_[p.eye];
    if (!p.targets.empty() && (!s.surface || (e.x == p.targetsEye.x && e.y == p.targetsEye.y && e.z == p.targetsEye.z)))
        return p.targets;
    p.targetsEye = e;
    std::vector<float>& out = p.targets;
    out.assign(p.samples.size() * 2, kNaN);
    // 3D: where the ray from the eye through the point meets the frame's plane, solved in
    // double (the frame's edges and normal): e + t (q - e) = ll + a right + b up.
    const Float3 n = cross(s.right, s.up);
    const double nn = dot(n, n);
    for (size_t i = 0; i < p.samples.size(); ++i) {
        const Float3 q = p.samples[i];
        if (std::isnan(q.x)) continue;
        if (!s.surface) {
            out[2 * i] = q.x;
            out[2 * i + 1] = q.y;
            continue;
        }
        const Float3 d = q - e;
        const double den = dot(n, d);
        if (den == 0.0 || nn == 0.0) continue;
        const double t = double(dot(n, s.lowerLeft - e)) / den;
        if (!(t > 0.0)) continue;
        const Float3 h = e + d * float(t) - s.lowerLeft;
        const double a = double(dot(h, s.right)) / double(dot(s.right, s.right)), b = double(dot(h, s.up)) / double(dot(s.up, s.up));
        out[2 * i] = float(a * p.width);
        out[2 * i + 1] = float((1.0 - b) * s.height);
    }
    return out;
}

void PostWarpStage::applyPane(const Screen& s, const Pane& p, Image& pixels) const {
    const std::vector<float>& t = targets(s, p);
    // The pane's own copy of its flat pixels, reused frame after frame.
    p.flat.width = p.width;
    p.flat.height = s.height;
    p.flat.rgb.resize(size_t(p.width) * size_t(s.height) * 3);
    for (int y = 0; y < s.height; ++y)
        std::memcpy(p.flat.pixel(0, y), pixels.pixel(p.x0, y), size_t(p.width) * 3);
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < p.width; ++x) {
            const size_t i = size_t(y) * size_t(p.width) + size_t(x);
            uint8_t* o = pixels.pixel(p.x0 + x, y);
            if (std::isnan(t[2 * i]) || !sampleBilinear(p.flat, t[2 * i], t[2 * i + 1], o)) o[0] = o[1] = o[2] = 0;
        }
}

void PostWarpStage::apply(const WallConfig&, size_t screen, int eye, Image& pixels) const {
    if (screen >= screens_.size()) return;
    const Screen& s = screens_[screen];
    if (s.panes.empty() || pixels.width != s.width || pixels.height != s.height) return;
    for (const Pane& p : s.panes)
        if (!s.quad || p.eye == eye) applyPane(s, p, pixels);
}

void PostWarpStage::drawGl(const WallConfig&, size_t screen) {
    if (screen >= screens_.size() || screens_[screen].panes.empty()) return;
    const Screen& s = screens_[screen];
    if (!gl_) {
        gl_ = std::make_unique<Gl>();
        gl_->program = linkProgram(presentVertexShader(), warpShader("post_warp.frag"));
        gl_->screens.resize(screens_.size());
    }
    Gl::Screen& g = gl_->screens[screen];
    if (!g.vao) {  // in this screen's context: vertex arrays are not shared
        for (GLuint* t : {&g.shown, &g.targets}) {
            glGenTextures(1, t);
            glBindTexture(GL_TEXTURE_2D, *t);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        }
        glBindTexture(GL_TEXTURE_2D, g.shown);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, s.width, s.height, 0, GL_RGB, GL_UNSIGNED_BYTE, nullptr);
        glBindTexture(GL_TEXTURE_2D, g.targets);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, s.width, s.height, 0, GL_RG, GL_FLOAT, nullptr);
        glGenVertexArrays(1, &g.vao);
    }
    // A pass per buffer: a quad-buffered screen's two, else the one back buffer with every pane's
    // targets side by side (each in its pane's pixels; the shader finds its pane by `split`).
    const int passes = s.quad ? 2 : 1;
    const int split = s.panes.size() == 2 && !s.quad ? s.panes[1].x0 : s.width;
    for (int pass = 0; pass < passes; ++pass) {
        std::vector<float>& scratch = gl_->scratch;
        scratch.assign(size_t(s.width) * size_t(s.height) * 2, -1e9f);
        for (const Pane& p : s.panes) {
            if (s.quad && p.eye != pass) continue;
            const std::vector<float>& t = targets(s, p);
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < p.width; ++x)
                    for (int c = 0; c < 2; ++c) {
                        const float v = t[(size_t(y) * size_t(p.width) + size_t(x)) * 2 + size_t(c)];
                        // Off every image: black (NaN in a texture is the driver's to read).
                        scratch[(size_t(y) * size_t(s.width) + size_t(p.x0 + x)) * 2 + size_t(c)] = std::isnan(v) ? -1e9f : v;
                    }
        }
        const GLenum buffer = s.quad ? (pass == 0 ? GL_BACK_LEFT : GL_BACK_RIGHT) : GL_BACK;
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, g.targets);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, s.width, s.height, GL_RG, GL_FLOAT, scratch.data());
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glReadBuffer(buffer);
        glDrawBuffer(buffer);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, g.shown);
        glCopyTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, 0, 0, s.width, s.height);
        glUseProgram(gl_->program);
        glUniform1i(glGetUniformLocation(gl_->program, "shown"), 0);
        glUniform1i(glGetUniformLocation(gl_->program, "targets"), 1);
        glUniform2i(glGetUniformLocation(gl_->program, "size"), s.width, s.height);
        glUniform1i(glGetUniformLocation(gl_->program, "split"), split);
        glBindVertexArray(g.vao);
        glDisable(GL_BLEND);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glBindVertexArray(0);
    glUseProgram(0);
    glDrawBuffer(GL_BACK);
    glReadBuffer(GL_BACK);
}

void PostWarpStage::releaseGl() {
    if (!gl_) return;
    glDeleteProgram(gl_->program);
    for (Gl::Screen& g : gl_->screens) {
        glDeleteTextures(1, &g.shown);
        glDeleteTextures(1, &g.targets);
    }
    gl_.reset();
}

}  // namespace rtwall
