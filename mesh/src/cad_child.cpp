// STEP and IGES imports in a child process.
//
// OpenCASCADE is not written for hostile input: fuzz_step found eight distinct null dereferences
// in OCCT 7.6's STEP translator within minutes (docs/assemblies.md, "Malformed STEP and IGES
// files"), plain segmentation faults that no handler can unwind safely, and nothing in OCCT
// bounds the memory or the time one import takes. None of that may take rtwall down. So the import runs in a forked child under an address-space limit and a stall limit,
// and answers through a pipe, one line per message:
//   P <fraction>   progress (the parent's progress function sees it; false there kills the child)
//   W <line>       a warning of the assembly
//   E <line>       the one-line error; the child then exits with status 3
// and, on success, with the assembly as assembly-cache bytes in a memfd, which the parent maps
// and validates in full like any cache (so the child's result is trusted no more than a file).
// The tessellated meshes stay where the child wrote them (views of the memfd's pages): the
// geometry exists once in the parent, and the child's copy goes with it. A crash is reported as a
// malformed file; no message within the stall limit (CPU time of the child) is reported as a
// hang and the child is killed. The cost is a fork and one encode/decode of the result (docs/assemblies.md).
#include "mesh_internal.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <new>
#include <string>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RTWALL_CAD_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define RTWALL_CAD_ASAN 1
#endif

namespace rtwall::detail {
namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const fs::path& file, const std::string& what) { throw InputError(file.string() + ": " + what); }

// One message line: control characters (a newline inside a name) become spaces.
void sendLine(int fd, char kind, const std::string& text) {
    std::string line(1, kind);
    line += ' ';
    line += text.substr(0, 4000);
    for (size_t i = 2; i < line.size(); ++i)
        if (static_cast<unsigned char>(line[i]) < 0x20) line[i] = ' ';
    line += '\n';
    writeAll(fd, line.data(), line.size());
}

// VmSize of this process in bytes (the address space the limit adds to), or 0.
uint64_t addressSpaceNow() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.starts_with("VmSize:")) return std::stoull(line.substr(7)) * 1024;
    return 0;
}

// How much more address space the child may take: OCCT needs some tens of bytes per byte of
// STEP (a 6.3 MB file peaks at 258 MB, docs/assemblies.md), tessellation more with small
// deflections; a count in a malformed file must not make it take the machine. At least 4 GiB,
// 256 bytes per byte of file, at most the physical memory.
uint64_t memoryBudget(uint64_t fileSize) {
    const uint64_t physical = uint64_t(::sysconf(_SC_PHYS_PAGES)) * uint64_t(::sysconf(_SC_PAGESIZE));
    const uint64_t want = std::max<uint64_t>(uint64_t(4) << 30, fileSize * 256);
    return physical > 0 ? std::min(want, physical) : want;
}

// The child: import, encode, write the bytes into `memfd`; messages on `out`. Never returns.
[[noreturn]] void runChild(const fs::path& file, const AssemblyOptions& options, const AssemblyKey& key, int memfd, int out,
                           uint64_t fileSize) {
    dropInheritedCrashHandlers();
#ifndef RTWALL_CAD_ASAN
    // AddressSanitizer reserves terabytes of shadow address space; the limit is left to it there.
    if (const uint64_t now = addressSpaceNow(); now > 0) {
        const rlimit limit{rlim_t(now + memoryBudget(fileSize)), rlim_t(now + memoryBudget(fileSize))};
        ::setrlimit(RLIMIT_AS, &limit);
    }
#else
    (void)fileSize;
#endif
    int code = 4;
    try {
        AssemblyOptions o = options;
        double sent = -1;
        o.progress = [out, &sent](double f) {
            if (f - sent >= 0.001 || f >= 1.0) {
                char buf[32];
                std::snprintf(buf, sizeof buf, "%.4f", f);
                sendLine(out, 'P', buf);
                sent = f;
            }
            return true;
        };
        // The parent held occtMutex() when it forked: this copy of it is locked, and this process
        // is the only user.
        const Assembly a = importCadHere(file, o, false);
        for (const std::string& w : a.warnings) sendLine(out, 'W', w);
        sendLine(out, 'R', a.reader);
        const std::vector<unsigned char> bytes = encodeAssemblyCache(a, key);
        code = writeAll(memfd, bytes.data(), bytes.size()) ? 0 : 5;
    } catch (const InputError& e) {
        sendLine(out, 'E', e.what());
        code = 3;
    } catch (const std::bad_alloc&) {
        sendLine(out, 'E', file.string() + ": out of memory while reading (the importer's limit is " +
                               std::to_string(memoryBudget(fileSize) >> 20) + " MiB)");
        code = 3;
    } catch (const std::exception& e) {
        sendLine(out, 'E', file.string() + ": " + e.what());
        code = 3;
    } catch (...) {
    }
    ::_exit(code);
}

