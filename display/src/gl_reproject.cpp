// The GL warp's passes, on one framebuffer object whose attachments change per pass. State
// textures hold what the CPU warp's Splat holds: RGBA8 (rgb, alpha = covered / 255) and R32F
// (the distance); the two crack passes ping-pong between two of each. A 32-bit float depth
// buffer holds each splat's key, its squared distance times 2^-64: a power of two keeps every
// float's order and precision, so the depth test decides as the CPU warp's key does.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "gl_reproject.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace rtwall {

ShaderSource warpShader(const std::string& name) {
    for (ShaderSource& s : warpShaders())
        if (s.name == name) return s;
    throw std::logic_error("no shipped shader " + name);
}

namespace {

// InputError, `what` and the driver's log, when `object` (a program, else a shader) did not
// link (compile); the object is deleted first.
void checkBuilt(GLuint object, bool program, const std::string& what) {
    GLint ok = 0;
    if (program) glGetProgramiv(object, GL_LINK_STATUS, &ok);
    else glGetShaderiv(object, GL_COMPILE_STATUS, &ok);
    if (ok) return;
    char log[2048] = {};
    if (program) {
        glGetProgramInfoLog(object, sizeof log, nullptr, log);
        glDeleteProgram(object);
    } else {
        glGetShaderInfoLog(object, sizeof log, nullptr, log);
        glDeleteShader(object);
    }
    throw InputError(what + std::string(log));
}


void setTexture(GLuint texture, GLenum internal, int w, int h, GLenum format, GLenum type, const void* data) {
    glBindTexture(GL_TEXTURE_2D, texture);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexImage2D(GL_TEXTURE_2D, 0, GLint(internal), w, h, 0, format, type, data);
}

void bindUnit(int unit, GLuint texture) {
    glActiveTexture(GLenum(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_2D, texture);
}

void uniform3(GLuint program, const char* name, const double v[3]) {
    glUniform3f(glGetUniformLocation(program, name), float(v[0]), float(v[1]), float(v[2]));
}

}  // namespace

GLuint compileShader(GLenum type, const ShaderSource& src) {
    const GLuint s = glCreateShader(type);
    const char* text = src.text.c_str();
    glShaderSource(s, 1, &text, nullptr);
    glCompileShader(s);
    checkBuilt(s, false, src.name + ": the OpenGL driver does not compile it: ");
    return s;
}

GLuint linkProgram(const ShaderSource& vert, const ShaderSource& frag) {
    const GLuint vs = compileShader(GL_VERTEX_SHADER, vert), fs = compileShader(GL_FRAGMENT_SHADER, frag);
    const GLuint program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    checkBuilt(program, true, frag.name + ": the OpenGL driver does not link it: ");
    return program;
}

struct GlReprojector::Impl {
    GLuint splat = 0, crack = 0, compose = 0, scan = 0, rowsInit = 0, rowScan = 0, fill = 0;  // programs
    GLuint vao = 0, fbo = 0, keys = 0;                              // keys: the depth renderbuffer
    GLuint sourceColour[2] = {}, sourceDepth[2] = {};               // newest, older
    int sourceW[2] = {-1, -1}, sourceH[2] = {-1, -1};
    GLuint state[2][2] = {}, stateDepth[2][2] = {};                 // per view, ping and pong
    GLuint composed = 0, composedDepth = 0, sides[2] = {}, rows[2] = {}, result = 0;  // rows: 1 x h
    int w = -1, h = -1;

