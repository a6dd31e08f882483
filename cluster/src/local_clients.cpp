// Render-client processes on this PC (LocalClients in rtwall/cluster.h).
#include <rtwall/cluster.h>
#include <rtwall/process.h>

#include <cstring>
#include <filesystem>

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
        args.insert(args.begin(), netnsPrefix.empty() ? "rtwall" : "ip");
        int pid = 0;
        const int err = spawnProcess(program, args, pid);
        if (err != 0) throw InputError(std::string("cannot start a local render client: ") + std::strerror(err));
        pids_.push_back(pid);
    }
}

LocalClients::~LocalClients() {
    // A frozen client (SIGSTOP) acts on SIGTERM only once it runs again; one that ignores it for
    // 2 s is killed.
    endProcesses(pids_, 2000);
}

}  // namespace rtwall