// CPU seconds (user and system) that process `pid` has used, from /proc/PID/stat; -1 if unknown.
double cpuSecondsOf(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string stat;
    std::getline(in, stat);
    const size_t close = stat.rfind(')');  // the command name may hold spaces and parentheses
    if (close == std::string::npos) return -1;
    std::istringstream fields(stat.substr(close + 2));
    std::string field;
    unsigned long long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && fields >> field; ++i) {
        if (i == 14) utime = std::strtoull(field.c_str(), nullptr, 10);
        if (i == 15) stime = std::strtoull(field.c_str(), nullptr, 10);
    }
    return double(utime + stime) / double(::sysconf(_SC_CLK_TCK));
}

struct Fd {
    int fd = -1;
    ~Fd() {
        if (fd >= 0) ::close(fd);
    }
};

// The child's exit status, its error line, and on success the assembly it left in `memfd`
// (also written to the cache file when there is one).
void finishChild(const fs::path& file, const AssemblyKey& key, const fs::path* cacheFile, int status, const std::string& error,
                 int memfd, CadImport& result) {
    if (WIFSIGNALED(status))
        fail(file, "OpenCASCADE crashed reading the file (signal " + std::to_string(WTERMSIG(status)) + ": " +
                       strsignal(WTERMSIG(status)) + "); the file is malformed");
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (code == 3 && !error.empty()) throw InputError(error);
    if (code != 0) fail(file, "the importer failed (exit status " + std::to_string(code) + ")");

    struct stat st {};
    if (::fstat(memfd, &st) != 0 || st.st_size <= 0) fail(file, "the importer returned no assembly");
    const auto size = size_t(st.st_size);
    void* map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, memfd, 0);
    if (map == MAP_FAILED) fail(file, "cannot map the assembly the importer returned");
    const std::shared_ptr<const void> keep(map, [size](const void* p) { ::munmap(const_cast<void*>(p), size); });
    const auto* bytes = static_cast<const unsigned char*>(map);
    std::vector<std::string> warnings = std::move(result.assembly.warnings);
    result.assembly = decodeAssemblyCache(bytes, size, key, file.string() + " (the importer's result)", keep);
    result.assembly.warnings = std::move(warnings);
    if (cacheFile) {
        try {
            writeAssemblyCacheBytes(bytes, size, *cacheFile);
        } catch (const std::exception& e) {
            result.cacheError = e.what();
        }
    }
}

}  // namespace

