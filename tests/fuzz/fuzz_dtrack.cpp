// libFuzzer target for the DTrack ASCII parser (display/src/dtrack.cpp): every datagram a
// tracker, or anybody else on the wall's network, can send to the wall's UDP port.
//
// Besides the sanitizers, it checks that a dropped packet says why in one line starting with
// "dtrack packet: ", and that a parsed frame written back by the simulator's writer reads back
// to a frame that writes the very same bytes (the writer rounds once; after that it is exact).
// Parsing again can fail only where rounding to the writer's 6 decimals moves a rotation just
// past the orthonormality tolerance; that is allowed, a crash or a changed frame is not.
//
// Build by hand with clang 14 (from the repository root; no CMake needed):
//   mkdir -p build-fuzz
//   clang++-14 -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
//     -Idisplay/include -Iengine/core/include tests/fuzz/fuzz_dtrack.cpp display/src/dtrack.cpp -o build-fuzz/fuzz_dtrack
// Run (new inputs go to the first directory, the committed seeds are only read):
//   mkdir -p build-fuzz/corpus-dtrack
//   build-fuzz/fuzz_dtrack -max_total_time=120 -timeout=10 build-fuzz/corpus-dtrack tests/fuzz/corpus/dtrack
// With CMake: -DCMAKE_CXX_COMPILER=clang++-14 -DRTWALL_FUZZ=ON, target fuzz_dtrack.
#include <rtwall/tracking.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace rtwall;

namespace {
[[noreturn]] void finding(const char* what, const std::string& detail) {
    std::fprintf(stderr, "fuzz_dtrack: %s: %s\n", what, detail.c_str());
    std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    DTrackParser parser;
    const std::optional<DTrackFrame> frame = parser.parse(std::string_view(reinterpret_cast<const char*>(data), size));
    if (!frame) {
        const std::string& e = parser.error();
        if (e.rfind("dtrack packet: ", 0) != 0 || e.find('\n') != std::string::npos || e.find('\r') != std::string::npos)
            finding("a dropped packet's reason is not one 'dtrack packet: ' line", e);
        return 0;
    }
    const std::string written = writeDTrackPacket(*frame);
    if (written.empty()) return 0;  // only lines of types the wall skips
    const std::optional<DTrackFrame> again = parser.parse(written);
    if (!again) {
        if (parser.error().find("orthonormal") == std::string::npos && parser.error().find("reflection") == std::string::npos)
            finding("the writer's output of a parsed frame does not parse", parser.error() + " in " + written);
        return 0;
    }
    if (writeDTrackPacket(*again) != written) finding("a written frame does not read back to itself", written);
    return 0;
}
