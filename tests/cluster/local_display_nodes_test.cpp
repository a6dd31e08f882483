// LocalDisplayNodes (rtwall/cluster.h): the node processes a wall on one PC starts. Stand-in
// executables (shell scripts that ignore the node's arguments) play nodes that end on their own
// or never do.
#include "scratch.h"

#include <rtwall/cluster.h>

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <chrono>
#include <string>
#include <vector>

namespace rtwall {
namespace {

std::filesystem::path script(const std::filesystem::path& dir, const std::string& name, const std::string& body) {
    const std::filesystem::path p = test::writeFile(dir / name, "#!/bin/sh\n" + body + "\n");
    ::chmod(p.c_str(), 0755);
    return p;
}

double secondsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The session waits for its nodes to end on the master's goodbye before it signals them: a node
// signalled between the last swap's release and its reading of it never shows the last frame.
TEST(LocalDisplayNodes, AwaitEndWaitsForNodesThatEndOnTheirOwnAndTheyAreNotSignalled) {
    const std::filesystem::path dir = test::scratchDir();
    LocalDisplayNodes::Options o;
    o.executable = script(dir, "ends.sh", "sleep 0.4; exit 3");
    o.outDir = dir;
    LocalDisplayNodes nodes({"left", "right"}, "tcp://127.0.0.1:1", o);
    EXPECT_EQ(nodes.running(), 2u);
    EXPECT_TRUE(nodes.awaitEnd(30'000));
    EXPECT_EQ(nodes.running(), 0u);
    const std::vector<std::string> ended = nodes.takeEnded();
    ASSERT_EQ(ended.size(), 2u);
    for (const std::string& line : ended) EXPECT_NE(line.find("exited with status 3"), std::string::npos) << line;
}

TEST(LocalDisplayNodes, AwaitEndIsBoundedWhenANodeDoesNotEnd) {
    const std::filesystem::path dir = test::scratchDir();
    LocalDisplayNodes::Options o;
    o.executable = script(dir, "stays.sh", "exec sleep 60");
    o.outDir = dir;
    const auto start = std::chrono::steady_clock::now();
    {
        LocalDisplayNodes nodes({"left"}, "tcp://127.0.0.1:1", o);
        EXPECT_FALSE(nodes.awaitEnd(300));
        EXPECT_GE(secondsSince(start), 0.3);
        EXPECT_EQ(nodes.running(), 1u);
    }  // the destructor's SIGTERM ends it
    EXPECT_LT(secondsSince(start), 10.0);
}

}  // namespace
}  // namespace rtwall
