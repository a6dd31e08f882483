// The GLFW / OpenGL 3.3 core presenter: one window per screen, all sharing the first window's
// context objects (textures), so the wall image is uploaded once per frame and each window
// draws its screen from it with present.frag. All windows are swapped together, back to back;
// with vsync only the first waits for the retrace, so the others do not each add a frame.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <rtwall/display.h>

#include "gl_reproject.h"
#include "swap_group.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rtwall {

namespace {

std::string gLastGlfwError;
void onGlfwError(int, const char* what) { gLastGlfwError = what ? what : "unknown GLFW error"; }

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct Screen {
    GLFWwindow* window = nullptr;
    GLuint vao = 0, program = 0;
    GLint uViewport = -1, uOutputSize = -1, uEyeMode = -1, uBlendWidth = -1, uBlendInvGamma = -1, uInvGamma = -1,
          uBrightness = -1, uTileSize = -1, uWallSize = -1, uFrameSize = -1;
};

}  // namespace

void OverlayStage::drawGl(const WallConfig& wall, size_t screen) {
    if (!overlay_ || screen != 0 || overlay_->width <= 0) return;
    const Image& o = *overlay_;
    const ScreenConfig& c = wall.screens.at(screen);
    if (!framebuffer_) {
        glGenTextures(1, &texture_);
        glGenFramebuffers(1, &framebuffer_);
        glBindTexture(GL_TEXTURE_2D, texture_);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer_);
    if (o.width != textureWidth_ || o.height != textureHeight_) {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, o.width, o.height, 0, GL_RGB, GL_UNSIGNED_BYTE, o.rgb.data());
        glFramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture_, 0);
        textureWidth_ = o.width;
        textureHeight_ = o.height;
    } else {
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, o.width, o.height, GL_RGB, GL_UNSIGNED_BYTE, o.rgb.data());
    }
    const int w = std::min(o.width, c.outputWidth - kOverlayMargin), h = std::min(o.height, c.outputHeight - kOverlayMargin);
    const int top = c.outputHeight - kOverlayMargin;
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    if (w > 0 && h > 0)  // image row 0 (the texture's first row) lands at the top: a flipped blit
        glBlitFramebuffer(0, 0, w, h, kOverlayMargin, top, kOverlayMargin + w, top - h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void OverlayStage::releaseGl() {
    glDeleteTextures(1, &texture_);
    glDeleteFramebuffers(1, &framebuffer_);
    texture_ = framebuffer_ = 0;
    textureWidth_ = textureHeight_ = 0;
}

namespace {

// A frame of warps: every view with an image and a depth per pixel, all of one size, at most the
// wall's (as checkFrameSize asks of the eyes' images).
void checkWarpFrame(const WallConfig& wall, const WallFrame& frame) {
    const Image* first = frame.warps[0].image;
    for (const ViewWarp& v : frame.warps) {
        if (!v.image || !v.depth)
            throw std::invalid_argument("GlPresenter::present: a view to warp has no image or no depth");
        const Image& i = *v.image;
        if (i.width < 1 || i.height < 1 || i.width > wall.width || i.height > wall.height || i.width != first->width ||
            i.height != first->height)
            throw std::invalid_argument("GlPresenter::present: a view to warp is " + std::to_string(i.width) + "x" +
                                        std::to_string(i.height) + ", the first " + std::to_string(first->width) + "x" +
                                        std::to_string(first->height) + ", the wall " + std::to_string(wall.width) + "x" +
                                        std::to_string(wall.height) + ": views are of one size, at most the wall's");
    }
}

}  // namespace

const char* uploadMethodName(UploadMethod m) { return m == UploadMethod::Pbo ? "pbo" : "texsubimage"; }

struct GlPresenter::Impl {
    WallConfig wall;
    std::string swapGroupLine;  // what joinSwapGroup said (empty: no swap_group asked for)
    Options options;
    std::vector<Screen> screens;
    GLuint wallTex[2] = {0, 0}, ownerTex = 0, pbo[2][2] = {{0, 0}, {0, 0}};
    int texW = 0, texH = 0;  // the frame size the wall textures hold (the wall's, or less: scaled frames)
    OverlayStage overlay;  // its framebuffer object lives in the first context: they are not shared
    int pboNext = 0;
    int ownerW = 0, ownerH = 0;
    PresentStats stats;
    InputState input;
    int lastWindow = 0;
    double lastCursor[2] = {0, 0};
    bool haveCursor = false;
    double lastSwap = 0, refresh = 60;
    bool quad = false;
    std::unique_ptr<GlReprojector> reprojector;  // made with the first frame that has warps
    GLuint warpFbo[2] = {0, 0};                  // reading a warp's result, drawing into an eye
    GLuint paintFbo = 0;                         // painting into an eye (paint())

    ~Impl() {
        if (!screens.empty()) {
            glfwMakeContextCurrent(screens[0].window);
            reprojector.reset();
            glDeleteFramebuffers(2, warpFbo);
            if (paintFbo) glDeleteFramebuffers(1, &paintFbo);
            glDeleteTextures(2, wallTex);
            glDeleteTextures(1, &ownerTex);
            glDeleteBuffers(4, &pbo[0][0]);
            overlay.releaseGl();
        }
        for (Screen& s : screens)
            if (s.window) {
                glfwMakeContextCurrent(s.window);
                glDeleteVertexArrays(1, &s.vao);
                glDeleteProgram(s.program);
                glfwDestroyWindow(s.window);
            }
        glfwTerminate();
    }

    void allocateWallTextures(int w, int h) {
        for (int e = 0; e < 2; ++e) {
            glBindTexture(GL_TEXTURE_2D, wallTex[e]);
            glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, w, h, 0, GL_RGB, GL_UNSIGNED_BYTE, nullptr);
        }
        texW = w;
        texH = h;
    }

    void upload(GLuint tex, GLuint* pbos, const Image& img) {
        glBindTexture(GL_TEXTURE_2D, tex);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        if (options.upload == UploadMethod::Pbo) {
            // Two buffers in turn, orphaned before each write, so the copy never waits for the
            // driver to finish reading last frame's data.
            glBindBuffer(GL_PIXEL_UNPACK_BUFFER, pbos[pboNext]);
            glBufferData(GL_PIXEL_UNPACK_BUFFER, GLsizeiptr(img.rgb.size()), nullptr, GL_STREAM_DRAW);
            void* dst = glMapBufferRange(GL_PIXEL_UNPACK_BUFFER, 0, GLsizeiptr(img.rgb.size()),
                                         GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
            if (dst) {
                std::memcpy(dst, img.rgb.data(), img.rgb.size());
                glUnmapBuffer(GL_PIXEL_UNPACK_BUFFER);
                glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, img.width, img.height, GL_RGB, GL_UNSIGNED_BYTE, nullptr);
            }
            glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
            if (dst) return;
        }
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, img.width, img.height, GL_RGB, GL_UNSIGNED_BYTE, img.rgb.data());
    }

    // The eyes' images from the frame's warps (issue 27), in the first context: each view warped
    // on the GPU, then blitted into its regions of its eye's wall texture (the whole texture
    // when it has none); an eye that gets regions before anything else is cleared to black
    // first, as the Compositor starts an eye from zero.
    void warpEyes(const WallFrame& frame) {
        if (!reprojector) {
            reprojector = std::make_unique<GlReprojector>();
            glGenFramebuffers(2, warpFbo);
        }
        bool written[2] = {false, false};
        glDisable(GL_SCISSOR_TEST);
        for (const ViewWarp& v : frame.warps) {
            const int eye = v.eye == 1 ? 1 : 0;
            const WarpSource newest{*v.image, *v.depth, v.camera};
            const bool hasOlder = v.olderImage && v.olderDepth;
            const WarpSource older{hasOlder ? *v.olderImage : *v.image, hasOlder ? *v.olderDepth : *v.depth, v.olderCamera};
            const GLuint result = reprojector->warp(newest, v.target, hasOlder ? &older : nullptr, WarpOptions{}, frame.warpDebug);
            glBindFramebuffer(GL_READ_FRAMEBUFFER, warpFbo[0]);
            glFramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, result, 0);
            glReadBuffer(GL_COLOR_ATTACHMENT0);
            glBindFramebuffer(GL_DRAW_FRAMEBUFFER, warpFbo[1]);
            glFramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, wallTex[eye], 0);
            const GLenum attachment = GL_COLOR_ATTACHMENT0;
            glDrawBuffers(1, &attachment);
            if (!v.regions.empty() && !written[eye]) {
                const GLfloat black[4] = {0, 0, 0, 1};
                glClearBufferfv(GL_COLOR, 0, black);
            }
            written[eye] = true;
            const std::vector<TileRect> whole{{0, 0, texW, texH}};
            for (const TileRect& r : v.regions.empty() ? whole : v.regions)  // texture row y is image row y
                glBlitFramebuffer(r.x0, r.y0, r.x1, r.y1, r.x0, r.y0, r.x1, r.y1, GL_COLOR_BUFFER_BIT, GL_NEAREST);
        }
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }

    // The frame's paints (the wand's ray) over the eyes' textures, once they are made: each
    // rectangle a scissored clear of its eye's texture (texture row y is image row y; an 8-bit
    // value v cleared as v / 255 is stored as v).
    void paint(const std::vector<EyePaint>& paints, bool haveRight) {
        if (paints.empty()) return;
        if (!paintFbo) glGenFramebuffers(1, &paintFbo);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, paintFbo);
        const GLenum attachment = GL_COLOR_ATTACHMENT0;
        glEnable(GL_SCISSOR_TEST);
        for (int eye = 0; eye < (haveRight ? 2 : 1); ++eye) {
            glFramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, wallTex[eye], 0);
            glDrawBuffers(1, &attachment);
            for (const EyePaint& p : paints) {
                const int x0 = std::max(p.rect.x0, 0), y0 = std::max(p.rect.y0, 0);
                const int x1 = std::min(p.rect.x1, texW), y1 = std::min(p.rect.y1, texH);
                if (p.eye != eye || x1 <= x0 || y1 <= y0) continue;
                glScissor(x0, y0, x1 - x0, y1 - y0);
                const GLfloat c[4] = {p.colour[0] / 255.0f, p.colour[1] / 255.0f, p.colour[2] / 255.0f, 1.0f};
                glClearBufferfv(GL_COLOR, 0, c);
            }
        }
        glDisable(GL_SCISSOR_TEST);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }

    // Screen s's present program: the shipped fragment shader or the config's; false when it
    // does not link.
    bool link(Screen& s, const ShaderSource& vert, const ShaderSource& frag, const ScreenConfig& c) {
        ShaderSource f = frag;
        if (!c.fragmentShader.empty()) {
            std::ifstream in(c.fragmentShader, std::ios::binary);
            std::ostringstream text;
            text << in.rdbuf();
            f = {c.fragmentShader.string(), text.str()};
        }
        const GLuint vs = compileShader(GL_VERTEX_SHADER, vert), fs = compileShader(GL_FRAGMENT_SHADER, f);
        s.program = glCreateProgram();
        glAttachShader(s.program, vs);
        glAttachShader(s.program, fs);
        glLinkProgram(s.program);
        glDeleteShader(vs);
        glDeleteShader(fs);
        GLint ok = 0;
        glGetProgramiv(s.program, GL_LINK_STATUS, &ok);
        if (!ok) return false;
        glUseProgram(s.program);
        glUniform1i(glGetUniformLocation(s.program, "wallLeft"), 0);
        glUniform1i(glGetUniformLocation(s.program, "wallRight"), 1);
        glUniform1i(glGetUniformLocation(s.program, "owners"), 2);
        s.uViewport = glGetUniformLocation(s.program, "viewport");
        s.uOutputSize = glGetUniformLocation(s.program, "outputSize");
        s.uEyeMode = glGetUniformLocation(s.program, "eyeMode");
        s.uBlendWidth = glGetUniformLocation(s.program, "blendWidth");
        s.uBlendInvGamma = glGetUniformLocation(s.program, "blendInvGamma");
        s.uInvGamma = glGetUniformLocation(s.program, "invGamma");
        s.uBrightness = glGetUniformLocation(s.program, "brightness");
        s.uTileSize = glGetUniformLocation(s.program, "tileSize");
        s.uWallSize = glGetUniformLocation(s.program, "wallSize");
        s.uFrameSize = glGetUniformLocation(s.program, "frameSize");
        glGenVertexArrays(1, &s.vao);  // vertex arrays are not shared between contexts
        return true;
    }

    // The window's keys, buttons, cursor and wheel go into `input`.
    static void listen(GLFWwindow* window) {
        glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int mods) {
            auto* im = static_cast<Impl*>(glfwGetWindowUserPointer(w));
            if (key < 0 || key >= int(im->input.keyDown.size())) return;
            im->input.keyDown[size_t(key)] = action != GLFW_RELEASE;
            if (action == GLFW_PRESS) {
                im->input.keysPressed.push_back(key);
                im->input.modsPressed.push_back(mods);
            }
        });
        glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int button, int action, int mods) {
            auto* im = static_cast<Impl*>(glfwGetWindowUserPointer(w));
            const bool down = action == GLFW_PRESS;
            if (button == GLFW_MOUSE_BUTTON_LEFT) {
                im->input.leftDown = down;
                if (down) {
                    im->input.leftPressed = true;
                    im->input.clickMods = mods;
                }
            } else if (button == GLFW_MOUSE_BUTTON_RIGHT) {
                im->input.rightDown = down;
            }
        });
        glfwSetCursorPosCallback(window, [](GLFWwindow* w, double x, double y) {
            auto* im = static_cast<Impl*>(glfwGetWindowUserPointer(w));
            int index = 0;
            for (size_t k = 0; k < im->screens.size(); ++k)
                if (im->screens[k].window == w) index = int(k);
            if (im->haveCursor && index == im->lastWindow && (im->input.leftDown || im->input.rightDown)) {
                im->input.mouseDx += x - im->lastCursor[0];
                im->input.mouseDy += y - im->lastCursor[1];
            }
            im->haveCursor = true;
            im->lastWindow = index;
            im->lastCursor[0] = x;
            im->lastCursor[1] = y;
            const ScreenConfig& sc = im->wall.screens[size_t(index)];
            im->input.wallX = sc.viewport.x + x * sc.viewport.width / sc.outputWidth;
            im->input.wallY = sc.viewport.y + y * sc.viewport.height / sc.outputHeight;
        });
        glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) {
            static_cast<Impl*>(glfwGetWindowUserPointer(w))->input.scroll += dy;
        });
    }

    void draw(size_t i, int eyeMode, int tileSize) {
        const ScreenConfig& c = wall.screens[i];
        const Screen& s = screens[i];
        glUseProgram(s.program);
        glUniform4i(s.uViewport, c.viewport.x, c.viewport.y, c.viewport.width, c.viewport.height);
        glUniform2i(s.uOutputSize, c.outputWidth, c.outputHeight);
        glUniform1i(s.uEyeMode, eyeMode);
        glUniform4i(s.uBlendWidth, c.blend[0], c.blend[1], c.blend[2], c.blend[3]);
        glUniform4f(s.uBlendInvGamma, float(1.0 / c.blendGamma[0]), float(1.0 / c.blendGamma[1]), float(1.0 / c.blendGamma[2]),
                    float(1.0 / c.blendGamma[3]));
        glUniform1f(s.uInvGamma, float(1.0 / c.gamma));
        glUniform1f(s.uBrightness, float(c.brightness));
        glUniform1i(s.uTileSize, tileSize);
        glUniform2i(s.uWallSize, wall.width, wall.height);
        glUniform2i(s.uFrameSize, texW, texH);
        glBindVertexArray(s.vao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
};

GlPresenter::GlPresenter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GlPresenter::~GlPresenter() = default;

std::unique_ptr<GlPresenter> GlPresenter::open(const WallConfig& wall, const Options& options, std::string* whyNot) {
    auto no = [&](const std::string& why) -> std::unique_ptr<GlPresenter> {
        if (whyNot) *whyNot = why;
        return nullptr;
    };
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if ((!display || !*display) && (!wayland || !*wayland)) return no("no DISPLAY");
    glfwSetErrorCallback(onGlfwError);
    if (!glfwInit()) return no("GLFW does not start: " + gLastGlfwError);
    auto impl = std::make_unique<Impl>();  // from here on, its destructor calls glfwTerminate
    impl->wall = wall;
    impl->options = options;
    impl->quad = wall.stereo.mode == StereoMode::QuadBuffer;
    int monitorCount = 0;
    GLFWmonitor** monitors = glfwGetMonitors(&monitorCount);
    if (monitorCount > 0)
        if (const GLFWvidmode* mode = glfwGetVideoMode(monitors[0]); mode && mode->refreshRate > 0) impl->refresh = mode->refreshRate;

    ShaderSource vert = presentVertexShader(), frag = presentFragmentShader();
    for (size_t i = 0; i < wall.screens.size(); ++i) {
        const ScreenConfig& c = wall.screens[i];
        glfwDefaultWindowHints();
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
        glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
        glfwWindowHint(GLFW_DECORATED, wall.screens.size() == 1 ? GLFW_TRUE : GLFW_FALSE);
        if (impl->quad) glfwWindowHint(GLFW_STEREO, GLFW_TRUE);
        GLFWmonitor* monitor = nullptr;
        if (c.fullscreen) {
            if (c.monitor >= monitorCount)
                return no("screen '" + c.name + "' wants monitor " + std::to_string(c.monitor) + ", there are " +
                          std::to_string(monitorCount));
            monitor = monitors[c.monitor];
        }
        const std::string title = "rtwall: " + wall.name + " / " + c.name;
        GLFWwindow* share = impl->screens.empty() ? nullptr : impl->screens[0].window;
        GLFWwindow* win = glfwCreateWindow(c.outputWidth, c.outputHeight, title.c_str(), monitor, share);
        if (!win)
            return no("no OpenGL 3.3 core window for screen '" + c.name + "'" + (impl->quad ? " (quad-buffered stereo)" : "") +
                      ": " + gLastGlfwError);
        impl->screens.push_back({});
        Screen& s = impl->screens.back();
        s.window = win;
        if (!monitor) glfwSetWindowPos(win, c.window[0], c.window[1]);
        glfwSetWindowUserPointer(win, impl.get());
        glfwMakeContextCurrent(win);
        glfwSwapInterval(i == 0 && (options.vsyncOverride < 0 ? wall.vsync : options.vsyncOverride == 1) ? 1 : 0);

        if (!impl->link(s, vert, frag, c)) return no("the present shaders of screen '" + c.name + "' do not link");
        Impl::listen(win);
    }

    // Textures and pixel buffers live in the first context and are shared by all.
    Impl& im = *impl;
    glfwMakeContextCurrent(im.screens[0].window);
    glGenTextures(2, im.wallTex);
    glGenTextures(1, &im.ownerTex);
    glGenBuffers(4, &im.pbo[0][0]);
    for (GLuint t : {im.wallTex[0], im.wallTex[1], im.ownerTex}) {
        glBindTexture(GL_TEXTURE_2D, t);
        // The wall textures are read with texelFetch at the wall's size, and filtered (bilinear,
        // as presentScreen's resizeBilinear) when a frame is smaller; the owner texture per tile.
        const GLint filter = t == im.ownerTex ? GL_NEAREST : GL_LINEAR;
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    im.allocateWallTextures(wall.width, wall.height);
    if (glGetError() != GL_NO_ERROR) return no("OpenGL refuses a " + std::to_string(wall.width) + "x" + std::to_string(wall.height) + " texture");
    if (wall.swapGroup > 0) {
        std::vector<GLFWwindow*> windows;
        for (const Screen& sc : impl->screens) windows.push_back(sc.window);
        impl->swapGroupLine = detail::joinSwapGroup(windows, wall.swapGroup, wall.swapBarrier);
        std::fprintf(stderr, "rtwall: %s\n", impl->swapGroupLine.c_str());
        glfwMakeContextCurrent(impl->screens[0].window);
    }
    return std::unique_ptr<GlPresenter>(new GlPresenter(std::move(impl)));
}

void GlPresenter::present(const WallFrame& frame, const PresentOptions& options, std::vector<Image>* capture) {
    Impl& im = *impl_;
    const WallConfig& wall = im.wall;
    const bool warping = !frame.warps.empty();
    if (warping) checkWarpFrame(wall, frame);
    else checkFrameSize(wall, frame, "GlPresenter::present");
    const int frameW = warping ? frame.warps[0].image->width : frame.left.width;
    const int frameH = warping ? frame.warps[0].image->height : frame.left.height;
    const bool haveRight = warping ? std::any_of(frame.warps.begin(), frame.warps.end(), [](const ViewWarp& v) { return v.eye == 1; })
                                   : !frame.right.rgb.empty();

    double t0 = now();
    glfwMakeContextCurrent(im.screens[0].window);
    if (frameW != im.texW || frameH != im.texH) im.allocateWallTextures(frameW, frameH);
    if (warping) {
        im.warpEyes(frame);
    } else {
        im.upload(im.wallTex[0], im.pbo[0], frame.left);
        if (haveRight) im.upload(im.wallTex[1], im.pbo[1], frame.right);
        im.pboNext ^= 1;
    }
    im.paint(frame.paints, haveRight);
    const int tileSize = options.falseColour && frame.tileSize > 0 ? frame.tileSize : 0;
    if (tileSize > 0) {
        // One texel per tile with the colour of its client: tiny, uploaded directly.
        const int tw = (frameW + tileSize - 1) / tileSize, th = (frameH + tileSize - 1) / tileSize;
        std::vector<uint8_t> rgb(size_t(tw) * th * 3);
        for (size_t t = 0; t < size_t(tw) * th; ++t) {
            const auto c = ownerColour(t < frame.tileOwners.size() ? frame.tileOwners[t] : UINT32_MAX);
            std::memcpy(&rgb[3 * t], c.data(), 3);
        }
        glBindTexture(GL_TEXTURE_2D, im.ownerTex);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        if (tw != im.ownerW || th != im.ownerH) {
            glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, tw, th, 0, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
            im.ownerW = tw;
            im.ownerH = th;
        } else {
            glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, tw, th, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
        }
    }
    glFlush();  // the other contexts see the new texture contents only after this
    double t1 = now();
    im.stats.uploadSeconds += t1 - t0;

    if (capture) capture->assign(im.screens.size(), Image{});
    for (size_t i = 0; i < im.screens.size(); ++i) {
        const ScreenConfig& c = wall.screens[i];
        glfwMakeContextCurrent(im.screens[i].window);
        int fw = 0, fh = 0;
        glfwGetFramebufferSize(im.screens[i].window, &fw, &fh);
        glViewport(0, 0, fw, fh);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, im.wallTex[0]);
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, im.wallTex[haveRight ? 1 : 0]);
        glActiveTexture(GL_TEXTURE2);
        glBindTexture(GL_TEXTURE_2D, im.ownerTex);
        const bool quad = im.quad && c.eye == Eye::Both;
        const int eyeMode = c.eye == Eye::Right ? 1 : (c.eye == Eye::Both && wall.stereo.mode == StereoMode::SideBySide ? 2 : 0);
        if (quad) {
            glDrawBuffer(GL_BACK_LEFT);
            im.draw(i, 0, tileSize);
            glDrawBuffer(GL_BACK_RIGHT);
            im.draw(i, 1, tileSize);
            glDrawBuffer(GL_BACK);
        } else {
            im.draw(i, eyeMode, tileSize);
        }
        // The screen's stages, then the overlay on top (as presentScreen runs them).
        for (ScreenStage* stage : options.stages) stage->drawGl(wall, i);
        im.overlay.set(options.overlay);
        im.overlay.drawGl(wall, i);
        if (capture) {
            Image& img = (*capture)[i];
            img.width = c.outputWidth;
            img.height = c.outputHeight;
            img.rgb.resize(size_t(img.width) * img.height * 3);
            std::vector<uint8_t> rows(img.rgb.size());
            glReadBuffer(quad ? GL_BACK_LEFT : GL_BACK);
            glPixelStorei(GL_PACK_ALIGNMENT, 1);
            glReadPixels(0, 0, img.width, img.height, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
            const size_t stride = size_t(img.width) * 3;
            for (int y = 0; y < img.height; ++y)  // OpenGL's row 0 is the bottom row
                std::memcpy(&img.rgb[size_t(y) * stride], &rows[size_t(img.height - 1 - y) * stride], stride);
        }
    }
    double t2 = now();
    im.stats.drawSeconds += t2 - t1;
    for (Screen& s : im.screens) glfwSwapBuffers(s.window);
    double t3 = now();
    im.stats.swapSeconds += t3 - t2;
    const bool vsync = im.options.vsyncOverride < 0 ? wall.vsync : im.options.vsyncOverride == 1;
    if (vsync && im.lastSwap > 0 && t3 - im.lastSwap > 1.5 / im.refresh) ++im.stats.late;
    im.lastSwap = t3;
    ++im.stats.frames;
}

InputState GlPresenter::poll() {
    Impl& im = *impl_;
    glfwPollEvents();
    for (Screen& s : im.screens)
        if (glfwWindowShouldClose(s.window)) im.input.closeRequested = true;
    InputState out = im.input;
    im.input.keysPressed.clear();
    im.input.modsPressed.clear();
    im.input.mouseDx = im.input.mouseDy = im.input.scroll = 0;
    im.input.leftPressed = false;
    return out;
}

void GlPresenter::setStatus(const std::string& text) { glfwSetWindowTitle(impl_->screens[0].window, text.c_str()); }

const PresentStats& GlPresenter::stats() const { return impl_->stats; }

const std::string& GlPresenter::swapGroup() const { return impl_->swapGroupLine; }

std::string GlPresenter::renderer() const {
    glfwMakeContextCurrent(impl_->screens[0].window);
    const GLubyte* r = glGetString(GL_RENDERER);
    return r ? reinterpret_cast<const char*>(r) : "unknown";
}

}  // namespace rtwall
