// What the display-node tests share: render-client threads, `rtwall display` node processes
// started headless, the bounded run until every node has shown its frames, and the check that
// each node's screens are byte-identical to the single-PC wall's screens of the same frame.
#pragma once

#include "child_process.h"

#include <rtwall/cluster.h>
#include <rtwall/display.h>

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace rtwall::test {

// Render clients on threads of the test, joined when it ends (each stops after its idle time).
class ClientThreads {
public:
    ClientThreads() = default;
    ClientThreads(const ClientThreads&) = delete;
    ClientThreads& operator=(const ClientThreads&) = delete;
    ~ClientThreads();
    void start(const ClientSettings& settings);

private:
    std::vector<std::thread> threads_;
};

// A one-thread render client of the master at `endpoint` that stops after 5 s without work.
ClientSettings localClient(const std::string& endpoint);

using NodeProcesses = std::vector<std::unique_ptr<ChildProcess>>;

// `exe display` for each node name, headless, writing `frames` frames under dir/<name>, giving up
// after 20 s idle; `extra` is appended to every node's arguments (keys, for instance).
NodeProcesses startDisplayNodes(const std::string& exe, const std::string& endpoint, const std::vector<std::string>& names,
                                const std::filesystem::path& dir, const std::vector<std::string>& extra = {});

// Every node joined (20 s each) before the first frame (a frame released without one names it on
// the other); then `render` until all have ended (30 frames at most); each must exit with 0
// within 10 s. Fatal failures: call it in ASSERT_NO_FATAL_FAILURE.
void runUntilNodesEnd(NodeProcesses& nodes, const std::function<void()>& render);

// For each node (name -> its screens), `perNode` files under dir/<name>; the newest frame every
// node presented (frame_NNNNNN_<screen>.png: a frame released while a node was not in, or already
// gone, names it on the others) is compared byte for byte with `one` presented with that frame
// number by a single-PC HeadlessPresenter.
void expectNodeScreensMatchOnePc(const WallConfig& wall, WallFrame one, const std::filesystem::path& dir,
                                 const std::map<std::string, std::vector<std::string>>& screensOf, size_t perNode);

}  // namespace rtwall::test
