// `rtwall bench web` (issue 31) runs and prints the JSON fields docs/web-console.md names, on
// one PC and with --nodes (the pictures from two display nodes); no timing is asserted, only
// that each phase measured frames and that the console answered.
#include "display_test_util.h"

#include "cli_util.h"

#include <gtest/gtest.h>

namespace rtwall {
namespace {

class WebBenchCli : public ::testing::TestWithParam<bool> {};

TEST_P(WebBenchCli, PrintsEveryFieldWithFramesMeasuredInEachPhase) {
    const bool nodes = GetParam();
    const test::CliResult r = test::runCli(RTWALL_EXE, std::string("bench web --frames 5 --width 96 --height 72 --attackers 4 --json") +
                                                           (nodes ? " --nodes" : ""),
                                           300, "env -u DISPLAY -u WAYLAND_DISPLAY");
    ASSERT_EQ(r.status, 0) << r.output;
    std::vector<std::string> fields = {"\"frames\" : 5", "\"quiet_ms\"", "\"page_ms\"", "\"attacked_ms\"", "\"page_ratio\"",
                                       "\"attacked_ratio\"", "\"requests\"", "\"answered\"", "\"refused\"", "\"cpu_per_second\""};
    fields.push_back(nodes ? "\"on_nodes\" : true" : "\"on_nodes\" : false");
    if (nodes) fields.insert(fields.end(), {"\"picture_ms\"", "\"screenshot_picture_ms\""});
    for (const std::string& f : fields) EXPECT_NE(r.output.find(f), std::string::npos) << f << " in\n" << r.output;
    EXPECT_EQ(r.output.find("\"answered\" : 0,"), std::string::npos) << "the page's requests were answered: " << r.output;
    EXPECT_EQ(r.output.find("\"median\" : 0.0"), std::string::npos) << "every phase measured frames: " << r.output;
}

INSTANTIATE_TEST_SUITE_P(OnePcAndNodes, WebBenchCli, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "Nodes" : "OnePc"; });

}  // namespace
}  // namespace rtwall
