// `rtwall bench denoise` (issue 28) behaves before its figures mean anything: one moving and one
// still row per setting with the fields; on the office at one GI sample the spatial
// filter scores better than the raw frames while the camera moves; and when the walk stops, the
// filters, going on with their history, change the shown image from frame to frame far less than
// the wall's plain accumulation, which starts again at the stop. No timing.
#include <bench.h>

#include <gtest/gtest.h>

#include <map>
#include <string>

#include "../scratch.h"

namespace rtwall::bench {
namespace {

TEST(DenoiseBench, RowsCarryTheFieldsAndTheFiltersHoldStillAfterAWalk) {
    DenoiseOptions o;
    o.text = nullptr;
    o.scenes = {"office"};
    o.dir = (test::scratchDir() / "scenes").string();
    o.sizes = {"48x36"};
    o.giSpp = {1};
    o.frames = 8;
    o.scoreEvery = 4;
    o.referenceSpp = 64;
    o.stillReferenceSpp = 64;
    o.stillSeconds = 0;
    o.flickerFrames = 4;
    o.threads = 2;
    const toml::table t = denoise(o);
    const toml::array& rows = *t["rows"].as_array();
    ASSERT_EQ(rows.size(), 6u);  // off, temporal, svgf: moving and still
    std::map<std::string, const toml::table*> moving, still;
    for (const auto& r : rows) {
        const toml::table& row = *r.as_table();
        for (const char* field : {"scene", "denoise", "gi_spp", "fps", "psnr_db", "flip", "flicker", "still"})
            EXPECT_TRUE(row.contains(field)) << field;
        const std::string mode = row["denoise"].value_or(std::string());
        (row["still"].value_or(false) ? still : moving)[mode] = &row;
        if (row["still"].value_or(false)) {
            EXPECT_TRUE(row.contains("seconds_to_40db"));
            EXPECT_TRUE(row.contains("flicker_cold"));
        }
    }
    ASSERT_EQ(moving.size(), 3u);
    ASSERT_EQ(still.size(), 3u);
    auto value = [](const toml::table* row, const char* field) { return (*row)[field].value_or(-1.0); };
    EXPECT_GT(value(moving["svgf"], "psnr_db"), value(moving["off"], "psnr_db") + 3.0);
    for (const char* mode : {"temporal", "svgf"})
        EXPECT_LT(value(still[mode], "flicker"), 0.5 * value(still["off"], "flicker")) << mode;
}

}  // namespace
}  // namespace rtwall::bench
