// A child process of the test (this build's rtwall, as a user starts it) whose output is read
// while it runs: wait for a line, signal it, find its own children, wait for it to end. Every
// wait is bounded; the destructor kills what is left.
#pragma once

#include <rtwall/process.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace rtwall::test {

class ChildProcess {
public:
    explicit ChildProcess(std::vector<std::string> args) {
        int fds[2];
        if (pipe(fds) != 0) return;
        if (args.empty() || spawnProcess(args[0], args, pid_, {fds[1], fds[0]}) != 0) pid_ = -1;
        close(fds[1]);
        reader_ = std::thread([this, fd = fds[0]] {
            char buf[4096];
            for (ssize_t n; (n = read(fd, buf, sizeof buf)) > 0;) {
                std::lock_guard lock(m_);
                output_.append(buf, size_t(n));
            }
            close(fd);
        });
    }
    ~ChildProcess() {
        if (pid_ > 0 && !status_) {
            ::kill(pid_, SIGCONT);
            ::kill(pid_, SIGKILL);
            waitpid(pid_, nullptr, 0);
        }
        if (reader_.joinable()) reader_.join();
    }
    pid_t pid() const { return pid_; }
    std::string output() const {
        std::lock_guard lock(m_);
        return output_;
    }
    // The first match of `pattern` in the output within ms (its first group, or the whole match).
    std::optional<std::string> waitFor(const std::string& pattern, int ms) const {
        const std::regex re(pattern);
        const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
        do {
            std::smatch m;
            const std::string out = output();
            if (std::regex_search(out, m, re)) return m.size() > 1 ? m[1].str() : m[0].str();
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        } while (std::chrono::steady_clock::now() < end);
        return std::nullopt;
    }
    void signal(int sig) const {
        if (pid_ > 0) ::kill(pid_, sig);
    }
    // Its exit status (128 + signal when killed), or nullopt if it is still running after ms.
    std::optional<int> wait(int ms) {
        if (status_) return status_;
        const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
        do {
            int st;
            if (waitpid(pid_, &st, WNOHANG) == pid_) {
                status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
                if (reader_.joinable()) reader_.join();
                return status_;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        } while (std::chrono::steady_clock::now() < end);
        return std::nullopt;
    }

private:
    pid_t pid_ = -1;
    std::optional<int> status_;
    mutable std::mutex m_;
    std::string output_;
    std::thread reader_;
};

// The children of a process, from /proc/<pid>/task/<tid>/children.
inline std::vector<pid_t> childrenOf(pid_t pid) {
    std::vector<pid_t> kids;
    std::error_code ec;
    for (const auto& task : std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
        std::ifstream in(task.path() / "children");
        for (pid_t k; in >> k;) kids.push_back(k);
    }
    return kids;
}

// Whether a process exists and is not a zombie.
inline bool alive(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string line;
    if (!std::getline(in, line)) return false;
    const size_t close = line.rfind(')');
    return close != std::string::npos && close + 2 < line.size() && line[close + 2] != 'Z';
}

}  // namespace rtwall::test
