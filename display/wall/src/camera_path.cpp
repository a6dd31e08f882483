// Camera paths (configs/README.md, "Camera paths"): keyframes at frame numbers, read, written
// (the wall's recorder, key R) and interpolated here and nowhere else.
#include <rtwall/toml_reader.h>
#include <rtwall/wall.h>

#include <cstdio>
#include <sstream>

namespace rtwall {

std::vector<CameraKey> readCameraPath(const std::filesystem::path& file, const std::array<double, 3>& origin) {
    using namespace toml_reader;
    const toml::table root = parseFile(file);
    Reader top(file, root, "");
    std::vector<CameraKey> keys;
    forEachTable(top, file, "key", [&](Reader& r, const toml::table&) {
        CameraKey k;
        k.frame = r.integer("frame", 0, 0, 100'000'000);
        if (!keys.empty() && k.frame <= keys.back().frame)
            r.fail(r.find("frame"), "key 'frame': keyframes must have increasing frame numbers");
        // World coordinates in double, made relative to the scene's origin before they become floats.
        auto rel = [&](const std::array<double, 3>& p) {
            return Float3{float(p[0] - origin[0]), float(p[1] - origin[1]), float(p[2] - origin[2])};
        };
        k.camera.position = rel(r.vec3d("position", {}, true));
        k.camera.lookAt = rel(r.vec3d("look_at", {}, true));
        k.camera.up = r.vec3("up", k.camera.up);
        k.camera.fovY = float(r.number("fov", k.camera.fovY, 0.01, 179.0));
        keys.push_back(k);
    });
    top.finish();
    if (keys.empty()) throw InputError(file.string() + ": a camera path needs at least one [[key]]");
    return keys;
}

std::string writeCameraPath(const std::vector<CameraKey>& keys, const std::array<double, 3>& origin) {
    std::ostringstream os;
    os << "# A camera path recorded by rtwall run: replay with rtwall run --camera-path FILE\n"
       << "# Positions in world coordinates (the scene file's), whatever origin the scene was rebased to.\n";
    char buf[160];
    // Sums and prints in double: 17 significant digits keep a float pose exact at 1e6 and beyond.
    auto world = [&](Float3 a) {
        std::snprintf(buf, sizeof buf, "[%.17g, %.17g, %.17g]", double(a.x) + origin[0], double(a.y) + origin[1],
                      double(a.z) + origin[2]);
        return std::string(buf);
    };
    for (const CameraKey& k : keys) {
        const CameraDesc& c = k.camera;
        os << "\n[[key]]\nframe = " << k.frame << "\nposition = " << world(c.position) << "\nlook_at = " << world(c.lookAt);
        std::snprintf(buf, sizeof buf, "\nup = [%.9g, %.9g, %.9g]\nfov = %.9g\n", double(c.up.x), double(c.up.y),
                      double(c.up.z), double(c.fovY));
        os << buf;
    }
    return os.str();
}

CameraDesc mixCameras(const CameraDesc& a, const CameraDesc& b, float t) {
    auto mix = [t](Float3 p, Float3 q) { return Float3{p.x + (q.x - p.x) * t, p.y + (q.y - p.y) * t, p.z + (q.z - p.z) * t}; };
    CameraDesc c = a;
    c.position = mix(a.position, b.position);
    c.lookAt = mix(a.lookAt, b.lookAt);
    c.up = mix(a.up, b.up);
    if (length(c.up) < 1e-6f) c.up = t < 0.5f ? a.up : b.up;  // opposite ups have no halfway
    c.fovY = a.fovY + (b.fovY - a.fovY) * t;
    return c;
}

CameraDesc cameraAt(const std::vector<CameraKey>& keys, int frame) {
    if (keys.empty()) throw std::invalid_argument("cameraAt: no keys");
    if (frame <= keys.front().frame) return keys.front().camera;
    for (size_t i = 1; i < keys.size(); ++i)
        if (frame <= keys[i].frame) {
            const CameraKey &a = keys[i - 1], &b = keys[i];
            return mixCameras(a.camera, b.camera, float(frame - a.frame) / float(b.frame - a.frame));
        }
    return keys.back().camera;
}

}  // namespace rtwall
