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
        if (sc.eye == Eye::Both && wall.stereo.mode != StereoMode::None)
            throw std::invalid_argument("post-warp: screen '" + sc.name + "' shows both eyes; the post-warp takes one eye a screen");
        Screen& s = screens_[ww.screen];
        s.width = sc.outputWidth;
        s.height = sc.outputHeight;
        s.eye = sc.eye == Eye::Right ? 1 : 0;
        const EyeWindow f = screenFrame(wall, ww.screen);
        s.lowerLeft = f.lowerLeft;
        s.right = f.right;
        s.up = f.up;
        s.samples.assign(size_t(s.width) * size_t(s.height), {kNaN, kNaN, kNaN});
        const PixelRect& vp = sc.viewport;
        for (const ScreenWarp& r : ww.regions) {
            s.surface = r.warp->kind == PixelWarp::Kind::SurfacePoints;
            // Each screen pixel's centre in wall pixels; the warp there (its rectangle is in
            // wall pixels of the viewport).
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) {
                    const float wx = float(vp.x) + (float(x) + 0.5f) * float(vp.width) / float(s.width);
                    const float wy = float(vp.y) + (float(y) + 0.5f) * float(vp.height) / float(s.height);
                    if (wx < float(r.rect.x0) || wx >= float(r.rect.x1) || wy < float(r.rect.y0) || wy >= float(r.rect.y1)) continue;
                    const Float3 v = sampleWarp(*r.warp, r.rect, wx, wy);
                    Float3& out = s.samples[size_t(y) * size_t(s.width) + size_t(x)];
                    if (std::isnan(v.x) || std::isnan(v.y) || std::isnan(v.z)) continue;
                    if (s.surface) {
                        out = v;
                    } else {  // the flat wall position it looks at, in this screen's pixels
                        out = {(wx + v.x - float(vp.x)) * float(s.width) / float(vp.width),
                               (wy + v.y - float(vp.y)) * float(s.height) / float(vp.height), 0.0f};
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

const std::vector<float>& PostWarpStage::targets(size_t screen) const {
    const Screen& s = screens_[screen];
    // 2D offsets are fixed; 3D points move with the eye: computed again only when it moved.
    const Float3 e = eyes_[s.eye];
    if (!s.targets.empty() && (!s.surface || (e.x == s.targetsEye.x && e.y == s.targetsEye.y && e.z == s.targetsEye.z)))
        return s.targets;
    s.targetsEye = e;
    std::vector<float>& out = s.targets;
    out.assign(s.samples.size() * 2, kNaN);
    // 3D: where the ray from the eye through the point meets the frame's plane, solved in
    // double (the frame's edges and normal): e + t (p - e) = ll + a right + b up.
    const Float3 n = cross(s.right, s.up);
    const double nn = dot(n, n);
    for (size_t i = 0; i < s.samples.size(); ++i) {
        const Float3 p = s.samples[i];
        if (std::isnan(p.x)) continue;
        if (!s.surface) {
            out[2 * i] = p.x;
            out[2 * i + 1] = p.y;
            continue;
        }
        const Float3 d = p - e;
        const double den = dot(n, d);
        if (den == 0.0 || nn == 0.0) continue;
        const double t = double(dot(n, s.lowerLeft - e)) / den;
        if (!(t > 0.0)) continue;
        const Float3 q = e + d * float(t) - s.lowerLeft;
        const double a = double(dot(q, s.right)) / double(dot(s.right, s.right)), b = double(dot(q, s.up)) / double(dot(s.up, s.up));
        out[2 * i] = float(a * s.width);
        out[2 * i + 1] = float((1.0 - b) * s.height);
    }
    return out;
}

void PostWarpStage::apply(const WallConfig&, size_t screen, Image& pixels) const {
    if (screen >= screens_.size() || screens_[screen].samples.empty()) return;
    const Screen& s = screens_[screen];
    if (pixels.width != s.width || pixels.height != s.height) return;
    const std::vector<float>& t = targets(screen);
    s.flat = pixels;  // the screen's own copy, reused frame after frame
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const size_t i = size_t(y) * size_t(s.width) + size_t(x);
            uint8_t* o = pixels.pixel(x, y);
            if (std::isnan(t[2 * i]) || !sampleBilinear(s.flat, t[2 * i], t[2 * i + 1], o)) o[0] = o[1] = o[2] = 0;
        }
}

void PostWarpStage::drawGl(const WallConfig&, size_t screen) {
    if (screen >= screens_.size() || screens_[screen].samples.empty()) return;
    const Screen& s = screens_[screen];
    if (!gl_) {
        gl_ = std::make_unique<Gl>();
        gl_->program = linkProgram(presentVertexShader(), warpShader("post_warp.frag"));
        gl_->screens.resize(screens_.size());
    }
    Gl::Screen& g = gl_->screens[screen];
    gl_->scratch = targets(screen);
    for (float& v : gl_->scratch)
        if (std::isnan(v)) v = -1e9f;  // off every image: black (NaN in a texture is the driver's to read)
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
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, g.targets);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, s.width, s.height, GL_RG, GL_FLOAT, gl_->scratch.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glDrawBuffer(GL_BACK);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, g.shown);
    glCopyTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, 0, 0, s.width, s.height);
    glUseProgram(gl_->program);
    glUniform1i(glGetUniformLocation(gl_->program, "shown"), 0);
    glUniform1i(glGetUniformLocation(gl_->program, "targets"), 1);
    glUniform2i(glGetUniformLocation(gl_->program, "size"), s.width, s.height);
    glBindVertexArray(g.vao);
    glDisable(GL_BLEND);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
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
