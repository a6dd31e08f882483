// The denoiser's instruction set (rtwall/denoise.h, DenoiseIsa): what this CPU has, the
// process's choice, and the names on the command line.
#include <rtwall/denoise.h>
#include <rtwall/input_error.h>

#include <atomic>
#include <string>

namespace rtwall {

namespace {

bool supports(DenoiseIsa isa) {
    switch (isa) {
    case DenoiseIsa::Avx512: return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
    case DenoiseIsa::Avx2: return __builtin_cpu_supports("avx2");
    default: return true;
    }
}

std::atomic<DenoiseIsa> processIsa{DenoiseIsa::Auto};

}  // namespace

DenoiseIsa denoiseIsaFromName(const std::string& name) {
    if (name == "auto") return DenoiseIsa::Auto;
    if (name == "sse2") return DenoiseIsa::Sse2;
    if (name == "avx2") return DenoiseIsa::Avx2;
    if (name == "avx512") return DenoiseIsa::Avx512;
    throw InputError("denoise instruction set '" + name + "' is not auto, sse2, avx2 or avx512");
}

const char* denoiseIsaName(DenoiseIsa isa) {
    switch (isa) {
    case DenoiseIsa::Sse2: return "sse2";
    case DenoiseIsa::Avx2: return "avx2";
    case DenoiseIsa::Avx512: return "avx512";
    default: return "auto";
    }
}

bool denoiseIsaSupported(DenoiseIsa isa) { return supports(isa); }

DenoiseIsa resolvedDenoiseIsa(DenoiseIsa isa) {
    if (isa != DenoiseIsa::Auto) return isa;
    return supports(DenoiseIsa::Avx512) ? DenoiseIsa::Avx512 : supports(DenoiseIsa::Avx2) ? DenoiseIsa::Avx2 : DenoiseIsa::Sse2;
}

void setDenoiseIsa(DenoiseIsa isa) {
    if (!supports(isa))
        throw InputError(std::string("denoise instruction set ") + denoiseIsaName(isa) + ": this CPU does not have it");
    processIsa.store(isa);
}

DenoiseIsa denoiseIsa() { return processIsa.load(); }

}  // namespace rtwall
