// The GL warp (display/src/gl_reproject.cpp) against the CPU warp (rtwall/reproject.h), under
// Xvfb with Mesa's llvmpipe: the same inputs give the same image and the same origins (mask)
// but for points that the float arithmetic of the shader puts across a pixel's edge from where
// the CPU's double arithmetic puts them. Tolerance, justified by that: at least 99.9 % of the
// pixels identical in colour and in origin (the measured share is printed, 99.997 % and more
// here), the hole counts within 0.1 % of the pixels, and every pixel of a surface that differs
// shows a colour the CPU result has within 2 pixels of it (a point moved by a rounding lands
// in the next pixel; a hole's fill may come from that neighbour). A warp to the own pose,
// through the warp itself and through the copy, gives the view bit for bit.
#include "display_test_util.h"
#include "gl_reproject.h"
#include "test_util.h"
#include "xvfb_server.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <rtwall/engine.h>
#include <rtwall/reproject.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace rtwall {
namespace {

const auto* const gXvfb = ::testing::AddGlobalTestEnvironment(new test::XvfbServer);

// A hidden window's OpenGL 3.3 core context, current while the fixture lives.
class GlWarp : public ::testing::Test {
protected:
    void SetUp() override {
        ASSERT_TRUE(glfwInit());
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
        window_ = glfwCreateWindow(64, 64, "gl warp test", nullptr, nullptr);
        ASSERT_NE(window_, nullptr);
        glfwMakeContextCurrent(window_);
        gl_ = std::make_unique<GlReprojector>();
    }
    void TearDown() override {
        gl_.reset();
        if (window_) glfwDestroyWindow(window_);
        glfwTerminate();
    }
    GLFWwindow* window_ = nullptr;
    std::unique_ptr<GlReprojector> gl_;
};

struct View {
    Image image;
    std::vector<float> depth;
    CameraDesc camera;
    WarpSource source() const { return {image, depth, camera}; }
};

// A floor with a raised block and sky above (as timeReprojection's), with a texture of
// distinct colours and a sky of a different colour in every pixel (so that which of two equally
// far points wins shows), seen from `camera`: the block uncovers floor when the head moves.
View synthetic(int width, int height, const CameraDesc& camera) {
    View v{{}, std::vector<float>(size_t(width) * size_t(height)), camera};
    v.image.width = width;
    v.image.height = height;
    v.image.rgb.resize(size_t(width) * size_t(height) * 3);
    const Camera cam(camera, width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            const Float3 d = cam.direction(float(x) + 0.5f, float(y) + 0.5f), o = cam.origin();
            float t = d.y < 0 ? -o.y / d.y : -1;  // the floor y = 0
            const Float3 p = o + d * t;
            // The block: x in [-0.3, 0.3], z in [-0.3, 0.3], its top at y = 0.4, seen from above.
            const float top = d.y < 0 ? (0.4f - o.y) / d.y : -1;
            const Float3 q = o + d * top;
            const bool onBlock = top > 0 && std::fabs(q.x) < 0.3f && std::fabs(q.z) < 0.3f;
            if (onBlock) t = top;
            v.depth[i] = t > 0 ? t * length(d) : kBackgroundDepth;
            const Float3 at = onBlock ? q : p;
            const int cx = int(std::floor(at.x * 8)), cz = int(std::floor(at.z * 8));
            for (int c = 0; c < 3; ++c)
                v.image.rgb[i * 3 + size_t(c)] =
                    t > 0 ? uint8_t((cx * 37 + cz * 91 + c * 60 + (onBlock ? 128 : 0)) & 0xFF) : uint8_t((x * 5 + y * 3 + c * 40) & 0xFF);
        }
    return v;
}

CameraDesc lookingAt(Float3 position, float fovY = 50, Float3 at = {0, 0, 0}) {
    CameraDesc c;
    c.position = position;
    c.lookAt = at;
    c.fovY = fovY;
    return c;
}

// The GL warp's image and origins against the CPU warp's (see the top of the file).
void expectAgreement(GlReprojector& gl, const WarpSource& newest, const CameraDesc& target, const WarpSource* older,
                     const WarpOptions& options, bool debug, const char* what) {
    Reprojector cpu;
    const WarpedView& truth = cpu.warp(newest, target, older, options);
    Image expected = truth.image;
    if (debug) warpDebugColours(truth, expected);
    gl.warp(newest, target, older, options, debug);
    Image shown;
    std::vector<WarpPixel> origins;
    gl.read(shown, &origins);
    ASSERT_EQ(shown.width, expected.width);
    ASSERT_EQ(shown.height, expected.height);
    const int w = shown.width, h = shown.height;
    size_t same = 0, sameOrigin = 0, far = 0, holes = 0, fromOlder = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            auto pixel = [](const Image& im, size_t k) { return std::array<uint8_t, 3>{im.rgb[k * 3], im.rgb[k * 3 + 1], im.rgb[k * 3 + 2]}; };
            sameOrigin += origins[i] == truth.mask[i];
            holes += origins[i] == WarpPixel::Older || origins[i] == WarpPixel::Filled;
            fromOlder += origins[i] == WarpPixel::Older;
            if (pixel(shown, i) == pixel(expected, i)) {
                ++same;
                continue;
            }
            // In a minified sky (every source pixel its own colour) the point a rounding lets
            // win may be one that wins nowhere on the CPU: its colour is then nowhere near.
            if (truth.depth[i] == kBackgroundDepth) continue;
            bool near = false;
            for (int dy = -2; dy <= 2 && !near; ++dy)
                for (int dx = -2; dx <= 2 && !near; ++dx) {
                    const int nx = std::clamp(x + dx, 0, w - 1), ny = std::clamp(y + dy, 0, h - 1);
                    near = pixel(shown, i) == pixel(expected, size_t(ny) * size_t(w) + size_t(nx));
                }
            far += !near;
        }
    const double n = double(w) * double(h);
    std::printf("[ %s ] %dx%d: %.3f %% of colours, %.3f %% of origins identical; holes GL %zu, CPU %zu, %zu from the older view\n",
                what, w, h, 100.0 * double(same) / n, 100.0 * double(sameOrigin) / n, holes, truth.holes, fromOlder);
    if (older) {
        EXPECT_GT(fromOlder, 0u) << what << ": the older view should fill some holes";
    }
    EXPECT_GE(double(same), 0.999 * n) << what;
    EXPECT_GE(double(sameOrigin), 0.999 * n) << what;
    EXPECT_EQ(far, 0u) << what << ": surface pixels whose colour the CPU warp has nowhere within 2 pixels";
    EXPECT_NEAR(double(holes), double(truth.holes), 0.001 * n) << what;
}

