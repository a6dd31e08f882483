// Vertex colours in the renderer (issue 3): the material colour is multiplied by the vertex
// colours, decoded from sRGB to linear and interpolated at the hit's barycentrics. A coloured
// triangle read from a PLY and from a VTK file renders exactly that colour in every pixel.
#include "test_util.h"

#include <rtwall/engine.h>
#include <rtwall/mesh.h>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

namespace rtwall {
namespace {

double srgbToLinear(int c) {
    const double s = c / 255.0;
    return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
}

SceneDesc triangleScene(const std::filesystem::path& file, ShadingMode shading) {
    SceneDesc d;
    d.meshes.push_back({"tri", file.string(), std::make_shared<const TriangleMesh>(loadMesh(file))});
    Material m;
    m.type = MaterialType::Lambert;
    m.color = {1.0f, 0.5f, 1.0f};  // the material colour is multiplied in, channel by channel
    d.materials.push_back(m);
    d.instances.push_back(InstanceDesc{});
    CameraDesc c;
    c.position = {0.1f, -0.05f, 3.0f};
    c.lookAt = {0.1f, -0.05f, 0.0f};
    c.fovY = 50.0f;
    d.cameras.push_back(c);
    // No lights: with a white ambient term a Lambert surface shows exactly its albedo.
    d.settings.width = 48;
    d.settings.height = 40;
    d.settings.ambient = {1, 1, 1};
    d.settings.shadows = false;
    d.settings.shading = shading;
    d.settings.threads = 1;
    return d;
}

struct Check {
    int interior = 0, background = 0;
    double maxError = 0;
};

// Expected colour in every pixel, from the pixel-centre ray intersected with the z = 0 plane in
// double precision and the triangle's barycentrics there.
Check compare(const SceneDesc& d) {
    const Scene scene(d);
    const RenderSettings& s = d.settings;
    const Camera camera(d.cameras.front(), s.width, s.height);
    std::vector<float> out(size_t(3 * s.width * s.height));
    renderTileLinear(scene, camera, {0, 0, s.width, s.height}, 0, s, out.data(), size_t(3 * s.width));
    const double colors[3][3] = {{srgbToLinear(255), srgbToLinear(128), srgbToLinear(0)},
                                 {srgbToLinear(0), srgbToLinear(255), srgbToLinear(0)},
                                 {srgbToLinear(0), srgbToLinear(0), srgbToLinear(255)}};
    const double material[3] = {1.0, 0.5, 1.0};
    Check check;
    for (int j = 0; j < s.height; ++j)
        for (int i = 0; i < s.width; ++i) {
            const Float3 o = camera.origin(), dir = camera.direction(float(i) + 0.5f, float(j) + 0.5f);
            const double t = -double(o.z) / dir.z;
            const double x = o.x + t * dir.x, y = o.y + t * dir.y;
            // Triangle (-1,-1), (1,-1), (0,1): barycentrics of vertices 1 and 2.
            const double w2 = (y + 1.0) / 2.0, w1 = (x + 1.0 - w2) / 2.0, w0 = 1.0 - w1 - w2;
            const float* p = &out[size_t(3 * (j * s.width + i))];
            if (std::min({w0, w1, w2}) < 0.02) {
                if (std::min({w0, w1, w2}) < -0.02) {
                    ++check.background;
                    EXPECT_NEAR(p[0], s.background.x, 1e-6) << i << "," << j;
                }
                continue;  // too near an edge for the pixel centre to be sure of the side
            }
            ++check.interior;
            const double len = std::sqrt(double(dir.x) * dir.x + double(dir.y) * dir.y + double(dir.z) * dir.z);
            const double cosine = s.shading == ShadingMode::EyeLight ? std::fabs(dir.z) / len : 1.0;
            for (int k = 0; k < 3; ++k) {
                const double expected = material[k] * cosine * (w0 * colors[0][k] + w1 * colors[1][k] + w2 * colors[2][k]);
                check.maxError = std::max(check.maxError, std::fabs(p[k] - expected));
                EXPECT_NEAR(p[k], expected, 2e-4) << "pixel " << i << "," << j << " channel " << k;
            }
        }
    return check;
}

TEST(VertexColorRender, PlyTriangleShowsTheInterpolatedColour) {
    const Check c = compare(triangleScene(test::dataDir() / "meshes" / "tri_colors_ascii.ply", ShadingMode::Full));
    EXPECT_GT(c.interior, 300);
    EXPECT_GT(c.background, 100);
}

TEST(VertexColorRender, VtkTriangleShowsTheInterpolatedColour) {
    const Check c = compare(triangleScene(test::dataDir() / "meshes" / "tri_colors.vtp", ShadingMode::Full));
    EXPECT_GT(c.interior, 300);
}

// The eyelight preview (the packet kernel's own shading loop) uses the colours too.
TEST(VertexColorRender, EyeLightPreviewUsesThem) {
    const Check c = compare(triangleScene(test::dataDir() / "meshes" / "tri_colors_ascii.ply", ShadingMode::EyeLight));
    EXPECT_GT(c.interior, 300);
}

// And the sRGB bytes: the corner pixels come out in their vertex's hue.
TEST(VertexColorRender, CornersTakeTheirVertexHue) {
    const SceneDesc d = triangleScene(test::dataDir() / "meshes" / "tri_colors_ascii.ply", ShadingMode::Full);
    const Scene scene(d);
    const Image img = renderFrame(scene, Camera(d.cameras.front(), d.settings.width, d.settings.height), d.settings);
    // Find the reddest and the bluest pixel: orange near vertex 0 (bottom left), blue at the top.
    int bestRed = -1, bestBlue = -1;
    for (int k = 0; k < img.width * img.height; ++k) {
        const uint8_t* p = &img.rgb[size_t(3 * k)];
        if (bestRed < 0 || p[0] - p[2] > img.rgb[size_t(3 * bestRed)] - img.rgb[size_t(3 * bestRed + 2)]) bestRed = k;
        if (bestBlue < 0 || p[2] - p[0] > img.rgb[size_t(3 * bestBlue + 2)] - img.rgb[size_t(3 * bestBlue)]) bestBlue = k;
    }
    EXPECT_GT(bestRed / img.width, img.height / 2) << "orange at the bottom";
    EXPECT_LT(bestRed % img.width, img.width / 2) << "orange on the left";
    EXPECT_LT(bestBlue / img.width, img.height / 2) << "blue at the top";
}

}  // namespace
}  // namespace rtwall
