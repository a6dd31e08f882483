// `rtwall render`'s option values: numbers, vectors and points, the camera, the region.
#include "render_args.h"

#include <rtwall/engine_testing.h>
#include <rtwall/vec.h>

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <vector>

namespace rtwall::cli {

namespace {

// "a,b,c,..." as exactly `count` numbers (each read as the nearest double).
std::vector<double> parseNumbers(const std::string& text, size_t count, const std::string& option) {
    std::vector<double> v;
    const char* p = text.data();
    const char* end = text.data() + text.size();
    while (v.size() < count) {
        double x = 0;
        const auto r = std::from_chars(p, end, x);
        if (r.ec != std::errc() || !std::isfinite(x)) break;
        v.push_back(x);
        p = r.ptr;
        if (p == end || *p != ',') break;
        ++p;
    }
    if (v.size() != count || p != end)
        throw InputError(option + " '" + text + "': expected " + std::to_string(count) + " numbers separated by commas");
    return v;
}
Float3 parseVector(const std::string& text, const std::string& option) {
    const std::vector<double> v = parseNumbers(text, 3, option);
    return {float(v[0]), float(v[1]), float(v[2])};
}
// A point in the scene file's world coordinates, made relative to the scene's origin in double
// precision as loading a scene file does.
Float3 parsePoint(const std::string& text, const std::string& option, const std::array<double, 3>& origin) {
    const std::vector<double> v = parseNumbers(text, 3, option);
    return {float(v[0] - origin[0]), float(v[1] - origin[1]), float(v[2] - origin[2])};
}

}  // namespace

CameraDesc chooseCamera(const SceneDesc& desc, const RenderOptions& o) {
    const CameraDesc* named = o.camera.empty() ? &desc.cameras.front() : desc.findCamera(o.camera);
    if (!named) {
        std::string names;
        for (const CameraDesc& c : desc.cameras) names += (names.empty() ? "" : ", ") + c.name;
        throw InputError(o.scene + ": no camera named '" + o.camera + "' (cameras: " + names + ")");
    }
    CameraDesc c = *named;
    if (!o.cameraPosition.empty()) c.position = parsePoint(o.cameraPosition, "--camera-position", desc.origin);
    if (!o.cameraLookAt.empty()) c.lookAt = parsePoint(o.cameraLookAt, "--camera-look-at", desc.origin);
    if (!o.cameraUp.empty()) c.up = parseVector(o.cameraUp, "--camera-up");
    if (o.fov > 0) c.fovY = float(o.fov);
    if (!o.cameraWindow.empty()) {
        const std::vector<double> v = parseNumbers(o.cameraWindow, 9, "--camera-window");
        const auto& org = desc.origin;
        ProjectionWindow w;
        w.lowerLeft = {float(v[0] - org[0]), float(v[1] - org[1]), float(v[2] - org[2])};
        w.right = {float(v[3]), float(v[4]), float(v[5])};
        w.up = {float(v[6]), float(v[7]), float(v[8])};
        if (length(cross(w.right, w.up)) == 0.0f) throw InputError("--camera-window '" + o.cameraWindow + "': the window has no area");
        c.window = w;
    }
    if (length(c.lookAt - c.position) == 0.0f) throw InputError("the camera looks at its own position");
    if (length(cross(c.lookAt - c.position, c.up)) == 0.0f) throw InputError("the camera's up is parallel to its viewing direction");
    return c;
}

TileRect parseRegion(const std::string& text, const RenderSettings& s) {
    TileRect r;
    if (std::sscanf(text.c_str(), "%d,%d,%d,%d", &r.x0, &r.y0, &r.x1, &r.y1) != 4 || r.x0 < 0 || r.y0 < 0 ||
        r.x1 > s.width || r.y1 > s.height || r.x0 >= r.x1 || r.y0 >= r.y1)
        throw InputError("--region '" + text + "': expected x0,y0,x1,y1 inside the " + std::to_string(s.width) + "x" +
                         std::to_string(s.height) + " image");
    return r;
}

void applyOverrides(RenderSettings& s, const RenderOptions& o) {
    if (o.width) s.width = o.width;
    if (o.height) s.height = o.height;
    if (o.threads >= 0) s.threads = o.threads;
    if (o.tile) s.tileSize = o.tile;
    if (!o.kernel.empty()) s.kernel = o.kernel == "single" ? KernelType::Single : KernelType::Packet;
    if (!o.view.empty()) s.view = viewModeFromName(o.view);
    if (!o.shading.empty()) s.shading = o.shading == "eyelight" ? ShadingMode::EyeLight : ShadingMode::Full;
    if (!o.shadows.empty()) s.shadows = o.shadows == "on";
    if (!o.background.empty()) s.background = parseVector(o.background, "--background");
    if (!o.ambient.empty()) s.ambient = parseVector(o.ambient, "--ambient");
    if (o.gi) s.gi = true;
    if (o.noGi) s.gi = false;
    if (o.samples) s.samples = o.samples;
    if (o.supersample) s.supersample = o.supersample;
    if (o.prune >= 0) s.pruneThreshold = float(o.prune);
    if (o.maxDepth) s.maxDepth = o.maxDepth;
}

TraceOptions traceOptionsOf(const RenderOptions& o) {
    TraceOptions trace;
    trace.packetWidth = o.packetWidth;
    if (o.clientId >= 0) trace.clientId = uint32_t(o.clientId);
    if (!o.fault.empty()) {
        const std::vector<double> f = parseNumbers(o.fault, 3, "--inject-tile-fault");
        trace.fault = injectFault({uint32_t(f[0]), int(f[1]), int(f[2])});
    }
    return trace;
}

}  // namespace rtwall::cli