TEST_F(GlWarp, ASyntheticDisocclusionWarpsAsOnTheCpu) {
    const View a = synthetic(200, 150, lookingAt({0, 1.2f, 2.0f})), c = synthetic(200, 150, lookingAt({0.5f, 1.2f, 2.0f}));
    const CameraDesc b = lookingAt({0.25f, 1.15f, 1.9f});
    Reprojector cpu;
    ASSERT_GT(cpu.warp(a.source(), b).holes, 200u) << "the block should uncover floor";
    const WarpSource older = c.source();
    expectAgreement(*gl_, a.source(), b, nullptr, {}, false, "synthetic");
    expectAgreement(*gl_, a.source(), b, &older, {}, false, "synthetic + older");
    WarpOptions options;
    options.background[0] = 200;  // rows the new pose sees beyond the view: the nearest row's pixels (the background never)
    // Looking at the horizon, stepped back and zoomed out: several sky pixels, all equally far,
    // land in one pixel, and the first of them wins.
    const View horizon = synthetic(200, 150, lookingAt({0, 1.2f, 2.0f}, 50, {0, 1.0f, 0}));
    expectAgreement(*gl_, horizon.source(), lookingAt({0.1f, 1.2f, 2.6f}, 75, {0, 1.0f, 0}), nullptr, options, false,
                    "synthetic, zoomed out");
    expectAgreement(*gl_, a.source(), b, &older, {}, true, "synthetic, debug view");
}

