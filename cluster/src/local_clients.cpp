// Render-client processes on this PC (LocalClients in rtwall/cluster.h).
#include <rtwall/cluster.h>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <chrono>
#include <csignal>
#include <cstring>
#include <thread>

extern char** environ;

namespace rtwall {

LocalClients::LocalClients(int count, const std::string& endpoint, int threadsEach, bool replay,
                           const std::string& netnsPrefix, const std::vector<std::string>& extraArgs,
                           const std::filesystem::path& executable) {
    const std::string threads = std::to_string(threadsEach);
    for (int i = 0; i < count; ++i) {
        // The same executable, so client and master always speak the same protocol version.
        // A client whose master has gone gives up after a few seconds on its own as well.
        std::vector<std::string> args = {"client", "--connect", endpoint, "--threads", threads, "--exit-after-idle", "5000"};
        if (replay) args.push_back("--replay");
        args.insert(args.end(), extraArgs.begin(), extraArgs.end());
        std::string program = executable.string();
        if (!netnsPrefix.empty()) {
            // `ip netns exec NS EXE ...`: the same executable, resolved, inside the namespace.
            std::error_code ec;
            args.insert(args.begin(), {"netns", "exec", netnsPrefix + std::to_string(i + 1),
                                       std::filesystem::canonical(executable, ec).string()});
            program = "/usr/sbin/ip";
        }
        std::vector<char*> argv{const_cast<char*>("rtwall")};
        if (!netnsPrefix.empty()) argv[0] = const_cast<char*>("ip");
        for (std::string& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        pid_t pid;
        const int err = posix_spawn(&pid, program.c_str(), nullptr, nullptr, argv.data(), environ);
        if (err != 0) throw InputError(std::string("cannot start a local render client: ") + std::strerror(err));
        pids_.push_back(pid);
    }
}

LocalClients::~LocalClients() {
    // A frozen client (SIGSTOP) acts on SIGTERM only once it runs again.
    for (pid_t pid : pids_) {
        kill(pid, SIGTERM);
        kill(pid, SIGCONT);
    }
    // Bounded wait: a client that ignores SIGTERM for 2 s is killed.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    for (pid_t pid : pids_) {
        int status;
        while (waitpid(pid, &status, WNOHANG) == 0) {
            if (std::chrono::steady_clock::now() > deadline) {
                kill(pid, SIGKILL);
                waitpid(pid, &status, 0);
                break;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
    }
}

}  // namespace rtwall
