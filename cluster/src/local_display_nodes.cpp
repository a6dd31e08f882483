// Display-node processes on this PC (LocalDisplayNodes in rtwall/cluster.h): a wall of several
// display nodes run in one command on one machine.
#include <rtwall/cluster.h>
#include <rtwall/process.h>

#include <sys/wait.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <thread>
#include <utility>

namespace rtwall {

LocalDisplayNodes::LocalDisplayNodes(const std::vector<std::string>& names, const std::string& endpoint, const Options& options) {
    for (const std::string& name : names) {
        // The same executable, so node and master speak the same protocol version. A node whose
        // master has gone gives up after a few seconds on its own as well.
        std::vector<std::string> args = {"display", "--connect", endpoint, "--node", name, "--exit-after-idle", "5000"};
        // --out also where a windowed node finds no display and writes its screens instead.
        args.insert(args.end(), {"--out", (options.outDir / name).string()});
        if (options.headless) args.push_back("--headless");
        args.insert(args.end(), options.extraArgs.begin(), options.extraArgs.end());
        args.insert(args.begin(), "rtwall");
        int pid = 0;
        const int err = spawnProcess(options.executable.string(), args, pid);
        if (err != 0) {
            // No destructor runs for a constructor that throws: the ones started so far go here.
            for (const Child& c : children_) {
                kill(c.pid, SIGKILL);
                waitpid(c.pid, nullptr, 0);
            }
            throw InputError("cannot start local display node '" + name + "': " + std::strerror(err));
        }
        children_.push_back({name, pid});
    }
}

void LocalDisplayNodes::reap(bool block) {
    for (Child& c : children_) {
        if (c.ended) continue;
        int status = 0;
        const pid_t r = waitpid(c.pid, &status, block ? 0 : WNOHANG);
        if (r == c.pid || (r < 0 && errno == ECHILD)) {
            c.ended = true;
            c.status = status;
            endedLines_.push_back("local display node '" + c.name + "' (pid " + std::to_string(c.pid) + ") " +
                                  (r < 0 ? "is gone" : describeExit(status)));
        }
    }
}

std::vector<std::string> LocalDisplayNodes::takeEnded() {
    reap(false);
    return std::exchange(endedLines_, {});
}

size_t LocalDisplayNodes::running() const {
    size_t n = 0;
    for (const Child& c : children_) n += !c.ended;
    return n;
}

int LocalDisplayNodes::pid(const std::string& name) const {
    for (const Child& c : children_)
        if (c.name == name && !c.ended) return c.pid;
    return 0;
}

bool LocalDisplayNodes::awaitEnd(int timeoutMs) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeoutMs);
    for (;;) {
        reap(false);
        if (running() == 0) return true;
        if (std::chrono::steady_clock::now() >= end) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
}

LocalDisplayNodes::~LocalDisplayNodes() {
    // SIGTERM: a node says goodbye and closes its windows; one that does not within 2 s is killed.
    std::vector<int> running;
    for (Child& c : children_) {
        if (!c.ended) running.push_back(c.pid);
        c.ended = true;
    }
    endProcesses(running, 2000);
}

}  // namespace rtwall