TEST_F(GlWarp, ARenderedFrameWarpsAsOnTheCpu) {
    SceneDesc d = test::demoScene(240, 180);
    d.settings.threads = 2;
    d.settings.shading = ShadingMode::EyeLight;
    const Scene scene(d);
    const CameraDesc a = d.cameras.front(), c = orbitCamera(a, 3.0);
    CameraDesc b = orbitCamera(a, 1.5);
    b.position.y += 0.1f;
    RenderedFrame fa = renderFrameWithDepth(scene, Camera(a, 240, 180), d.settings);
    RenderedFrame fc = renderFrameWithDepth(scene, Camera(c, 240, 180), d.settings);
    const WarpSource newest{fa.image, fa.depth, a}, older{fc.image, fc.depth, c};
    expectAgreement(*gl_, newest, b, nullptr, {}, false, "demo");
    expectAgreement(*gl_, newest, b, &older, {}, false, "demo + older");
    expectAgreement(*gl_, newest, b, &older, {}, true, "demo, debug view");
    // Depth that is no depth is a hole on both (and never a crash).
    std::vector<float> broken = fa.depth;
    for (size_t i = 0; i < broken.size(); i += 5) broken[i] = i % 2 ? std::nanf("") : -1.0f;
    expectAgreement(*gl_, {fa.image, broken, a}, b, nullptr, {}, false, "demo, broken depth");
}

// The own pose: through the splats (every pixel lands on itself, all warped) and through the
// copy (all fresh), the view's bytes.
TEST_F(GlWarp, TheOwnPoseGivesTheViewBitForBit) {
    const View a = synthetic(160, 120, lookingAt({0.1f, 1.3f, 2.0f}));
    for (bool copy : {false, true}) {
        WarpOptions options;
        options.copySamePose = copy;
        gl_->warp(a.source(), a.camera, nullptr, options);
        Image shown;
        std::vector<WarpPixel> origins;
        gl_->read(shown, &origins);
        EXPECT_EQ(shown.rgb, a.image.rgb) << (copy ? "copy" : "warp");
        EXPECT_EQ(size_t(std::count(origins.begin(), origins.end(), copy ? WarpPixel::Fresh : WarpPixel::Warped)),
                  origins.size());
    }
    std::vector<float> short_(a.depth.begin(), a.depth.end() - 1);
    EXPECT_THROW(gl_->warp({a.image, short_, a.camera}, a.camera), std::invalid_argument);
}

// A GL presenter of `wall` in hidden windows (null, and why, where none opens).
std::unique_ptr<GlPresenter> hiddenPresenter(const WallConfig& wall, std::string& why) {
    GlPresenter::Options o;
    o.visible = false;
    return GlPresenter::open(wall, o, &why);
}

// The GL presenter with warps (WallFrame::warps): two views, each warped to its own target,
// into the left half and the top right quarter of the eye (the bottom right quarter black),
// show what the CPU warps composed into the eye (as the Compositor copies regions) show through
// the headless presenter, to the tolerance above (99.9 % of the pixels identical); and so does
// the debug view.
TEST(GlPresenterWarps, TheEyeShowsTheCpuWarpsComposed) {
    const int w = 160, h = 120;
    const WallConfig wall = singleScreenWall(w, h);
    std::string why;
    const std::unique_ptr<GlPresenter> gl = hiddenPresenter(wall, why);
    ASSERT_TRUE(gl) << why;
    const View a = synthetic(w, h, lookingAt({0, 1.2f, 2.0f})), b = synthetic(w, h, lookingAt({0.4f, 1.0f, 2.2f}));
    const View c = synthetic(w, h, lookingAt({0.5f, 1.2f, 2.0f}));
    WallFrame frame;
    frame.number = 1;
    ViewWarp va;
    va.regions = {{0, 0, w / 2, h}};
    va.image = &a.image;
    va.depth = &a.depth;
    va.camera = a.camera;
    va.olderImage = &c.image;
    va.olderDepth = &c.depth;
    va.olderCamera = c.camera;
    va.target = lookingAt({0.25f, 1.15f, 1.9f});
    ViewWarp vb;
    vb.regions = {{w / 2, 0, w, h / 2}};
    vb.image = &b.image;
    vb.depth = &b.depth;
    vb.camera = b.camera;
    vb.target = lookingAt({0.3f, 1.1f, 2.1f});
    frame.warps = {va, vb};
    for (bool debug : {false, true}) {
        frame.warpDebug = debug;
        std::vector<Image> shown;
        gl->present(frame, {}, &shown);
        WallFrame cpu;
        cpu.left.width = w;
        cpu.left.height = h;
        cpu.left.rgb.assign(size_t(w) * size_t(h) * 3, 0);
        Reprojector warper;
        for (const ViewWarp& v : frame.warps) {
            const WarpSource older{v.olderImage ? *v.olderImage : *v.image, v.olderDepth ? *v.olderDepth : *v.depth, v.olderCamera};
            const WarpedView& out = warper.warp({*v.image, *v.depth, v.camera}, v.target, v.olderImage ? &older : nullptr);
            Image img = out.image;
            if (debug) warpDebugColours(out, img);
            for (const TileRect& r : v.regions)
                for (int y = r.y0; y < r.y1; ++y)
                    std::copy_n(img.rgb.begin() + ptrdiff_t((size_t(y) * size_t(w) + size_t(r.x0)) * 3), size_t(r.width()) * 3,
                                cpu.left.rgb.begin() + ptrdiff_t((size_t(y) * size_t(w) + size_t(r.x0)) * 3));
        }
        const Image expected = presentScreen(wall, 0, cpu, {});
        ASSERT_EQ(shown.size(), 1u);
        ASSERT_EQ(shown[0].rgb.size(), expected.rgb.size());
        size_t same = 0;
        for (size_t i = 0; i < size_t(w) * size_t(h); ++i)
            same += std::equal(&shown[0].rgb[i * 3], &shown[0].rgb[i * 3 + 3], &expected.rgb[i * 3]);
        std::printf("[ presenter%s ] %.3f %% of the pixels identical\n", debug ? ", debug view" : "", 100.0 * double(same) / double(w * h));
        EXPECT_GE(double(same), 0.999 * double(w * h)) << (debug ? "debug view" : "");
    }
}

