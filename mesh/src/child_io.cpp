// What the importers that run in a forked child (VTK, STEP/IGES) share: writing whole buffers to
// a pipe or memfd, and dying of a crash by the signal itself.
#include "mesh_internal.h"

#include <cerrno>
#include <csignal>

#include <sys/resource.h>
#include <unistd.h>

namespace rtwall::detail {

bool writeAll(int fd, const void* data, size_t n) {
    auto p = static_cast<const char*>(data);
    while (n > 0) {
        const ssize_t w = ::write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return false;
        p += w;
        n -= size_t(w);
    }
    return true;
}

void dropInheritedCrashHandlers() {
    // A crash in the child is the parent's to report ("VTK crashed reading the file"): a handler
    // inherited from the parent (a crash reporter, libFuzzer's, which would record the input as
    // its own finding and write an artifact) must not run in the child's copy, nor may the
    // crash leave a core file behind.
    for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(sig, SIG_DFL);
    const rlimit noCore{0, 0};
    ::setrlimit(RLIMIT_CORE, &noCore);
}

}  // namespace rtwall::detail
