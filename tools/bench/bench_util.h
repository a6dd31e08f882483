// Small helpers every benchmark shares: medians (rtwall/tune.h), timing, PSNR.
#pragma once

#include <rtwall/engine.h>
#include <rtwall/image.h>
#include <rtwall/tune.h>

#include <toml++/toml.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <span>
#include <sstream>

namespace rtwall::bench {

// Wall-clock seconds that f takes.
template <class F> double secondsOf(F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Wall-clock seconds since construction or the last restart().
class Stopwatch {
public:
    double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
    void restart() { start_ = std::chrono::steady_clock::now(); }

private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// PSNR in dB of two images of the same size, infinite when they are identical. Cheaper than
// compareImages (no SSIM, no FLIP) for benchmarks that quote PSNR alone.
inline double psnrDb(const Image& a, const Image& b) {
    double se = 0;
    for (size_t i = 0; i < a.rgb.size() && i < b.rgb.size(); ++i) {
        const double d = double(a.rgb[i]) - double(b.rgb[i]);
        se += d * d;
    }
    if (se == 0) return INFINITY;
    return 10.0 * std::log10(255.0 * 255.0 * double(a.rgb.size()) / se);
}

// A linear frame (3 floats a pixel, as renderFrameLinear and the denoiser give it) as the 8-bit
// sRGB image the wall shows.
inline Image srgbImage(std::span<const float> linear, int width, int height) {
    Image img;
    img.width = width;
    img.height = height;
    img.rgb.resize(linear.size());
    linearToSrgb8(linear.data(), linear.size(), img.rgb.data());
    return img;
}

// A result as TOML text, for the benchmarks whose human-readable form is their whole result.
inline void printToml(std::FILE* text, const toml::table& result) {
    std::ostringstream out;
    out << result << "\n";
    std::fputs(out.str().c_str(), text);
}

}  // namespace rtwall::bench
