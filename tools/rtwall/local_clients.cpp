#include "local_clients.h"

#include <rtwall/mesh.h>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <thread>

extern char** environ;

namespace rtwall::cli {

LocalClients::LocalClients(int count, const std::string& endpoint, int threadsEach, bool replay) {
    const std::string threads = std::to_string(threadsEach);
    for (int i = 0; i < count; ++i) {
        // The same executable, so client and master always speak the same protocol version.
        // A client whose master has gone gives up after a few seconds on its own as well.
        const char* argv[] = {"rtwall", "client", "--connect", endpoint.c_str(), "--threads", threads.c_str(),
                              "--exit-after-idle", "5000", replay ? "--replay" : nullptr, nullptr};
        pid_t pid;
        const int err = posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, const_cast<char**>(argv), environ);
        if (err != 0) throw InputError(std::string("cannot start a local render client: ") + std::strerror(err));
        pids_.push_back(pid);
    }
}

LocalClients::~LocalClients() {
    for (pid_t pid : pids_) kill(pid, SIGTERM);
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

}  // namespace rtwall::cli
