// libFuzzer target for the MPCDI reader (display/src/mpcdi.cpp, issue 30): a calibration file is
// a user's input, and a damaged or hostile one must be one InputError line, never a crash, a hang
// or an allocation for sizes it merely claims (-malloc_limit_mb holds it to that).
//
// The first byte picks what the rest is (a byte the fuzzer mutates like any other):
//   0: a whole .mpcdi archive (zip: libzip's reading, then mpcdi.xml and its entries);
//   1: mpcdi.xml and entries without the zip (the fuzzer reaches the XML and PFM/PNG checks far
//      more often than through a zip's CRCs): the parts are split at "\0\0"; the first is the
//      XML, the n-th distinct entry the reader asks for is part n + 1 (absent past the last);
//   2: a PFM geometry warp alone.
// Besides the sanitizers it checks that an error is one line starting with the file's name, and
// that what is read holds together (grid sizes, sample counts, map values in [0, 1]).
//
// Seeds: tests/fuzz/corpus/mpcdi, written by tools/mpcdi_testgen.py (see the README there).
// Run by hand: build-fuzz/tests/fuzz/fuzz_mpcdi -max_total_time=600 -malloc_limit_mb=512 DIR tests/fuzz/corpus/mpcdi
#include <rtwall/input_error.h>
#include <rtwall/mpcdi.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <string_view>
#include <vector>

using namespace rtwall;

namespace {

[[noreturn]] void finding(const char* what, const std::string& detail) {
    std::fprintf(stderr, "fuzz_mpcdi: %s: %s\n", what, detail.c_str());
    std::abort();
}

void checkMessage(const std::string& e) {
    if (e.rfind("in.mpcdi: ", 0) != 0) finding("an error does not start with the file's name", e);
    if (e.find('\n') != std::string::npos) finding("an error of more than one line", e);
}

void checkWarp(const MpcdiWarp& w) {
    if (w.width < 1 || w.height < 1 || w.samples.size() != size_t(w.width) * size_t(w.height))
        finding("a warp's samples disagree with its size", std::to_string(w.width) + "x" + std::to_string(w.height));
    size_t valid = 0;
    for (const Float3& p : w.samples) {
        if (std::isinf(p.x) || std::isinf(p.y) || std::isinf(p.z)) finding("an infinite sample was accepted", "");
        valid += !(std::isnan(p.x) || std::isnan(p.y) || std::isnan(p.z));
    }
    if (valid != w.validSamples) finding("validSamples is wrong", std::to_string(w.validSamples));
}

void checkFile(const MpcdiFile& f) {
    if (f.buffers.empty()) finding("a file without buffers was accepted", "");
    for (const MpcdiBuffer& b : f.buffers) {
        if (b.regions.empty()) finding("a buffer without regions was accepted", b.id);
        for (const MpcdiRegion& r : b.regions) {
            checkWarp(r.warp);
            if (f.profile == MpcdiProfile::Simulation3d && !r.frustum) finding("a 3d region without a frustum was accepted", r.id);
            if (r.frustum)  // the wall traces along these: finite at the frustum's corners, hence inside it
                for (const double u : {0.0, 1.0})
                    for (const double v : {0.0, 1.0}) {
                        const Float3 d = frustumDirection(*r.frustum, u, v);
                        if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z)) finding("a frustum direction is not finite", r.id);
                    }
            if (r.warp.validSamples == 0) finding("an all-NaN warp was accepted", r.id);
            for (const auto* m : {&r.alpha, &r.beta}) {
                if (!*m) continue;
                const MpcdiMap& map = **m;
                if (map.width != r.xResolution || map.height != r.yResolution ||
                    map.values.size() != size_t(map.width) * size_t(map.height) * size_t(map.components))
                    finding("a blend map's size disagrees with its region", r.id);
                for (float v : map.values)
                    if (!(v >= 0 && v <= 1)) finding("a blend map value outside [0, 1]", std::to_string(v));
            }
        }
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const int mode = data[0] % 3;
    const std::span<const uint8_t> rest(data + 1, size - 1);
    try {
        if (mode == 0) {
            checkFile(parseMpcdi(rest, "in.mpcdi"));
        } else if (mode == 1) {
            std::vector<std::string_view> parts;
            std::string_view all(reinterpret_cast<const char*>(rest.data()), rest.size());
            for (;;) {
                const size_t cut = all.find(std::string_view("\0\0", 2));
                parts.push_back(all.substr(0, cut));
                if (cut == std::string_view::npos) break;
                all.remove_prefix(cut + 2);
            }
            std::map<std::string, size_t> asked;
            const MpcdiEntries entries = [&](const std::string& name) -> std::optional<std::vector<uint8_t>> {
                const size_t n = asked.emplace(name, asked.size()).first->second;
                if (n + 1 >= parts.size()) return std::nullopt;
                return std::vector<uint8_t>(parts[n + 1].begin(), parts[n + 1].end());
            };
            checkFile(parseMpcdiXml(parts[0], entries, "in.mpcdi"));
        } else {
            checkWarp(parsePfm(rest, "in.mpcdi"));
        }
    } catch (const InputError& e) {
        checkMessage(e.what());
    }
    return 0;
}
