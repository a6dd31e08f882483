#include <rtwall/tune.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <string>

namespace rtwall {

namespace {

constexpr int kWindow = 11;
constexpr double kSigma = 1.5;

std::string sizeOf(const Image& img) { return std::to_string(img.width) + "x" + std::to_string(img.height); }

void checkSame(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height)
        throw InputError("the images differ in size: " + sizeOf(a) + " against " + sizeOf(b));
    if (a.rgb.size() != size_t(a.width) * a.height * 3 || b.rgb.size() != a.rgb.size())
        throw InputError("an image's pixel buffer does not match its size " + sizeOf(a));
}

std::vector<double> luminance(const Image& img) {
    std::vector<double> y(size_t(img.width) * img.height);
    for (size_t i = 0; i < y.size(); ++i)
        y[i] = 0.299 * img.rgb[3 * i] + 0.587 * img.rgb[3 * i + 1] + 0.114 * img.rgb[3 * i + 2];
    return y;
}

// The normalised 1D Gaussian; the 2D window is its outer product (separable filtering).
std::array<double, kWindow> gaussian() {
    std::array<double, kWindow> g{};
    double sum = 0;
    for (int i = 0; i < kWindow; ++i) {
        const double x = i - kWindow / 2;
        g[i] = std::exp(-x * x / (2 * kSigma * kSigma));
        sum += g[i];
    }
    for (double& v : g) v /= sum;
    return g;
}

// "Valid" separable filtering: out is (w - 10) x (h - 10).
std::vector<double> filterValid(const std::vector<double>& in, int w, int h) {
    static const std::array<double, kWindow> g = gaussian();
    const int ow = w - kWindow + 1, oh = h - kWindow + 1;
    std::vector<double> rows(size_t(ow) * h), out(size_t(ow) * oh);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < ow; ++x) {
            double s = 0;
            for (int k = 0; k < kWindow; ++k) s += g[k] * in[size_t(y) * w + x + k];
            rows[size_t(y) * ow + x] = s;
        }
    for (int y = 0; y < oh; ++y)
        for (int x = 0; x < ow; ++x) {
            double s = 0;
            for (int k = 0; k < kWindow; ++k) s += g[k] * rows[size_t(y + k) * ow + x];
            out[size_t(y) * ow + x] = s;
        }
    return out;
}

}  // namespace

double ssimLuminance(const Image& a, const Image& b) {
    checkSame(a, b);
    if (a.width < kWindow || a.height < kWindow)
        throw InputError("SSIM needs images of at least 11x11 pixels, not " + sizeOf(a));
    const int w = a.width, h = a.height;
    const std::vector<double> x = luminance(a), y = luminance(b);
    std::vector<double> xx(x.size()), yy(x.size()), xy(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
        xx[i] = x[i] * x[i];
        yy[i] = y[i] * y[i];
        xy[i] = x[i] * y[i];
    }
    const std::vector<double> mx = filterValid(x, w, h), my = filterValid(y, w, h), mxx = filterValid(xx, w, h),
                              myy = filterValid(yy, w, h), mxy = filterValid(xy, w, h);
    const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
    double sum = 0;
    for (size_t i = 0; i < mx.size(); ++i) {
        const double vx = mxx[i] - mx[i] * mx[i], vy = myy[i] - my[i] * my[i], cxy = mxy[i] - mx[i] * my[i];
        sum += ((2 * mx[i] * my[i] + c1) * (2 * cxy + c2)) / ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
    }
    return sum / double(mx.size());
}

ImageError compareImages(const Image& test, const Image& reference) {
    checkSame(test, reference);
    ImageError e;
    double se = 0, abs = 0;
    for (size_t i = 0; i < test.rgb.size(); ++i) {
        const int d = std::abs(int(test.rgb[i]) - int(reference.rgb[i]));
        se += double(d) * d;
        abs += d;
        if (d > e.maxError) {
            e.maxError = d;
            const size_t p = i / 3;
            e.maxX = int(p % size_t(test.width));
            e.maxY = int(p / size_t(test.width));
        }
    }
    const double n = double(test.rgb.size());
    e.rmse = n > 0 ? std::sqrt(se / n) : 0.0;
    e.meanAbs = n > 0 ? abs / n : 0.0;
    e.psnrDb = e.rmse == 0 ? kIdenticalPsnr : 20.0 * std::log10(255.0 / e.rmse);
    e.ssim = ssimLuminance(test, reference);
    e.flip = e.identical() ? 0.0 : flipMean(test, reference);
    return e;
}

Image differenceImage(const Image& test, const Image& reference, int scaleLevels) {
    checkSame(test, reference);
    Image out{test.width, test.height, std::vector<uint8_t>(test.rgb.size())};
    std::vector<int> err(size_t(test.width) * test.height);
    int largest = 0;
    for (size_t p = 0; p < err.size(); ++p) {
        int d = 0;
        for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(test.rgb[3 * p + c]) - int(reference.rgb[3 * p + c])));
        err[p] = d;
        largest = std::max(largest, d);
    }
    const double scale = scaleLevels > 0 ? scaleLevels : std::max(1, largest);
    // Black, blue, green, yellow, red at 0, 1/4, 1/2, 3/4, 1 of the scale; no error stays black.
    static const double stops[5][3] = {{0, 0, 0}, {0, 0, 255}, {0, 200, 0}, {255, 230, 0}, {255, 0, 0}};
    for (size_t p = 0; p < err.size(); ++p) {
        const double t = std::min(1.0, err[p] / scale) * 4.0;
        const int k = std::min(3, int(t));
        const double f = t - k;
        for (int c = 0; c < 3; ++c)
            out.rgb[3 * p + c] = uint8_t(std::lround(stops[k][c] + (stops[k + 1][c] - stops[k][c]) * f));
    }
    return out;
}

Image resizeBilinear(const Image& src, int width, int height) {
    if (src.width <= 0 || src.height <= 0 || width <= 0 || height <= 0)
        throw InputError("cannot resample a " + sizeOf(src) + " image to " + std::to_string(width) + "x" +
                         std::to_string(height));
    if (src.width == width && src.height == height) return src;
    Image out{width, height, std::vector<uint8_t>(size_t(width) * height * 3)};
    const double sx = double(src.width) / width, sy = double(src.height) / height;
    for (int y = 0; y < height; ++y) {
        const double fy = std::clamp((y + 0.5) * sy - 0.5, 0.0, double(src.height - 1));
        const int y0 = int(fy), y1 = std::min(y0 + 1, src.height - 1);
        const double wy = fy - y0;
        for (int x = 0; x < width; ++x) {
            const double fx = std::clamp((x + 0.5) * sx - 0.5, 0.0, double(src.width - 1));
            const int x0 = int(fx), x1 = std::min(x0 + 1, src.width - 1);
            const double wx = fx - x0;
            for (int c = 0; c < 3; ++c) {
                const double top = src.pixel(x0, y0)[c] * (1 - wx) + src.pixel(x1, y0)[c] * wx;
                const double bottom = src.pixel(x0, y1)[c] * (1 - wx) + src.pixel(x1, y1)[c] * wx;
                out.pixel(x, y)[c] = uint8_t(std::lround(top * (1 - wy) + bottom * wy));
            }
        }
    }
    return out;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    const size_t n = v.size(), mid = n / 2;
    std::nth_element(v.begin(), v.begin() + mid, v.end());
    if (n % 2) return v[mid];
    const double upper = v[mid];
    return 0.5 * (*std::max_element(v.begin(), v.begin() + mid) + upper);
}

}  // namespace rtwall
