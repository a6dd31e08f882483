// Image regression against references kept in tests/data/reference.
//
// Tolerance: rendering is deterministic for one build, but Embree picks its kernels by CPU
// (SSE, AVX2, AVX-512) and the compiler may contract differently on another machine, which can
// move a few silhouette pixels. So: at most 0.5% of the pixels may differ by more than 8 levels
// in any channel, and the mean absolute difference must stay below 0.5 levels.
// RTWALL_UPDATE_REFERENCES=1 rewrites the references; on failure a diff image (differences x8)
// is written next to the test's scratch directory.
#include "test_util.h"

#include <gtest/gtest.h>

#include <cstdlib>

namespace rtwall {
namespace {

struct Comparison {
    double meanAbs = 0;
    size_t largeDiffPixels = 0;
    Image diff;
};

Comparison compare(const Image& a, const Image& b) {
    Comparison c;
    c.diff = a;
    uint64_t sum = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            int worst = 0;
            for (int k = 0; k < 3; ++k) {
                const int d = std::abs(int(a.pixel(x, y)[k]) - int(b.pixel(x, y)[k]));
                sum += uint64_t(d);
                worst = std::max(worst, d);
                c.diff.pixel(x, y)[k] = uint8_t(std::min(255, d * 8));
            }
            c.largeDiffPixels += worst > 8;
        }
    c.meanAbs = double(sum) / double(a.rgb.size());
    return c;
}

void checkAgainstReference(const std::string& name, const Image& img) {
    const auto refPath = test::dataDir() / "reference" / (name + ".png");
    if (std::getenv("RTWALL_UPDATE_REFERENCES")) {
        writePng(img, refPath);
        GTEST_SKIP() << "wrote " << refPath;
    }
    ASSERT_TRUE(std::filesystem::exists(refPath)) << refPath << " is missing; run with RTWALL_UPDATE_REFERENCES=1";
    const Image ref = readPng(refPath);
    ASSERT_EQ(ref.width, img.width);
    ASSERT_EQ(ref.height, img.height);
    const Comparison c = compare(img, ref);
    const size_t allowed = size_t(img.width) * img.height / 200;
    if (c.largeDiffPixels > allowed || c.meanAbs >= 0.5) {
        const auto dir = test::scratchDir();
        writePng(img, dir / (name + ".png"));
        writePng(c.diff, dir / (name + ".diff.png"));
        ADD_FAILURE() << name << ": " << c.largeDiffPixels << " pixels differ by more than 8 levels (allowed " << allowed
                      << "), mean abs difference " << c.meanAbs << "; image and diff written to " << dir;
    }
}

TEST(ImageRegression, DemoScene) {
    SceneDesc desc = test::demoScene(200, 150);
    const Scene scene(desc);
    checkAgainstReference("demo_200x150", renderFrame(scene, Camera(desc.cameras.front(), 200, 150), desc.settings));
}

TEST(ImageRegression, DemoSceneTopCamera) {
    SceneDesc desc = test::demoScene(120, 90, 1);
    const Scene scene(desc);
    checkAgainstReference("demo_top_120x90",
                          renderFrame(scene, Camera(*desc.findCamera("top"), 120, 90), desc.settings));
}

TEST(ImageRegression, MeshFileWithDefaultCameraAndLight) {
    const SceneDesc desc = sceneFromMeshFile(test::sourceDir() / "configs/meshes/knot.ply");
    RenderSettings s = desc.settings;
    s.width = 128;
    s.height = 96;
    const Scene scene(desc);
    checkAgainstReference("knot_default_128x96", renderFrame(scene, Camera(desc.cameras.front(), 128, 96), s));
}

TEST(ImageRegression, ComparisonDetectsAChangedImage) {
    // The comparison itself must be able to fail.
    Image a;
    a.width = 20;
    a.height = 10;
    a.rgb.assign(600, 100);
    Image b = a;
    b.pixel(3, 3)[1] = 200;
    const Comparison c = compare(a, b);
    EXPECT_EQ(c.largeDiffPixels, 1u);
    EXPECT_GT(c.meanAbs, 0.0);
}

}  // namespace
}  // namespace rtwall
