#include <rtwall/engine.h>

#include <cmath>
#include <numbers>

namespace rtwall {

CameraDesc orbitCamera(const CameraDesc& c, double degrees) {
    const double a = degrees * std::numbers::pi / 180.0, ca = std::cos(a), sa = std::sin(a);
    const double x = c.position.x - c.lookAt.x, z = c.position.z - c.lookAt.z;
    CameraDesc o = c;
    o.position.x = float(c.lookAt.x + ca * x + sa * z);
    o.position.z = float(c.lookAt.z - sa * x + ca * z);
    return o;
}

}  // namespace rtwall
