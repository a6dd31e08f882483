#include "node_kit.h"

#include "files.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <set>

namespace rtwall::test {

ClientThreads::~ClientThreads() {
    for (auto& t : threads_) t.join();
}

void ClientThreads::start(const ClientSettings& settings) {
    threads_.emplace_back([settings] { runClient(settings); });
}

ClientSettings localClient(const std::string& endpoint) {
    ClientSettings c;
    c.connect = endpoint;
    c.threads = 1;
    c.exitAfterIdleMs = 5000;
    return c;
}

NodeProcesses startDisplayNodes(const std::string& exe, const std::string& endpoint, const std::vector<std::string>& names,
                                const std::filesystem::path& dir, const std::vector<std::string>& extra) {
    NodeProcesses nodes;
    for (const std::string& name : names) {
        std::vector<std::string> argv{exe,       "display", "--connect", endpoint, "--node", name, "--headless", "--out",
                                      (dir / name).string(), "--frames", "3", "--exit-after-idle", "20000"};
        argv.insert(argv.end(), extra.begin(), extra.end());
        nodes.push_back(std::make_unique<ChildProcess>(argv));
    }
    return nodes;
}

void runUntilNodesEnd(NodeProcesses& nodes, const std::function<void()>& render) {
    for (auto& n : nodes) ASSERT_TRUE(n->waitFor("joined", 20000)) << n->output();
    for (int i = 0; i < 30; ++i) {
        render();
        if (std::all_of(nodes.begin(), nodes.end(), [](auto& n) { return n->wait(0).has_value(); })) break;
    }
    for (auto& n : nodes) {
        const std::optional<int> status = n->wait(10000);
        ASSERT_TRUE(status.has_value()) << n->output();
        EXPECT_EQ(*status, 0) << n->output();
    }
}

void expectNodeScreensMatchOnePc(const WallConfig& wall, WallFrame one, const std::filesystem::path& dir,
                                 const std::map<std::string, std::vector<std::string>>& screensOf, size_t perNode) {
    // The frame to compare: the newest that every node presented ("frame_NNNNNN_"). Each node
    // stops after presenting its frames, and a frame released while one node was not in yet (or
    // already gone) carries the left-out overlay on the others, so a node's own newest frame can
    // name another as left out; a frame all presented was released with all holding it.
    std::set<std::string> common;
    bool first = true;
    for (const auto& [name, screens] : screensOf) {
        std::set<std::string> stems;
        size_t files = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir / name)) {
            stems.insert(e.path().filename().string().substr(0, 13));
            ++files;
        }
        ASSERT_EQ(files, perNode) << name;
        if (first) common = stems;
        std::set<std::string> both;
        std::set_intersection(common.begin(), common.end(), stems.begin(), stems.end(), std::inserter(both, both.end()));
        if (!first) common = std::move(both);
        first = false;
    }
    ASSERT_FALSE(common.empty()) << "no frame presented by every node";
    const std::string stem = *common.rbegin();
    for (const auto& [name, screens] : screensOf) {
        one.number = uint32_t(std::stoul(stem.substr(6, 6)));
        HeadlessPresenter whole(wall, dir / ("one-" + name));
        whole.present(one);
        for (const std::string& screen : screens) {
            const std::filesystem::path mine = dir / name / (stem + screen + ".png");
            ASSERT_TRUE(std::filesystem::exists(mine)) << mine;
            EXPECT_EQ(fileBytes(mine), fileBytes(dir / ("one-" + name) / (stem + screen + ".png"))) << name << " " << screen;
        }
    }
}

}  // namespace rtwall::test
