#include <rtwall/engine.h>
#include <rtwall/vec.h>

#include <cmath>
#include <numbers>

namespace rtwall {

namespace {
// The identity with three entries of its row-major matrix set.
Transform withEntries(int i, int j, int k, double x, double y, double z) {
    Transform t;
    t.m[i] = x;
    t.m[j] = y;
    t.m[k] = z;
    return t;
}
}  // namespace

Transform Transform::translate(double x, double y, double z) { return withEntries(3, 7, 11, x, y, z); }
Transform Transform::scale(double x, double y, double z) { return withEntries(0, 5, 10, x, y, z); }

Transform Transform::rotateDegrees(double ax, double ay, double az, double degrees) {
    const double len = std::sqrt(ax * ax + ay * ay + az * az);
    if (!(len > 0.0)) return {};
    ax /= len;
    ay /= len;
    az /= len;
    const double a = degrees * std::numbers::pi / 180.0, c = std::cos(a), s = std::sin(a), k = 1.0 - c;
    Transform t;
    t.m = {c + ax * ax * k,      ax * ay * k - az * s, ax * az * k + ay * s, 0,
           ay * ax * k + az * s, c + ay * ay * k,      ay * az * k - ax * s, 0,
           az * ax * k - ay * s, az * ay * k + ax * s, c + az * az * k,      0};
    return t;
}

Transform Transform::operator*(const Transform& b) const {
    Transform r;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 4; ++j) {
            double v = m[4 * i + 0] * b.m[j] + m[4 * i + 1] * b.m[4 + j] + m[4 * i + 2] * b.m[8 + j];
            if (j == 3) v += m[4 * i + 3];
            r.m[4 * i + j] = v;
        }
    }
    return r;
}

Float3 Transform::applyPoint(const Float3& p) const {
    return {float(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]), float(m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7]),
            float(m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11])};
}

const CameraDesc* SceneDesc::findCamera(const std::string& name) const {
    for (const CameraDesc& c : cameras)
        if (c.name == name) return &c;
    return nullptr;
}

std::string SceneDesc::partPath(int32_t part) const {
    std::string path;
    // Bounded by the part count, so a bad parent link cannot loop.
    for (size_t steps = 0; part >= 0 && size_t(part) < parts.size() && steps <= parts.size(); ++steps) {
        path = path.empty() ? parts[size_t(part)].name : parts[size_t(part)].name + "/" + path;
        part = parts[size_t(part)].parent;
    }
    return path;
}

Bounds3 SceneDesc::worldBounds() const {
    Bounds3 world;
    for (const InstanceDesc& in : instances) {
        const Bounds3 b = meshes.at(in.mesh).mesh->bounds();
        if (b.empty()) continue;
        for (int corner = 0; corner < 8; ++corner) {
            const Float3 p{(corner & 1) ? b.hi.x : b.lo.x, (corner & 2) ? b.hi.y : b.lo.y, (corner & 4) ? b.hi.z : b.lo.z};
            world.extend(in.transform.applyPoint(p));
        }
    }
    return world;
}

}  // namespace rtwall
