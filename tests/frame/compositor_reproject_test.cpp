// The Compositor's re-projection (issue 27): the views of the newest frame composed with depth,
// warped to the cameras of a newer pose and composed into the eyes as compose() does. At the
// rendered cameras it gives compose()'s bytes (a static head on a re-projecting wall shows the
// frames as rendered); moved, each view is exactly what the Reprojector makes of it with the
// frame before as the older source; the frame before fills what the newest left open.
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/frame.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rtwall {
namespace {

constexpr int kW = 96, kH = 72;

// A checkered floor-like wall with a box in front of it (as reproject_test.cpp's), lit from behind the viewer.
SceneDesc wallAndBox() {
    SceneDesc d;
    test::addQuadAndBox(d);
    Material wall = test::material("wall", MaterialType::Lambert, {0.9f, 0.9f, 0.9f});
    wall.texture.kind = TextureKind::Checker;
    wall.texture.color2 = {0.1f, 0.3f, 0.6f};
    d.materials = {wall, test::material("box", MaterialType::Lambert, {0.8f, 0.1f, 0.1f})};
    d.instances.push_back({0, 0, Transform::rotateDegrees(1, 0, 0, 90) * Transform::scale(10, 1, 10)});
    d.instances.push_back({1, 1, Transform::translate(0, 0, 4)});
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0.3f, -0.4f, -1.0f};
    d.lights = {sun};
    test::setImage(d.settings, kW, kH, 32);
    d.settings.threads = 1;
    return d;
}

// An eye's off-axis camera through a 4 x 3 window at z = 6.5 (a wall's view).
CameraDesc eyeAt(float x) {
    CameraDesc c;
    c.position = {x, 0.0f, 10.0f};
    c.lookAt = {x, 0.0f, 0.0f};
    c.window = ProjectionWindow{{-2.0f, -1.5f, 6.5f}, {4.0f, 0, 0}, {0, 3.0f, 0}};
    return c;
}

struct Frame {
    std::vector<FrameView> views;
    std::vector<int> eyes;
    std::vector<Image> images;
    std::vector<std::vector<float>> depth;
};

// Both eyes (`separation` apart about x) rendered with their depth; `regions`: each eye's view
// shows only one half of the image (as a CAVE's planes do), else the whole image.
Frame stereoFrame(const Scene& scene, const RenderSettings& settings, float x, float separation, bool regions) {
    Frame f;
    for (int eye : {0, 1}) {
        FrameView v;
        v.camera = eyeAt(x + (eye ? 0.5f : -0.5f) * separation);
        if (regions) {
            v.regions = {{eye ? kW / 2 : 0, 0, kW / 2, kH}};
            v.refWidth = kW;
            v.refHeight = kH;
        }
        RenderedFrame r = renderFrameWithDepth(scene, Camera(v.camera, kW, kH), settings);
        f.views.push_back(v);
        f.eyes.push_back(eye);
        f.images.push_back(std::move(r.image));
        f.depth.push_back(std::move(r.depth));
    }
    return f;
}

EyeImages compose(Compositor& c, const Frame& f, bool withDepth = true) {
    ComposeFrame cf;
    cf.views = f.views;
    cf.eyes = f.eyes;
    if (withDepth) cf.depth = f.depth;
    return c.compose(cf, f.images);
}

std::vector<CameraDesc> camerasOf(const Frame& f) {
    std::vector<CameraDesc> out;
    for (const FrameView& v : f.views) out.push_back(v.camera);
    return out;
}

TEST(CompositorReproject, AtTheRenderedCamerasItGivesComposeBytes) {
    const SceneDesc d = wallAndBox();
    const Scene scene(d);
    for (bool regions : {false, true}) {
        Compositor c;
        const Frame f = stereoFrame(scene, d.settings, 0.2f, 0.065f, regions);
        const EyeImages composed = compose(c, f);
        const EyeImages& shown = c.reproject(camerasOf(f));
        EXPECT_EQ(shown.left.rgb, composed.left.rgb) << "regions " << regions;
        EXPECT_EQ(shown.right.rgb, composed.right.rgb) << "regions " << regions;
        EXPECT_EQ(shown.left.width, kW);
        // A second frame at the same cameras: still the composed bytes (the older source is unused).
        const EyeImages again = compose(c, f);
        EXPECT_EQ(c.reproject(camerasOf(f)).left.rgb, again.left.rgb);
    }
}

TEST(CompositorReproject, EachViewIsTheReprojectorsWarpWithTheFrameBeforeAsOlder) {
    const SceneDesc d = wallAndBox();
    const Scene scene(d);
    Compositor c;
    // The head swayed: the frame before saw the box from the left, the newest from the right,
    // the refresh is between them, so the frame before saw what the newest hides.
    const Frame before = stereoFrame(scene, d.settings, -0.3f, 0.065f, false);
    const Frame newest = stereoFrame(scene, d.settings, 0.3f, 0.065f, false);
    compose(c, before);
    compose(c, newest);
    std::vector<CameraDesc> targets = camerasOf(newest);
    for (CameraDesc& t : targets) {
        t.position.x -= 0.3f;  // the head went back left
        t.lookAt.x -= 0.3f;
    }
    const EyeImages& shown = c.reproject(targets);
    for (size_t v = 0; v < 2; ++v) {
        Reprojector r;
        const WarpSource older{before.images[v], before.depth[v], before.views[v].camera};
        const WarpedView& w = r.warp({newest.images[v], newest.depth[v], newest.views[v].camera}, targets[v], &older);
        EXPECT_EQ((v ? shown.right : shown.left).rgb, w.image.rgb) << "view " << v;
        EXPECT_EQ(c.warped(v).mask, w.mask);
        EXPECT_GT(std::count(w.mask.begin(), w.mask.end(), WarpPixel::Older), 0) << "the frame before fills part of the holes";
        EXPECT_NE(w.image.rgb, newest.images[v].rgb) << "the warp moved the view";
    }
}

// Without the frame before, what it would have filled falls to the row fallback.
TEST(CompositorReproject, TheFrameBeforeIsTheOlderSourceOnlyWithTheSameViews) {
    const SceneDesc d = wallAndBox();
    const Scene scene(d);
    const Frame before = stereoFrame(scene, d.settings, -0.3f, 0.065f, false);
    const Frame newest = stereoFrame(scene, d.settings, 0.3f, 0.065f, false);
    std::vector<CameraDesc> targets = camerasOf(newest);
    for (CameraDesc& t : targets) t.position.x -= 0.3f, t.lookAt.x -= 0.3f;
    Compositor alone;
    compose(alone, newest);
    alone.reproject(targets);
    EXPECT_EQ(std::count(alone.warped(0).mask.begin(), alone.warped(0).mask.end(), WarpPixel::Older), 0);
    EXPECT_GT(alone.warped(0).holes, 0u);
    // A frame of one view between them: the two-view frame before it is no older source.
    Compositor changed;
    compose(changed, before);
    Frame mono = before;
    mono.views.resize(1), mono.eyes.resize(1), mono.images.resize(1), mono.depth.resize(1);
    compose(changed, mono);
    compose(changed, newest);
    changed.reproject(targets);
    EXPECT_EQ(std::count(changed.warped(0).mask.begin(), changed.warped(0).mask.end(), WarpPixel::Older), 0);
}

TEST(CompositorReproject, DebugColoursTintTheWarpedView) {
    const SceneDesc d = wallAndBox();
    const Scene scene(d);
    Compositor c;
    const Frame f = stereoFrame(scene, d.settings, 0.0f, 0.065f, false);
    compose(c, f);
    std::vector<CameraDesc> targets = camerasOf(f);
    targets[0].position.x += 0.2f;
    const Image left = c.reproject(targets, {}, true).left;
    Image tinted;
    warpDebugColours(c.warped(0), tinted);
    EXPECT_EQ(left.rgb, tinted.rgb);
    EXPECT_NE(left.rgb, c.reproject(targets, {}, false).left.rgb);
}

TEST(CompositorReproject, NothingToWarpOrTheWrongTargetsThrow) {
    const SceneDesc d = wallAndBox();
    const Scene scene(d);
    Compositor c;
    const Frame f = stereoFrame(scene, d.settings, 0.0f, 0.065f, false);
    EXPECT_THROW(c.reproject(camerasOf(f)), std::invalid_argument);
    compose(c, f, false);  // composed without depth: still nothing to warp
    EXPECT_EQ(c.reprojectViews(), 0u);
    EXPECT_THROW(c.reproject(camerasOf(f)), std::invalid_argument);
    compose(c, f);
    EXPECT_EQ(c.reprojectViews(), 2u);
    EXPECT_THROW(c.reproject(std::vector<CameraDesc>(1)), std::invalid_argument);
    EXPECT_NO_THROW(c.reproject(camerasOf(f)));
}

}  // namespace
}  // namespace rtwall