// The wand's ray over a warped frame (WallFrame::paints): the GL presenter paints it after its
// warp, where the eye image never passes through the CPU, exactly in the ray's colour, the rest
// as the CPU warp to the tolerance above; over an uploaded frame it shows what the headless
// presenter shows of the same frame with the same paints, byte for byte.
TEST(GlPresenterWarps, PaintsAreDrawnOverTheWarpedEye) {
    const int w = 160, h = 120;
    const WallConfig wall = singleScreenWall(w, h);
    std::string why;
    const std::unique_ptr<GlPresenter> gl = hiddenPresenter(wall, why);
    ASSERT_TRUE(gl) << why;
    const View a = synthetic(w, h, lookingAt({0, 1.2f, 2.0f}));
    WallFrame frame;
    frame.number = 1;
    ViewWarp va;
    va.image = &a.image;
    va.depth = &a.depth;
    va.camera = a.camera;
    va.target = lookingAt({0.2f, 1.15f, 1.9f});
    frame.warps = {va};
    const std::array<uint8_t, 3> yellow{255, 230, 40};
    frame.paints = {{0, {10, 10, 30, 12}, yellow}, {0, {50, 60, 52, 90}, yellow}, {0, {150, 100, 170, 130}, {9, 99, 199}}};
    std::vector<Image> shown;
    gl->present(frame, {}, &shown);
    ASSERT_EQ(shown.size(), 1u);
    Reprojector warper;
    WallFrame cpu;
    cpu.left = warper.warp({a.image, a.depth, a.camera}, va.target).image;
    applyPaints(frame.paints, 0, cpu.left);
    const Image expected = presentScreen(wall, 0, cpu, {});
    ASSERT_EQ(shown[0].rgb.size(), expected.rgb.size());
    size_t same = 0, painted = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            const bool eq = std::equal(&shown[0].rgb[i * 3], &shown[0].rgb[i * 3 + 3], &expected.rgb[i * 3]);
            same += eq;
            bool inPaint = false;
            for (const EyePaint& p : frame.paints)
                inPaint |= x >= p.rect.x0 && x < p.rect.x1 && y >= p.rect.y0 && y < p.rect.y1;
            if (inPaint) {
                ++painted;
                EXPECT_TRUE(eq) << x << "," << y << ": a painted pixel";
            }
        }
    EXPECT_EQ(painted, size_t(20 * 2 + 2 * 30 + 10 * 20));
    EXPECT_GE(double(same), 0.999 * double(w * h));
    // An uploaded frame with paints: the headless presenter's bytes.
    WallFrame plain;
    plain.number = 2;
    plain.left = a.image;
    plain.paints = frame.paints;
    gl->present(plain, {}, &shown);
    const auto dir = test::scratchDir();
    WallConfig written = wall;
    written.writeEvery = 1;
    HeadlessPresenter headless(written, dir);
    headless.present(plain, {});
    ASSERT_EQ(headless.written().size(), 1u);
    EXPECT_EQ(shown[0].rgb, readPng(headless.written()[0]).rgb);
}

}  // namespace
}  // namespace rtwall
