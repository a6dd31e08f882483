// `rtwall bench cluster --display-nodes K` as a user meets it (issue 19): one-line errors for
// counts and settings it cannot run, and a short run of two display-node processes, two
// replaying clients and the master on loopback whose figures are checked where they are exact;
// and `--features` (issue 28): what the denoiser's features add to the bytes of a GI frame.
#include "cli_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <regex>
#include <string>

namespace rtwall {
namespace {

test::CliResult run(const std::string& args) { return test::runCli(RTWALL_EXE, "bench cluster " + args, 120); }

void expectOneLineError(const test::CliResult& r, const std::string& mustContain) {
    EXPECT_NE(r.status, 0) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(mustContain), std::string::npos) << r.output;
}

TEST(BenchClusterNodes, BadNodeCountsAndSettingsGiveOneLineErrors) {
    const std::string tiny = "--width 128 --height 64 --tile 16 --frames 2 ";
    expectOneLineError(run(tiny + "--display-nodes 0"), "--display-nodes");
    expectOneLineError(run(tiny + "--display-nodes 65"), "--display-nodes");
    expectOneLineError(run(tiny + "--display-nodes two"), "--display-nodes");
    expectOneLineError(run(tiny + "--display-nodes -1"), "--display-nodes");
    // 3 nodes need 12 equal screen columns: 100 pixels do not split so.
    expectOneLineError(run("--width 100 --height 64 --tile 16 --display-nodes 1,3"),
                       "--display-nodes 3: a 100-pixel wide wall does not split into 12 equal screen columns");
    expectOneLineError(run(tiny + "--display-nodes 2 --node-addresses 127.0.0.1"), "--node-addresses: 1 given for 2 display nodes");
    expectOneLineError(run(tiny + "--display-nodes 2 --node-codecs raw,png"), "--node-codecs");
}

// The first number after "KEY": in the JSON of the only result row that has it.
std::vector<double> numbersOf(const std::string& json, const std::string& key) {
    std::vector<double> out;
    const std::regex re("\"" + key + "\"\\s*:\\s*(-?[0-9.eE+-]+)");
    for (auto it = std::sregex_iterator(json.begin(), json.end(), re); it != std::sregex_iterator(); ++it)
        out.push_back(std::stod((*it)[1].str()));
    return out;
}

TEST(BenchClusterNodes, TwoNodesOnLoopbackSwapEveryFrameAndSplitTheBytes) {
    // 128x64 in 16-pixel tiles, two nodes of 64 columns each: raw tiles are 3 bytes a pixel, so
    // each node receives exactly half of 128 x 64 x 3 bytes a frame, and no node is left out
    // (frames are paced by the swap: the run fails when a frame is not swapped).
    const test::CliResult r =
        test::runCli(RTWALL_EXE, "bench cluster --json --width 128 --height 64 --tile 16 --frames 4 --max-clients 2 "
                                 "--display-nodes 2 --node-codecs raw",
                     120);
    ASSERT_EQ(r.status, 0) << r.output;
    // The JSON comes last, after the processes' lines on stderr.
    const size_t key = r.output.find("\"benchmark\"");
    ASSERT_NE(key, std::string::npos) << r.output;
    const size_t json = r.output.rfind('{', key);
    ASSERT_NE(json, std::string::npos) << r.output;
    const std::string out = r.output.substr(json);
    EXPECT_EQ(numbersOf(out, "display_nodes"), std::vector<double>{2});
    EXPECT_EQ(numbersOf(out, "bytes_per_frame"), std::vector<double>{128 * 64 * 3});
    EXPECT_EQ(numbersOf(out, "max_node_mb_per_frame"), std::vector<double>{128 * 64 * 3 / 2 * 1e-6});
    EXPECT_EQ(numbersOf(out, "nodes_left_out"), std::vector<double>{0});
    EXPECT_EQ(numbersOf(out, "fan_out_tiles"), std::vector<double>{0});
    const std::vector<double> fps = numbersOf(out, "fps");
    ASSERT_EQ(fps.size(), 1u);
    EXPECT_GT(fps[0], 0);
    const std::regex nodeBytes("\"node_bytes_per_frame\"\\s*:\\s*\\[\\s*12288(\\.0)?\\s*,\\s*12288(\\.0)?\\s*\\]");
    EXPECT_TRUE(std::regex_search(out, nodeBytes)) << out;
}

// The bench stops its node processes with SIGTERM: a node waiting in its poll (here for a master
// that is not there; port 9 is discard, nothing answers) stops with status 0 and says goodbye
// rather than failing on the interrupted wait.
TEST(BenchClusterNodes, ANodeProcessStopsCleanlyOnSigterm) {
    for (int i = 0; i < 3; ++i) {
        const test::CliResult r = test::runCli("timeout --preserve-status -s TERM 1 " + std::string(RTWALL_EXE),
                                               "display --connect tcp://127.0.0.1:9 --node n1 --headless --out /tmp", 30);
        EXPECT_EQ(r.status, 0) << r.output;
        EXPECT_EQ(r.output.find("error"), std::string::npos) << r.output;
    }
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// `rtwall bench cluster --features` (issue 28): the GI scene's frames, plain and then with depth
// and each mode's features, in one run; what travels grows by the features the mode reads
// (temporal: normal and id; svgf: also the albedo), and an unknown mode is refused.
TEST(BenchClusterFeatures, EachModeSendsItsFeaturesAndCostsBytes) {
    const test::CliResult r = test::runCli(
        RTWALL_EXE, "bench cluster --json --width 128 --height 64 --tile 16 --frames 2 --client-counts 1 --features temporal,svgf", 120);
    ASSERT_EQ(r.status, 0) << r.output;
    const size_t key = r.output.find("\"benchmark\"");
    ASSERT_NE(key, std::string::npos) << r.output;
    const std::string out = r.output.substr(r.output.rfind('{', key));
    const std::vector<double> bytes = numbersOf(out, "bytes_per_frame");
    ASSERT_EQ(bytes.size(), 3u) << out;
    EXPECT_LT(bytes[0], bytes[1]) << "depth, normal and id with every tile";
    EXPECT_LT(bytes[1], bytes[2]) << "and the albedo";
    for (const char* mode : {"\"off\"", "\"temporal\"", "\"svgf\""}) EXPECT_NE(out.find(mode), std::string::npos) << mode;
    const test::CliResult bad = test::runCli(RTWALL_EXE, "bench cluster --width 128 --height 64 --features median", 30);
    EXPECT_NE(bad.status, 0);
    EXPECT_NE(bad.output.find("--features"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace rtwall
