#include <rtwall/image_sample.h>

#include <algorithm>
#include <cmath>

namespace rtwall {

bool sampleBilinear(const Image& image, double x, double y, uint8_t out[3]) {
    const int w = image.width, h = image.height;
    if (!(x >= 0.0 && x <= double(w) && y >= 0.0 && y <= double(h))) return false;
    const double gx = std::clamp(x - 0.5, 0.0, double(w - 1)), gy = std::clamp(y - 0.5, 0.0, double(h - 1));
    const int x0 = int(gx), y0 = int(gy), x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
    const double tx = gx - x0, ty = gy - y0;
    const uint8_t *a = image.pixel(x0, y0), *b = image.pixel(x1, y0), *c = image.pixel(x0, y1), *e = image.pixel(x1, y1);
    for (int k = 0; k < 3; ++k) {
        const double top = a[k] + tx * (b[k] - a[k]), bottom = c[k] + tx * (e[k] - c[k]);
        out[k] = uint8_t(std::lround(top + ty * (bottom - top)));
    }
    return true;
}

}  // namespace rtwall
