// The command line that renders one tile again (TileError's replay). It lives beside the
// settings it spells out: a setting added to RenderSettings, CameraDesc or TraceOptions that can
// change a pixel belongs here too (tests/engine/replay_test.cpp changes each and renders).
#include <rtwall/engine.h>

#include <charconv>
#include <cmath>

namespace rtwall {

namespace {

// Shortest text that reads back as the same float (and, read as a double and rounded to float,
// too: it is far closer to the float than to the midpoint of two floats).
std::string text(float v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}
std::string text(double v) {
    char buf[40];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}
std::string text(const Float3& v) { return text(v.x) + "," + text(v.y) + "," + text(v.z); }

// A coordinate in the scene file's world, p, such that float(p - origin) (what loading the scene
// file and `rtwall render --camera-position` compute) is `relative` again. origin + relative
// rounded to a double is that p unless `relative` is many orders of magnitude below `origin`;
// then a neighbouring double may be, and where none is, the nearest is the best there is.
double worldCoordinate(double origin, float relative) {
    const double p = origin + double(relative);
    if (float(p - origin) == relative) return p;
    double up = p, down = p;
    for (int i = 0; i < 8; ++i) {
        up = std::nextafter(up, INFINITY);
        if (float(up - origin) == relative) return up;
        down = std::nextafter(down, -INFINITY);
        if (float(down - origin) == relative) return down;
    }
    return p;
}
// At the origin, the float itself (its shortest text is read back as that float).
std::string worldText(double origin, float relative) {
    return origin == 0.0 ? text(relative) : text(worldCoordinate(origin, relative));
}
std::string worldText(const std::array<double, 3>& origin, const Float3& v) {
    return worldText(origin[0], v.x) + "," + worldText(origin[1], v.y) + "," + worldText(origin[2], v.z);
}

// A shell word: as it is when it holds nothing a POSIX shell would read specially.
std::string shellWord(const std::string& s) {
    const bool plain = !s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                                                         "_-+=.,:/@%") == std::string::npos;
    if (plain) return s;
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

const char* viewName(ViewMode v) {
    switch (v) {
    case ViewMode::Shaded: return "shaded";
    case ViewMode::Depth: return "depth";
    case ViewMode::Rays: return "rays";
    case ViewMode::TileTime: return "tile_time";
    case ViewMode::Client: return "client";
    }
    return "shaded";
}

}  // namespace

std::string replayCommand(const TileReplay& t) {
    const RenderSettings& s = t.settings;
    const CameraDesc& c = t.camera;
    const TileRect& r = t.rect;
    std::string cmd = "rtwall render " + shellWord(t.scene);
    if (sceneSourceKind(t.scene) == SceneSourceKind::Builtin) cmd += " --triangles " + std::to_string(t.builtinTriangles);
    cmd += " --width " + std::to_string(s.width) + " --height " + std::to_string(s.height);
    cmd += " --frame " + std::to_string(t.frame);
    cmd += " --region " + std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.x1) + "," +
           std::to_string(r.y1);
    cmd += " --camera-position " + worldText(t.origin, c.position) + " --camera-look-at " + worldText(t.origin, c.lookAt) +
           " --camera-up " + text(c.up) + " --fov " + text(c.fovY);
    if (c.window)
        cmd += " --camera-window " + worldText(t.origin, c.window->lowerLeft) + "," + text(c.window->right) + "," +
               text(c.window->up);
    cmd += std::string(" --kernel ") + (s.kernel == KernelType::Single ? "single" : "packet");
    // The width the tile was traced with (0 would let the replaying CPU choose its own).
    cmd += " --packet-width " + std::to_string(t.trace.packetWidth != 0 ? t.trace.packetWidth : packetWidth());
    cmd += std::string(" --shading ") + (s.shading == ShadingMode::EyeLight ? "eyelight" : "full");
    cmd += " --max-depth " + std::to_string(s.maxDepth) + " --supersample " + std::to_string(s.supersample);
    cmd += std::string(" --shadows ") + (s.shadows ? "on" : "off");
    cmd += " --background " + text(s.background) + " --ambient " + text(s.ambient);
    cmd += " --prune " + text(s.pruneThreshold);
    cmd += s.gi ? " --gi" : " --no-gi";
    cmd += " --samples " + std::to_string(s.samples);
    cmd += std::string(" --view ") + viewName(s.view);
    if (s.view == ViewMode::Client) cmd += " --client-id " + std::to_string(t.trace.clientId);
    return cmd + " --out tile.png";
}

}  // namespace rtwall
