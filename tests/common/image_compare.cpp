#include "image_compare.h"

#include <algorithm>
#include <sstream>

namespace rtwall::test {

std::string imageDifference(const Image& a, const Image& b) {
    std::ostringstream s;
    if (a.width != b.width || a.height != b.height || a.rgb.size() != b.rgb.size()) {
        s << "sizes differ: " << a.width << "x" << a.height << " (" << a.rgb.size() << " bytes) vs " << b.width << "x"
          << b.height << " (" << b.rgb.size() << " bytes)";
        return s.str();
    }
    for (size_t i = 0; i + 2 < a.rgb.size(); i += 3) {
        if (a.rgb[i] == b.rgb[i] && a.rgb[i + 1] == b.rgb[i + 1] && a.rgb[i + 2] == b.rgb[i + 2]) continue;
        const size_t p = i / 3;
        s << "first differing pixel (" << p % size_t(a.width) << ", " << p / size_t(a.width) << "): rgb " << int(a.rgb[i])
          << " " << int(a.rgb[i + 1]) << " " << int(a.rgb[i + 2]) << " vs " << int(b.rgb[i]) << " " << int(b.rgb[i + 1]) << " "
          << int(b.rgb[i + 2]);
        return s.str();
    }
    if (a.rgb != b.rgb) return "bytes differ after the last whole pixel";
    return {};
}

size_t differingBytes(const Image& a, const Image& b) {
    if (a.rgb.size() != b.rgb.size()) return std::max(a.rgb.size(), b.rgb.size());
    size_t n = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) n += a.rgb[i] != b.rgb[i];
    return n;
}

}  // namespace rtwall::test
