// Rendering is deterministic by design: the packet and single-ray kernels, any thread count
// and any tile size give the same bytes.
#include "image_compare.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <set>

namespace rtwall {
namespace {

class Determinism : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        desc_ = new SceneDesc(test::demoScene(160, 120, 1));
        scene_ = new Scene(*desc_);
    }
    static void TearDownTestSuite() {
        delete scene_;
        delete desc_;
    }
    static Image render(const RenderSettings& s) {
        return renderFrame(*scene_, Camera(desc_->cameras.front(), s.width, s.height), s);
    }
    static SceneDesc* desc_;
    static Scene* scene_;
};
SceneDesc* Determinism::desc_ = nullptr;
Scene* Determinism::scene_ = nullptr;

// Guards against a vacuous pass: the reference image must show a real scene.
void expectRichImage(const Image& img) {
    std::set<uint32_t> colours;
    for (size_t i = 0; i + 2 < img.rgb.size(); i += 3)
        colours.insert(uint32_t(img.rgb[i]) << 16 | uint32_t(img.rgb[i + 1]) << 8 | img.rgb[i + 2]);
    EXPECT_GT(colours.size(), 1000u);
}

TEST_F(Determinism, PacketAndSingleKernelsAreBitIdentical) {
    RenderSettings packet = desc_->settings, single = desc_->settings;
    packet.kernel = KernelType::Packet;
    single.kernel = KernelType::Single;
    const Image a = render(packet), b = render(single);
    expectRichImage(a);
    EXPECT_EQ(test::differingBytes(a, b), 0u);
}

TEST_F(Determinism, PacketAndSingleAgreeWithSupersampling) {
    RenderSettings packet = desc_->settings;
    packet.supersample = 3;
    RenderSettings single = packet;
    single.kernel = KernelType::Single;
    EXPECT_EQ(test::differingBytes(render(packet), render(single)), 0u);
}

TEST_F(Determinism, ThreadCountDoesNotChangeTheImage) {
    RenderSettings s = desc_->settings;
    s.threads = 1;
    const Image one = render(s);
    expectRichImage(one);
    for (int threads : {2, 3, 8}) {
        s.threads = threads;
        EXPECT_EQ(test::differingBytes(one, render(s)), 0u) << threads << " threads";
    }
}

TEST_F(Determinism, TileSizeDoesNotChangeTheImage) {
    RenderSettings s = desc_->settings;
    s.tileSize = 32;
    const Image ref = render(s);
    for (int tile : {1, 7, 16, 61, 1024}) {
        s.tileSize = tile;
        EXPECT_EQ(test::differingBytes(ref, render(s)), 0u) << "tile " << tile;
    }
}

TEST_F(Determinism, SingleTilesMatchTheFullFrame) {
    // renderTile on an arbitrary rectangle writes exactly the full frame's pixels there.
    const RenderSettings& s = desc_->settings;
    const Camera camera(desc_->cameras.front(), s.width, s.height);
    const Image full = render(s);
    const TileRect rect{37, 21, 101, 64};
    std::vector<uint8_t> tile(size_t(rect.width()) * rect.height() * 3);
    renderTile(*scene_, camera, rect, 0, s, {tile.data(), size_t(rect.width()) * 3});
    size_t bad = 0;
    for (int y = rect.y0; y < rect.y1; ++y)
        for (int x = rect.x0; x < rect.x1; ++x)
            for (int c = 0; c < 3; ++c)
                bad += tile[(size_t(y - rect.y0) * rect.width() + (x - rect.x0)) * 3 + c] != full.pixel(x, y)[c];
    EXPECT_EQ(bad, 0u);
}

// renderFrameLinear is the frame before quantisation: the same bytes as renderFrame once
// quantised, the same values as a single linear tile anywhere, whatever the thread count.
TEST_F(Determinism, LinearFrameIsTheFrameBeforeQuantisation) {
    RenderSettings s = desc_->settings;
    s.threads = 2;
    const Camera camera(desc_->cameras.front(), s.width, s.height);
    const Image full = render(s);
    expectRichImage(full);
    const std::vector<float> linear = renderFrameLinear(*scene_, camera, s, 0);
    ASSERT_EQ(linear.size(), full.rgb.size());
    std::vector<uint8_t> quantised(linear.size());
    linearToSrgb8(linear.data(), linear.size(), quantised.data());
    EXPECT_EQ(quantised, full.rgb);
    s.threads = 1;
    EXPECT_EQ(renderFrameLinear(*scene_, camera, s, 0), linear);
    const TileRect rect{37, 21, 101, 64};
    std::vector<float> tile(size_t(rect.width()) * rect.height() * 3);
    renderTileLinear(*scene_, camera, rect, 0, s, tile.data(), size_t(rect.width()) * 3);
    size_t bad = 0;
    for (int y = rect.y0; y < rect.y1; ++y)
        for (int x = rect.x0; x < rect.x1; ++x)
            for (int c = 0; c < 3; ++c)
                bad += tile[(size_t(y - rect.y0) * rect.width() + (x - rect.x0)) * 3 + c] !=
                       linear[(size_t(y) * s.width + x) * 3 + c];
    EXPECT_EQ(bad, 0u);
}

}  // namespace
}  // namespace rtwall