    Impl() {
        const ShaderSource full = presentVertexShader();  // one triangle over the whole target
        splat = linkProgram(warpShader("warp_splat.vert"), warpShader("warp_splat.frag"));
        crack = linkProgram(full, warpShader("warp_crack.frag"));
        compose = linkProgram(full, warpShader("warp_compose.frag"));
        scan = linkProgram(full, warpShader("warp_scan.frag"));
        rowsInit = linkProgram(full, warpShader("warp_rows.frag"));
        rowScan = linkProgram(full, warpShader("warp_rowscan.frag"));
        fill = linkProgram(full, warpShader("warp_fill.frag"));
        glGenVertexArrays(1, &vao);
        glGenFramebuffers(1, &fbo);
        glGenRenderbuffers(1, &keys);
        for (auto [names, n] : textures()) glGenTextures(n, names);
    }
    ~Impl() {
        for (GLuint p : {splat, crack, compose, scan, rowsInit, rowScan, fill}) glDeleteProgram(p);
        glDeleteVertexArrays(1, &vao);
        glDeleteFramebuffers(1, &fbo);
        glDeleteRenderbuffers(1, &keys);
        for (auto [names, n] : textures()) glDeleteTextures(n, names);
    }
    // Every texture name array and its length: made and deleted together.
    std::array<std::pair<GLuint*, GLsizei>, 9> textures() {
        return {{{sourceColour, 2}, {sourceDepth, 2}, {&state[0][0], 4}, {&stateDepth[0][0], 4}, {&composed, 1}, {&composedDepth, 1},
                 {sides, 2}, {rows, 2}, {&result, 1}}};
    }

