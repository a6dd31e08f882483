#include <rtwall/warp.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rtwall {

ImageProjection::ImageProjection(const CameraDesc& desc, int w, int h) : width(w), height(h) {
    const Camera camera(desc, w, h);
    const Float3 o = camera.origin(), u = camera.du(), v = camera.dv(), c = camera.corner();
    origin[0] = o.x, origin[1] = o.y, origin[2] = o.z;
    const double m[3][3] = {{u.x, v.x, c.x}, {u.y, v.y, c.y}, {u.z, v.z, c.z}};
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    const double r = det != 0.0 ? 1.0 / det : 0.0;  // a degenerate camera sees nothing
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            // The cofactor of m[j][i]: the inverse is the adjugate over the determinant.
            const int a0 = (j + 1) % 3, a1 = (j + 2) % 3, b0 = (i + 1) % 3, b1 = (i + 2) % 3;
            inv[i][j] = (m[a0][b0] * m[a1][b1] - m[a0][b1] * m[a1][b0]) * r;
        }
}

void checkWarpSource(const WarpSource& s, const char* which) {
    const size_t n = size_t(std::max(0, s.image.width)) * size_t(std::max(0, s.image.height));
    if (s.depth.size() != n || s.image.rgb.size() != n * 3)
        throw std::invalid_argument(std::string("reproject: the ") + which + " view has " + std::to_string(s.depth.size()) +
                                    " depths and " + std::to_string(s.image.rgb.size()) + " colour bytes for " +
                                    std::to_string(s.image.width) + "x" + std::to_string(s.image.height) + " pixels");
}

}  // namespace rtwall
