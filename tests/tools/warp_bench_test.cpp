// `rtwall bench warp` (issue 30) behaves before its figures mean anything: on a flat screen
// (arc 0) the post-warp resamples the flat render at its pixel centres, so it scores what the
// direct rays score (within an edge pixel's float rounding); on a curved one its resampling blurs, which FLIP sees. No timing.
#include <bench.h>

#include <gtest/gtest.h>

namespace rtwall::bench {
namespace {

TEST(WarpBench, FlatBothAgreeCurvedThePostWarpBlurs) {
    WarpOptions o;
    o.text = nullptr;
    o.scene = RTWALL_SOURCE_DIR "/configs/demo.toml";
    o.width = 96;
    o.height = 72;
    o.runs = 1;
    o.threads = 2;
    o.spans = {0, 90};
    const toml::table t = warp(o);
    const toml::array& rows = *t["rows"].as_array();
    ASSERT_EQ(rows.size(), 2u);
    const auto get = [&](size_t row, const char* method, const char* field) {
        return rows[row].as_table()->at_path(std::string(method) + "." + field).value_or(-1.0);
    };
    for (const char* m : {"direct", "direct_ss2", "post", "post_2x"})
        for (const char* f : {"psnr_db", "flip", "ssim", "frame_s"}) EXPECT_GE(get(0, m, f), 0.0) << m << "." << f;
    // Not to the bit: a surface point on the flat screen, in float, is not exactly the flat
    // camera's pixel centre, so an edge pixel or two may hit otherwise.
    EXPECT_NEAR(get(0, "direct", "psnr_db"), get(0, "post", "psnr_db"), 0.05);
    EXPECT_NEAR(get(0, "direct", "flip"), get(0, "post", "flip"), 1e-4);
    EXPECT_GT(get(1, "post", "flip"), get(1, "direct", "flip"));
    EXPECT_GT(get(1, "post_2x", "flip"), get(1, "direct_ss2", "flip"));
}

}  // namespace
}  // namespace rtwall::bench