    void sizeTargets(int width, int height) {
        if (width == w && height == h) return;
        w = width;
        h = height;
        for (int v = 0; v < 2; ++v)
            for (int k = 0; k < 2; ++k) {
                setTexture(state[v][k], GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
                setTexture(stateDepth[v][k], GL_R32F, w, h, GL_RED, GL_FLOAT, nullptr);
            }
        setTexture(composed, GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        setTexture(composedDepth, GL_R32F, w, h, GL_RED, GL_FLOAT, nullptr);
        for (GLuint s : sides) setTexture(s, GL_RG32I, w, h, GL_RG_INTEGER, GL_INT, nullptr);
        for (GLuint r : rows) setTexture(r, GL_RG32I, 1, h, GL_RG_INTEGER, GL_INT, nullptr);
        setTexture(result, GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        glBindRenderbuffer(GL_RENDERBUFFER, keys);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    }

    void upload(int slot, const WarpSource& s) {
        const int sw = s.image.width, sh = s.image.height;
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        if (sw != sourceW[slot] || sh != sourceH[slot]) {
            setTexture(sourceColour[slot], GL_RGB8, sw, sh, GL_RGB, GL_UNSIGNED_BYTE, s.image.rgb.data());
            setTexture(sourceDepth[slot], GL_R32F, sw, sh, GL_RED, GL_FLOAT, s.depth.data());
            sourceW[slot] = sw;
            sourceH[slot] = sh;
            return;
        }
        glBindTexture(GL_TEXTURE_2D, sourceColour[slot]);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, sw, sh, GL_RGB, GL_UNSIGNED_BYTE, s.image.rgb.data());
        glBindTexture(GL_TEXTURE_2D, sourceDepth[slot]);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, sw, sh, GL_RED, GL_FLOAT, s.depth.data());
    }

    // Attaches `colours` (in order) to the framebuffer, and the key buffer when `withKeys`.
    void target(std::initializer_list<GLuint> colours, bool withKeys) {
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        GLenum buffers[3] = {};
        GLenum n = 0;
        for (GLuint t : colours) {
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + n, GL_TEXTURE_2D, t, 0);
            buffers[n] = GL_COLOR_ATTACHMENT0 + n;
            ++n;
        }
        for (GLenum k = n; k < 3; ++k) glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + k, GL_TEXTURE_2D, 0, 0);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, withKeys ? keys : 0);
        glDrawBuffers(GLsizei(n), buffers);
        glViewport(0, 0, w, h);
    }

    void fullScreen() {
        glBindVertexArray(vao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }

    // Source `slot` splatted into state[slot][0], then its cracks closed (ping to pong and back).
    void splatView(int slot, const WarpSource& s, const ImageProjection& to, float crackRatio) {
        const Camera from(s.camera, s.image.width, s.image.height);
        const Float3 o = from.origin(), c = from.corner(), u = from.du(), v = from.dv();
        const double corner[3] = {c.x, c.y, c.z}, du[3] = {u.x, u.y, u.z}, dv[3] = {v.x, v.y, v.z};
        const double shift[3] = {double(o.x) - to.origin[0], double(o.y) - to.origin[1], double(o.z) - to.origin[2]};
        double solved[4][3];
        to.solve(corner, solved[0]);
        to.solve(du, solved[1]);
        to.solve(dv, solved[2]);
        to.solve(shift, solved[3]);
        target({state[slot][0], stateDepth[slot][0]}, true);
        const GLfloat none[4] = {0, 0, 0, 0}, farthest = 1.0f;
        glDepthMask(GL_TRUE);  // before the clear: the mask holds for clears too
        glClearBufferfv(GL_COLOR, 0, none);
        glClearBufferfv(GL_COLOR, 1, none);
        glClearBufferfv(GL_DEPTH, 0, &farthest);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glUseProgram(splat);
        bindUnit(0, sourceColour[slot]);
        bindUnit(1, sourceDepth[slot]);
        glUniform1i(glGetUniformLocation(splat, "sourceColour"), 0);
        glUniform1i(glGetUniformLocation(splat, "sourceDepth"), 1);
        glUniform2i(glGetUniformLocation(splat, "sourceSize"), s.image.width, s.image.height);
        glUniform2i(glGetUniformLocation(splat, "targetSize"), w, h);
        uniform3(splat, "corner", corner);
        uniform3(splat, "du", du);
        uniform3(splat, "dv", dv);
        uniform3(splat, "shift", shift);
        uniform3(splat, "solvedCorner", solved[0]);
        uniform3(splat, "solvedDu", solved[1]);
        uniform3(splat, "solvedDv", solved[2]);
        uniform3(splat, "solvedShift", solved[3]);
        glUniform1f(glGetUniformLocation(splat, "keyScale"), std::ldexp(1.0f, -64));
        glPointSize(1.0f);
        glBindVertexArray(vao);
        glDrawArrays(GL_POINTS, 0, GLsizei(size_t(s.image.width) * size_t(s.image.height)));
        glDisable(GL_DEPTH_TEST);
        glUseProgram(crack);
        glUniform1i(glGetUniformLocation(crack, "state"), 0);
        glUniform1i(glGetUniformLocation(crack, "depth"), 1);
        glUniform1f(glGetUniformLocation(crack, "ratio"), crackRatio);
        for (int pass : {1, 2}) {
            const int in = pass == 1 ? 0 : 1, out = 1 - in;
            target({state[slot][out], stateDepth[slot][out]}, false);
            bindUnit(0, state[slot][in]);
            bindUnit(1, stateDepth[slot][in]);
            glUniform1i(glGetUniformLocation(crack, "pass"), pass);
            fullScreen();
        }
    }

    // The passes of a scan program (warp_scan.frag, warp_rowscan.frag) with step 1, 2, 4, ...
    // below `length`, ping-ponging between `textures` (starting from [0]) on targets `width`
    // wide and h high; returns which of the two holds the result.
    int scanPasses(GLuint program, const char* input, const GLuint (&textures)[2], int length, int width) {
        int current = 0;
        glUseProgram(program);
        glUniform1i(glGetUniformLocation(program, input), 0);
        for (int step = 1; step < length; step *= 2) {
            target({textures[1 - current]}, false);
            glViewport(0, 0, width, h);
            bindUnit(0, textures[current]);
            glUniform1i(glGetUniformLocation(program, "step"), step);
            fullScreen();
            current = 1 - current;
        }
        return current;
    }

    // The views (or the newest as it is) into composed, then the row scans and the fill.
    void composeAndFill(bool copySource, bool hasOlder, const WarpOptions& options, bool debug) {
        target({composed, composedDepth, sides[0]}, false);
        glUseProgram(compose);
        const char* names[5] = {"newestState", "newestDepth", "olderState", "olderDepth", "sourceColour"};
        const GLuint textures[5] = {state[0][0], stateDepth[0][0], state[1][0], stateDepth[1][0], sourceColour[0]};
        for (int i = 0; i < 5; ++i) {
            bindUnit(i, textures[i]);
            glUniform1i(glGetUniformLocation(compose, names[i]), i);
        }
        glUniform1i(glGetUniformLocation(compose, "hasOlder"), hasOlder);
        glUniform1i(glGetUniformLocation(compose, "copySource"), copySource);
        fullScreen();
        const int current = scanPasses(scan, "sides", sides, w, w);
        // Rows without a known pixel: the nearest rows that have one, above and below.
        target({rows[0]}, false);
        glViewport(0, 0, 1, h);
        glUseProgram(rowsInit);
        bindUnit(0, sides[current]);
        glUniform1i(glGetUniformLocation(rowsInit, "sides"), 0);
        fullScreen();
        const int currentRows = scanPasses(rowScan, "rows", rows, h, 1);
        target({result}, false);
        glUseProgram(fill);
        bindUnit(0, composed);
        bindUnit(1, composedDepth);
        bindUnit(2, sides[current]);
        bindUnit(3, rows[currentRows]);
        glUniform1i(glGetUniformLocation(fill, "rows"), 3);
        glUniform1i(glGetUniformLocation(fill, "composed"), 0);
        glUniform1i(glGetUniformLocation(fill, "composedDepth"), 1);
        glUniform1i(glGetUniformLocation(fill, "sides"), 2);
        glUniform3f(glGetUniformLocation(fill, "background"), float(options.background[0]) / 255.0f,
                    float(options.background[1]) / 255.0f, float(options.background[2]) / 255.0f);
        glUniform1i(glGetUniformLocation(fill, "debug"), debug);
        GLint tints[12];
        for (int i = 0; i < 12; ++i) tints[i] = kWarpTints[i / 3][i % 3];
        glUniform3iv(glGetUniformLocation(fill, "tints"), 4, tints);
        fullScreen();
    }
};

