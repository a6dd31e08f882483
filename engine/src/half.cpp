// IEEE 754 half-precision conversions (round to nearest even) with the compiler's and the CPU's
// own: GCC's _Float16 (a libgcc call per value), the F16C instructions for the bulk versions
// where the CPU has them (8 values per instruction, about 100 times faster), and F16C alone
// where the compiler has no _Float16 on x86 (clang 14, the fuzz build). All round identically
// (checked exhaustively over every float), so every build and every PC sends and sums the same
// values.
#include <rtwall/engine.h>

#include <immintrin.h>

#include <bit>

namespace rtwall {

namespace {

// One value through F16C. Not _cvtss_sh: clang's headers define it as a C99 compound literal
// (a -Wc99-extensions warning in C++); this is the same instruction on the low lane.
__attribute__((target("f16c"))) inline uint16_t halfOfF16c(float v) {
    return static_cast<uint16_t>(_mm_extract_epi16(_mm_cvtps_ph(_mm_set_ss(v), _MM_FROUND_TO_NEAREST_INT), 0));
}

__attribute__((target("f16c,avx"))) void toHalfF16c(const float* in, size_t count, uint16_t* out) {
    size_t i = 0;
    for (; i + 8 <= count; i += 8)
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i),
                         _mm256_cvtps_ph(_mm256_loadu_ps(in + i), _MM_FROUND_TO_NEAREST_INT));
    for (; i < count; ++i) out[i] = halfOfF16c(in[i]);
}

__attribute__((target("f16c,avx"))) void fromHalfF16c(const uint16_t* in, size_t count, float* out) {
    size_t i = 0;
    for (; i + 8 <= count; i += 8)
        _mm256_storeu_ps(out + i, _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i))));
    for (; i < count; ++i) out[i] = _cvtsh_ss(in[i]);
}

}  // namespace

#if defined(__FLT16_MAX__)

uint16_t halfFromFloat(float v) { return std::bit_cast<uint16_t>(static_cast<_Float16>(v)); }
float floatFromHalf(uint16_t bits) { return static_cast<float>(std::bit_cast<_Float16>(bits)); }

namespace {
bool hasF16c() {
    static const bool yes = __builtin_cpu_supports("f16c") && __builtin_cpu_supports("avx");
    return yes;
}
}  // namespace

void halfFromFloat(const float* in, size_t count, uint16_t* out) {
    if (hasF16c()) return toHalfF16c(in, count, out);
    for (size_t i = 0; i < count; ++i) out[i] = halfFromFloat(in[i]);
}

void floatFromHalf(const uint16_t* in, size_t count, float* out) {
    if (hasF16c()) return fromHalfF16c(in, count, out);
    for (size_t i = 0; i < count; ++i) out[i] = floatFromHalf(in[i]);
}

#else

__attribute__((target("f16c"))) uint16_t halfFromFloat(float v) {
    return halfOfF16c(v);
}
__attribute__((target("f16c"))) float floatFromHalf(uint16_t bits) { return _cvtsh_ss(bits); }
void halfFromFloat(const float* in, size_t count, uint16_t* out) { toHalfF16c(in, count, out); }
void floatFromHalf(const uint16_t* in, size_t count, float* out) { fromHalfF16c(in, count, out); }

#endif

}  // namespace rtwall
