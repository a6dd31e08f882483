#include <rtwall/process.h>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <thread>

extern char** environ;

namespace rtwall {

int spawnProcess(const std::string& program, const std::vector<std::string>& argv, int& pid, const ChildOutput& output) {
    std::vector<std::string> args = argv;  // posix_spawn takes char*, not const char*
    std::vector<char*> cargs;
    for (std::string& a : args) cargs.push_back(a.data());
    cargs.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (output.fd >= 0) {
        posix_spawn_file_actions_adddup2(&actions, output.fd, 1);
        posix_spawn_file_actions_adddup2(&actions, output.fd, 2);
    }
    if (output.closeInChild >= 0) posix_spawn_file_actions_addclose(&actions, output.closeInChild);
    pid_t child = -1;
    const int err = posix_spawn(&child, program.c_str(), &actions, nullptr, cargs.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (err == 0) pid = child;
    return err;
}

void endProcesses(const std::vector<int>& pids, int graceMs) {
    for (int pid : pids) {
        kill(pid, SIGTERM);
        kill(pid, SIGCONT);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(graceMs);
    for (int pid : pids) {
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

std::string describeExit(int status) {
    if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
    if (WIFSIGNALED(status))
        return std::string("killed by signal ") + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
    return "ended";
}

}  // namespace rtwall