GlReprojector::GlReprojector() : impl_(std::make_unique<Impl>()) {}
GlReprojector::~GlReprojector() = default;

unsigned GlReprojector::warp(const WarpSource& newest, const CameraDesc& target, const WarpSource* older,
                             const WarpOptions& options, bool debug) {
    checkWarpSource(newest, "newest");
    if (older) checkWarpSource(*older, "older");
    Impl& m = *impl_;
    m.sizeTargets(newest.image.width, newest.image.height);
    if (m.w <= 0 || m.h <= 0) return m.result;
    m.upload(0, newest);
    const bool copy = options.copySamePose && samePose(newest.camera, target);
    if (!copy) {
        const ImageProjection to(target, m.w, m.h);
        m.splatView(0, newest, to, options.crackRatio);
        if (older && older->image.width > 0 && older->image.height > 0) {
            m.upload(1, *older);
            m.splatView(1, *older, to, options.crackRatio);
        }
    }
    m.composeAndFill(copy, older && !copy && older->image.width > 0 && older->image.height > 0, options, debug);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glActiveTexture(GL_TEXTURE0);
    return m.result;
}

unsigned GlReprojector::texture() const { return impl_->result; }
int GlReprojector::width() const { return std::max(0, impl_->w); }
int GlReprojector::height() const { return std::max(0, impl_->h); }

void GlReprojector::read(Image& image, std::vector<WarpPixel>* origins) const {
    const Impl& m = *impl_;
    const int w = width(), h = height();
    std::vector<uint8_t> rgba(size_t(w) * size_t(h) * 4);
    if (!rgba.empty()) {
        glBindFramebuffer(GL_READ_FRAMEBUFFER, m.fbo);
        glFramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, m.result, 0);
        glReadBuffer(GL_COLOR_ATTACHMENT0);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
        glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    }
    image.width = w;
    image.height = h;
    image.rgb.resize(size_t(w) * size_t(h) * 3);
    if (origins) origins->resize(size_t(w) * size_t(h));
    for (size_t i = 0; i < size_t(w) * size_t(h); ++i) {
        for (int c = 0; c < 3; ++c) image.rgb[i * 3 + size_t(c)] = rgba[i * 4 + size_t(c)];
        if (origins) (*origins)[i] = WarpPixel(std::min<uint8_t>(rgba[i * 4 + 3], 3));
    }
}

}  // namespace rtwall