CadImport importCad(const fs::path& file, const AssemblyOptions& options, const AssemblyKey& key, const fs::path* cacheFile) {
    CadImport result;
    if (const char* inProcess = std::getenv("RTWALL_CAD_IN_PROCESS"); inProcess && *inProcess == '1') {
        result.assembly = importCadHere(file, options);
        if (cacheFile) {
            try {
                writeAssemblyCache(result.assembly, key, *cacheFile);
            } catch (const std::exception& e) {
                result.cacheError = e.what();
            }
        }
        return result;
    }
    // What importCadHere checks before OCCT sees the file, here, so that the usual mistakes
    // cost no fork.
    if (!(options.linearDeflection > 0) || !(options.angularDeflection > 0)) fail(file, "tessellation deflections must be positive");
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) fail(file, "cannot open the file");
    const uint64_t fileSize = fs::file_size(file, ec);

    Fd memfd{::memfd_create("rtwall-cad-assembly", MFD_CLOEXEC)};
    int pipeFds[2];
    if (memfd.fd < 0 || ::pipe2(pipeFds, O_CLOEXEC) != 0) fail(file, std::string("cannot start the importer: ") + std::strerror(errno));
    Fd in{pipeFds[0]};
    pid_t pid;
    {
        // No other thread may be inside OCCT while the child's copy of the process is taken.
        const std::lock_guard<std::mutex> lock(occtMutex());
        std::fflush(nullptr);
        pid = ::fork();
        if (pid == 0) {
            ::close(pipeFds[0]);
            runChild(file, options, key, memfd.fd, pipeFds[1], fileSize);
        }
    }
    ::close(pipeFds[1]);
    if (pid < 0) fail(file, std::string("cannot start the importer: ") + std::strerror(errno));

    // Messages until the child exits (not only until the pipe closes: a process forked meanwhile
    // by another thread may hold the pipe's write end), a stall, or a cancel.
    auto killChild = [pid] {
        ::kill(pid, SIGKILL);
        int status = 0;
        while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
    };
    // A hang is a child that reports nothing while it burns CPU: parsing (before the first
    // progress report) runs at some MB/s, each later step reports. Counted in the child's CPU
    // seconds, so that a loaded machine does not make a slow import a hang; a child blocked
    // without using CPU is caught by ten times that in wall time.
    const double stallCpu = 120.0 + double(fileSize) / double(1 << 20);
    const auto stallWall = std::chrono::seconds(int64_t(10 * stallCpu));
    auto lastMessage = std::chrono::steady_clock::now();
    double cpuAtLastMessage = 0;
    std::string pending, error, reader;
    double lastFraction = 0;
    auto lastAsked = std::chrono::steady_clock::now();
    char buf[4096];
    int status = 0;
    for (bool exited = false, open = true; !exited;) {
        // After the child has exited, what it wrote is in the pipe: drain it without waiting.
        if (::waitpid(pid, &status, WNOHANG) == pid) exited = true;
        for (pollfd pfd{in.fd, POLLIN, 0}; open && ::poll(&pfd, 1, exited ? 0 : 100) > 0; pfd.revents = 0) {
            const ssize_t n = ::read(in.fd, buf, sizeof buf);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                open = false;
                break;
            }
            pending.append(buf, size_t(n));
            lastMessage = std::chrono::steady_clock::now();
            cpuAtLastMessage = cpuSecondsOf(pid);
            if (!exited) break;
        }
        for (size_t nl; (nl = pending.find('\n')) != std::string::npos;) {
            const std::string line = pending.substr(0, nl);
            pending.erase(0, nl + 1);
            if (line.size() < 2) continue;
            const std::string text = line.substr(2);
            if (line[0] == 'P') {
                lastFraction = std::strtod(text.c_str(), nullptr);
                if (options.progress && !options.progress(lastFraction)) {
                    if (!exited) killChild();
                    throw Cancelled();
                }
            } else if (line[0] == 'W') {
                result.assembly.warnings.push_back(text);
            } else if (line[0] == 'R') {
                reader = text;
            } else if (line[0] == 'E' && error.empty()) {
                error = text;
            }
        }
        // Parsing a large file reports nothing for seconds: the progress function is still asked
        // every 0.1 s, so that a cancel (Ctrl-C) takes effect at once.
        if (!exited && options.progress && std::chrono::steady_clock::now() - lastAsked > std::chrono::milliseconds(100)) {
            lastAsked = std::chrono::steady_clock::now();
            if (!options.progress(lastFraction)) {
                killChild();
                throw Cancelled();
            }
        }
        if (!exited && (cpuSecondsOf(pid) - cpuAtLastMessage > stallCpu || std::chrono::steady_clock::now() - lastMessage > stallWall)) {
            killChild();
            fail(file, "OpenCASCADE did not finish reading the file (no progress in " + std::to_string(int(stallCpu)) +
                           " s of CPU time); the file is malformed or too large");
        }
        if (!open && !exited) {
            // The pipe closed: the child is exiting; wait for it.
            while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
            }
            exited = true;
        }
    }
    finishChild(file, key, cacheFile, status, error, memfd.fd, result);
    result.assembly.reader = reader;
    return result;
}

}  // namespace rtwall::detail
