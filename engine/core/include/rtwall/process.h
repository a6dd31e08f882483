// Child processes: start one (posix_spawn, its output optionally into a pipe), end a few with a
// bounded wait, and say how one ended. Written once for the cluster's local clients and display
// nodes and the tests' child processes.
#pragma once

#include <string>
#include <vector>

namespace rtwall {

// Where a child's standard output and error go: `fd` (both of them; -1: where this process's
// go). `closeInChild` (-1: none) is closed in the child, such as the read end of that pipe.
struct ChildOutput {
    int fd = -1;
    int closeInChild = -1;
};

// Starts `program` with `argv` (argv[0] is the name the process sees; argv may not be empty) in
// this process's environment. Returns 0 and sets `pid`, or the error number (errno) of the failure.
int spawnProcess(const std::string& program, const std::vector<std::string>& argv, int& pid, const ChildOutput& output = {});

// Ends processes this one started: each gets SIGTERM and SIGCONT (a stopped process acts on
// SIGTERM only once it runs again); one still running `graceMs` later is killed. Every one of
// them is reaped.
void endProcesses(const std::vector<int>& pids, int graceMs);

// How a process ended, from its wait status: "exited with status 3", "killed by signal 9 (Killed)".
std::string describeExit(int status);

}  // namespace rtwall
