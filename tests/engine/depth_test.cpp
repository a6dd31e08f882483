// Depth with every tile (issue 27): renderTile's optional depth output is the distance along
// each pixel's primary ray, kBackgroundDepth where the ray escapes; asking for it leaves the
// colour bytes as they are. The single-ray kernel gives the same depth bit for bit in blocks of
// every width; packets of every width give the same background and the same hits, at distances
// within 4 units in the last place: Embree's packet intersectors round a few hit distances
// (a handful of pixels a frame) one or two ulps apart from rtcIntersect1's, 1e-3 of the wire
// codec's step, which the 8-bit colour never shows (packet_width_test.cpp).
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/engine.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>

namespace rtwall {
namespace {

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// The largest distance in units in the last place between two buffers of positive floats
// (a background pixel against a hit is as far as can be).
uint32_t worstUlps(const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size()) return UINT32_MAX;
    uint32_t worst = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        int32_t x, y;
        std::memcpy(&x, &a[i], 4);
        std::memcpy(&y, &b[i], 4);
        worst = std::max(worst, uint32_t(std::min<int64_t>(std::abs(int64_t(x) - int64_t(y)), UINT32_MAX)));
    }
    return worst;
}

// Renders `frame` with the single-ray kernel, then with packets of every width and with the
// single-ray kernel in blocks of every width: colour and depth must match bit for bit, and the
// colour must be what renderFrame gives without depth.
void expectDepthAgreesEverywhere(const SceneDesc& d, uint32_t frame) {
    const Scene scene(d);
    const Camera camera(d.cameras.front(), d.settings.width, d.settings.height);
    RenderSettings single = d.settings;
    single.kernel = KernelType::Single;
    const RenderedFrame reference = renderFrameWithDepth(scene, camera, single, frame);
    EXPECT_EQ(reference.image.rgb, renderFrame(scene, camera, single, frame).rgb) << "depth changed the colour";
    size_t background = 0;
    for (float v : reference.depth) background += v == kBackgroundDepth;
    EXPECT_GT(background, 0u) << "the scene should show some background";
    EXPECT_LT(background, reference.depth.size()) << "the scene should show some surface";
    for (int width : {4, 8, 16})
        for (KernelType kernel : {KernelType::Packet, KernelType::Single}) {
            RenderSettings s = d.settings;
            s.kernel = kernel;
            TraceOptions trace;
            trace.packetWidth = width;
            const RenderedFrame got = renderFrameWithDepth(scene, camera, s, frame, trace);
            const char* name = kernel == KernelType::Packet ? "packets of " : "single rays in blocks of ";
            EXPECT_EQ(got.image.rgb, reference.image.rgb) << name << width;
            if (kernel == KernelType::Single)
                EXPECT_TRUE(sameBits(got.depth, reference.depth)) << name << width << ", frame " << frame;
            else
                EXPECT_LE(worstUlps(got.depth, reference.depth), 4u) << name << width << ", frame " << frame;
        }
}

// Every material (alpha masks, glass, a volume) cut by a section plane with caps, above a floor
// that does not fill the view; full shading, eye light and path tracing (stochastic: jittered
// sub-pixel positions, so two frames).
TEST(KernelDepth, EveryWidthAndBothKernelsGiveTheSameDepth) {
    SceneDesc d = test::materialZoo(test::scratchDir(), 96, 64);
    d.settings.threads = 2;
    d.cameras.front() = test::cameraAt({0, 3, 9}, {0, 0, 0});
    d.sections[0].enabled = true;
    d.sections[0].point = {0.2f, 0, 0};
    d.sections[0].normal = {-1, 0, 0.3f};
    expectDepthAgreesEverywhere(d, 1);
    d.settings.shading = ShadingMode::EyeLight;
    expectDepthAgreesEverywhere(d, 1);
    d.settings.shading = ShadingMode::Full;
    d.settings.gi = true;
    d.settings.supersample = 2;
    for (uint32_t f = 1; f <= 2; ++f) expectDepthAgreesEverywhere(d, f);
}

// A square of side 2 at y = 0 seen from 4 units above: every pixel whose centre ray meets it
// has depth 4 |d| / |d.y| (the distance along the ray, not eye-space z), the rest the marker.
TEST(KernelDepth, IsTheDistanceAlongThePrimaryRay) {
    SceneDesc d;
    test::addQuadAndBox(d);
    d.materials.push_back(test::material("white", MaterialType::Lambert, {1, 1, 1}));
    d.instances.push_back({0, 0, Transform{}});
    d.cameras.push_back(test::cameraAt({0.3f, 4, 0.2f}, {0.3f, 0, 0.2f}, 45.0f, {0, 0, -1}));
    test::setImage(d.settings, 80, 60, 16);
    d.settings.threads = 1;
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 80, 60);
    const RenderedFrame f = renderFrameWithDepth(scene, camera, d.settings);
    size_t hits = 0, misses = 0;
    for (int y = 0; y < 60; ++y)
        for (int x = 0; x < 80; ++x) {
            const Float3 dir = camera.direction(float(x) + 0.5f, float(y) + 0.5f);
            const Float3 at = camera.origin() + dir * (-camera.origin().y / dir.y);  // on y = 0
            const float got = f.depth[size_t(y) * 80 + size_t(x)];
            const bool inside = std::fabs(at.x) < 0.98f && std::fabs(at.z) < 0.98f;
            const bool outside = std::fabs(at.x) > 1.02f || std::fabs(at.z) > 1.02f;
            if (inside) {
                ++hits;
                EXPECT_NEAR(got, 4.0f * length(dir) / std::fabs(dir.y), 2e-5f * got) << x << "," << y;
            } else if (outside) {
                ++misses;
                EXPECT_EQ(got, kBackgroundDepth) << x << "," << y;
            }
        }
    EXPECT_GT(hits, 1000u);
    EXPECT_GT(misses, 500u);
}

// The linear path writes the same depth as the 8-bit one, and the tile's rows go where the
// strides say.
TEST(KernelDepth, LinearTilesCarryTheSameDepth) {
    SceneDesc d = test::materialZoo(test::scratchDir(), 64, 48);
    const Scene scene(d);
    const Camera camera(d.cameras.front(), 64, 48);
    const RenderedFrame whole = renderFrameWithDepth(scene, camera, d.settings);
    const TileRect rect{8, 4, 40, 30};
    std::vector<float> rgb(64 * 48 * 3), depth(64 * 48, -1.0f);
    renderTileLinear(scene, camera, rect, 0, d.settings, rgb.data() + (4 * 64 + 8) * 3, 64 * 3,
                     DepthView{depth.data() + 4 * 64 + 8, 64});
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) {
            const size_t i = size_t(y) * 64 + size_t(x);
            const bool in = x >= rect.x0 && x < rect.x1 && y >= rect.y0 && y < rect.y1;
            EXPECT_EQ(depth[i], in ? whole.depth[i] : -1.0f) << x << "," << y;
        }
}

}  // namespace
}  // namespace rtwall
