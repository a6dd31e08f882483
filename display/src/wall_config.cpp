// Wall configs: strict reading (every key checked, every problem with its line), validation of
// the layout as a whole (overlaps, bezels, stereo eyes), and writing back out. The keys, their
// ranges and their help are the tables in wall_config_keys.h.
#include "wall_config_sections.h"

#include <rtwall/display.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <set>
#include <sstream>
#include <stdexcept>

namespace rtwall {

namespace {

using toml_reader::KeyType;
using toml_reader::Reader;

// An array of exactly n integers in the table's range.
template <size_t N>
std::array<int, N> intArray(Reader& r, const std::string& key, std::array<int, N> def, bool required = false) {
    const toml_reader::Key& spec = r.spec(key, KeyType::Integers);
    const int lo = int(spec.lo), hi = int(spec.hi);
    const toml::node* n = r.find(key);
    if (!n) {
        if (required) r.fail(nullptr, "missing required key '" + key + "'");
        return def;
    }
    const toml::array* a = n->as_array();
    if (!a || a->size() != N) r.fail(n, "key '" + key + "': expected an array of " + std::to_string(N) + " integers");
    std::array<int, N> v{};
    for (size_t i = 0; i < N; ++i) {
        const auto* e = a->get(i)->as_integer();
        if (!e) r.fail(n, "key '" + key + "': element " + std::to_string(i) + " is " + Reader::typeName(*a->get(i)) + ", not an integer");
        if (e->get() < lo || e->get() > hi)
            r.fail(n, "key '" + key + "': element " + std::to_string(i) + " (" + std::to_string(e->get()) +
                          ") is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        v[i] = int(e->get());
    }
    return v;
}

// A number for all four edges, or an array of four numbers (left, right, top, bottom), in the
// table's range.
std::array<double, 4> edgeNumbers(Reader& r, const std::string& key, std::array<double, 4> def) {
    const toml_reader::Key& spec = r.spec(key, KeyType::Numbers);
    const double lo = spec.lo, hi = spec.hi;
    const toml::node* n = r.find(key);
    if (!n) return def;
    auto one = [&](const toml::node& e, const std::string& what) {
        double v;
        if (auto i = e.as_integer()) v = double(i->get());
        else if (auto f = e.as_floating_point()) v = f->get();
        else r.fail(n, "key '" + key + "': " + what + " is " + Reader::typeName(e) + ", not a number");
        if (!std::isfinite(v) || v < lo || v > hi) {
            std::ostringstream os;
            os << "key '" << key << "': " << what << " (" << v << ") is out of range [" << lo << ", " << hi << "]";
            r.fail(n, os.str());
        }
        return v;
    };
    if (const toml::array* a = n->as_array()) {
        if (a->size() != 4) r.fail(n, "key '" + key + "': expected a number or an array of 4 numbers (left, right, top, bottom)");
        std::array<double, 4> v{};
        for (size_t i = 0; i < 4; ++i) v[i] = one(*a->get(i), "element " + std::to_string(i));
        return v;
    }
    const double v = one(*n, "the value");
    return {v, v, v, v};
}

Eye eyeFromName(const std::string& s) {
    if (s == "left") return Eye::Left;
    if (s == "right") return Eye::Right;
    if (s == "both") return Eye::Both;
    return Eye::Mono;
}
const char* eyeName(Eye e) {
    switch (e) {
    case Eye::Left: return "left";
    case Eye::Right: return "right";
    case Eye::Both: return "both";
    default: return "mono";
    }
}
StereoMode stereoFromName(const std::string& s) {
    if (s == "passive") return StereoMode::Passive;
    if (s == "side_by_side") return StereoMode::SideBySide;
    if (s == "quad_buffer") return StereoMode::QuadBuffer;
    return StereoMode::None;
}
const char* stereoName(StereoMode m) {
    switch (m) {
    case StereoMode::Passive: return "passive";
    case StereoMode::SideBySide: return "side_by_side";
    case StereoMode::QuadBuffer: return "quad_buffer";
    default: return "none";
    }
}

// Options shared by [grid] and [[screen]] (colour correction, output).
void readScreenCommon(Reader& r, ScreenConfig& s) {
    s.blendGamma = edgeNumbers(r, "blend_gamma", s.blendGamma);
    s.gamma = r.number("gamma", s.gamma);
    s.brightness = r.number("brightness", s.brightness);
    s.fullscreen = r.boolean("fullscreen", s.fullscreen);
}

bool eyesMeet(Eye a, Eye b) {
    if (a == Eye::Mono || b == Eye::Mono || a == Eye::Both || b == Eye::Both) return true;
    return a == b;
}

// The part `in` of screen s is inside one of s's blending ramps.
bool blended(const ScreenConfig& s, const PixelRect& in) {
    const PixelRect& v = s.viewport;
    return (s.blend[0] > 0 && in.x + in.width <= v.x + s.blend[0]) ||
           (s.blend[1] > 0 && in.x >= v.x + v.width - s.blend[1]) ||
           (s.blend[2] > 0 && in.y + in.height <= v.y + s.blend[2]) ||
           (s.blend[3] > 0 && in.y >= v.y + v.height - s.blend[3]);
}

// Three corners that span a rectangle; fails at `node` otherwise.
void checkRectangle(Reader& r, const toml::node* node, Float3 ll, Float3 lr, Float3 ul, const std::string& what) {
    auto sub = [](Float3 a, Float3 b) { return Float3{a.x - b.x, a.y - b.y, a.z - b.z}; };
    auto dot = [](Float3 a, Float3 b) { return double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z; };
    const Float3 across = sub(lr, ll), up = sub(ul, ll);
    const double la = std::sqrt(dot(across, across)), lu = std::sqrt(dot(up, up));
    if (la < 1e-6 || lu < 1e-6) r.fail(node, what + " corners must span a rectangle");
    if (std::fabs(dot(across, up)) > 1e-3 * la * lu)
        r.fail(node, "lower_left->lower_right and lower_left->upper_left must be at right angles");
}

// [[node]] tables: which display node drives which columns and rows of a [grid] (inclusive
// ranges; both eyes' screens of a passive-stereo grid). Every grid screen on exactly one node.
void readNodeRegions(Reader& top, const std::filesystem::path& file, WallConfig& w, int cols, int rows) {
    if (!top.has("node")) return;
    if (cols == 0) top.fail(top.find("node"), "[[node]] regions are for a [grid]; with [[screen]] give node = \"NAME\" on each screen");
    std::vector<int> owner(size_t(cols) * rows, -1);  // region index per cell
    std::vector<std::string> names;
    toml_reader::forEachTable(top, file, wall_keys::kNode, [&](Reader& r, const toml::table&) {
        const std::string name = r.string("name", "", true);
        if (!validNodeName(name)) r.fail(r.find("name"), "key 'name': '" + name + "' is not a node name (1 to 32 letters, digits, '-' or '_')");
        if (std::find(names.begin(), names.end(), name) != names.end())
            r.fail(r.find("name"), "key 'name': node '" + name + "' has a region already (one [[node]] per node)");
        const std::array<int, 2> c = intArray<2>(r, "columns", {0, cols - 1});
        const std::array<int, 2> rr = intArray<2>(r, "rows", {0, rows - 1});
        if (c[0] > c[1] || c[1] >= cols)
            r.fail(r.find("columns"), "key 'columns': [" + std::to_string(c[0]) + ", " + std::to_string(c[1]) +
                                          "] is not a first and last column of the grid's 0.." + std::to_string(cols - 1));
        if (rr[0] > rr[1] || rr[1] >= rows)
            r.fail(r.find("rows"), "key 'rows': [" + std::to_string(rr[0]) + ", " + std::to_string(rr[1]) +
                                       "] is not a first and last row of the grid's 0.." + std::to_string(rows - 1));
        for (int y = rr[0]; y <= rr[1]; ++y)
            for (int x = c[0]; x <= c[1]; ++x) {
                int& o = owner[size_t(y) * cols + x];
                if (o >= 0)
                    r.fail(r.find("columns") ? r.find("columns") : r.find("rows"),
                           "screen c" + std::to_string(x) + "r" + std::to_string(y) + " is in the region of node '" + names[size_t(o)] + "' too");
                o = int(names.size());
            }
        names.push_back(name);
    });
    for (int y = 0; y < rows; ++y)
        for (int x = 0; x < cols; ++x)
            if (owner[size_t(y) * cols + x] < 0)
                top.fail(top.find("node"), "[[node]]: screen c" + std::to_string(x) + "r" + std::to_string(y) +
                                               " is in no node's region (every screen needs a node)");
    // Grid screens are made row-major per eye.
    for (size_t i = 0; i < w.screens.size(); ++i) {
        const size_t cell = i % (size_t(cols) * rows);
        w.screens[i].node = names[size_t(owner[cell])];
    }
}

// What the sections say about each other while the file is read: the [wall] nodes a [grid]
// checks its size against, and per screen the node its layout messages point at.
struct WallParse {
    WallParse(const std::filesystem::path& f, WallConfig& wall) : file(f), w(wall) {}
    const std::filesystem::path& file;
    WallConfig& w;
    const toml::node* widthNode = nullptr;
    const toml::node* heightNode = nullptr;
    bool stereoCorners = false;
    Eye defaultEye = Eye::Mono;
    std::vector<const toml::node*> viewportNodes;  // per screen, for messages about the layout
    int gridColumns = 0, gridRows = 0;
};

Reader readWall(Reader& top, WallParse& p) {
    const toml::table* wallT = toml_reader::subTable(top, "wall");
    if (!wallT) top.fail(nullptr, "missing required table [wall]");
    WallConfig& w = p.w;
    Reader wr(p.file, *wallT, "[wall]: ", wall_keys::kWall);
    w.name = wr.string("name", w.name);
    p.widthNode = wr.find("width");
    p.heightNode = wr.find("height");
    w.width = wr.integer("width", 0);
    w.height = wr.integer("height", 0);
    w.vsync = wr.boolean("vsync", w.vsync);
    if (wr.has("reproject")) w.reproject = wr.choice("reproject", "off") == "on";
    w.reprojectDebug = wr.boolean("reproject_debug", w.reprojectDebug);
    w.refreshHz = wr.number("refresh_hz", w.refreshHz);
    w.swapGroup = wr.integer("swap_group", 0);
    w.swapBarrier = wr.integer("swap_barrier", 0);
    if (w.swapBarrier > 0 && w.swapGroup == 0) wr.fail(wr.find("swap_barrier"), "key 'swap_barrier': needs swap_group (a barrier binds a swap group)");
    wr.finish();
    return wr;
}

void readStereo(Reader& top, WallParse& p) {
    auto r = toml_reader::sectionReader(top, p.file, wall_keys::kStereo);
    if (!r) return;
    p.stereoCorners = r->has("lower_left") && r->has("lower_right") && r->has("upper_left");
    StereoConfig& st = p.w.stereo;
    st.mode = stereoFromName(r->choice("mode", "none"));
    toml_reader::readFields<StereoConfig>(*r, st,
                                          {{"eye_separation", &StereoConfig::eyeSeparation}, {"viewer", &StereoConfig::viewer},
                                           {"lower_left", &StereoConfig::lowerLeft}, {"lower_right", &StereoConfig::lowerRight},
                                           {"upper_left", &StereoConfig::upperLeft}});
    checkRectangle(*r, r->find("upper_left"), st.lowerLeft, st.lowerRight, st.upperLeft, "the wall's");
    r->finish();
}

void readTrackingSection(Reader& top, WallParse& p) {
    const toml::table* t = toml_reader::subTable(top, "tracking");
    if (!t) return;
    Reader r(p.file, *t, "[tracking]: ", wall_keys::kTracking);
    readTracking(r, p.w.tracking);
    // The frusta follow from where the head is relative to the physical screens.
    if (!p.stereoCorners)
        top.fail(t, "[tracking]: a tracked wall needs its physical corners: lower_left, lower_right and upper_left in [stereo] "
                    "(with mode = \"none\" for a mono wall)");
}

// [grid]'s bezels in pixels (left, right, top, bottom), given in pixels or in millimetres of a
// screen of screen_mm; `bezelNode` is where messages about them point.
std::array<int, 4> readBezel(Reader& r, int sw, int sh, const toml::node*& bezelNode) {
    std::array<int, 4> bezel{};  // left, right, top, bottom
    if (r.has("bezel") && r.has("bezel_mm")) r.fail(r.find("bezel_mm"), "give either 'bezel' (pixels) or 'bezel_mm'");
    bezel = intArray<4>(r, "bezel", bezel);
    bezelNode = r.find("bezel");
    if (r.has("bezel_mm")) {
        bezelNode = r.find("bezel_mm");
        const std::array<double, 4> mm = edgeNumbers(r, "bezel_mm", {0, 0, 0, 0});
        if (!r.has("screen_mm")) r.fail(bezelNode, "key 'bezel_mm' needs 'screen_mm' = [width, height], the visible area in millimetres");
        const std::array<int, 2> smm = intArray<2>(r, "screen_mm", {0, 0});
        for (int i = 0; i < 4; ++i) bezel[i] = int(std::lround(mm[i] * (i < 2 ? double(sw) / smm[0] : double(sh) / smm[1])));
    } else if (r.has("screen_mm")) {
        intArray<2>(r, "screen_mm", {0, 0});
    }
    if (bezel[0] + bezel[1] >= sw)
        r.fail(bezelNode, "the bezel (" + std::to_string(bezel[0] + bezel[1]) + " pixels left and right) is wider than the screen (" +
                              std::to_string(sw) + ")");
    if (bezel[2] + bezel[3] >= sh)
        r.fail(bezelNode, "the bezel (" + std::to_string(bezel[2] + bezel[3]) + " pixels top and bottom) is taller than the screen (" +
                              std::to_string(sh) + ")");
    return bezel;
}

void readGrid(Reader& top, Reader& wr, WallParse& p) {
    const toml::table* t = toml_reader::subTable(top, "grid");
    WallConfig& w = p.w;
    Reader r(p.file, *t, "[grid]: ", wall_keys::kGrid);
    const int cols = r.integer("columns", 1), rows = r.integer("rows", 1);
    p.gridColumns = cols;
    p.gridRows = rows;
    const int sw = r.integer("screen_width", 0), sh = r.integer("screen_height", 0);
    if (!r.has("screen_width")) r.fail(nullptr, "missing required key 'screen_width'");
    if (!r.has("screen_height")) r.fail(nullptr, "missing required key 'screen_height'");
    const toml::node* bezelNode = nullptr;
    const std::array<int, 4> bezel = readBezel(r, sw, sh, bezelNode);
    const int overlap = r.integer("overlap", 0);
    if (overlap > 0 && (bezel != std::array<int, 4>{}))
        r.fail(r.find("overlap"), "overlapping projectors have no bezels: give 'overlap' or a bezel, not both");
    if (2 * overlap >= std::min(sw, sh)) r.fail(r.find("overlap"), "key 'overlap': must be less than half the screen");
    ScreenConfig base;
    readScreenCommon(r, base);
    const int firstMonitor = r.integer("first_monitor", 0);
    r.finish();
    // Bezels between screens are hidden wall pixels; the outer ones are not rendered.
    const int stepX = sw + bezel[0] + bezel[1] - overlap, stepY = sh + bezel[2] + bezel[3] - overlap;
    const int total = cols * rows;
    const bool pairs = w.stereo.mode == StereoMode::Passive;
    for (int eye = 0; eye < (pairs ? 2 : 1); ++eye)
        for (int row = 0; row < rows; ++row)
            for (int col = 0; col < cols; ++col) {
                ScreenConfig s = base;
                s.name = "c" + std::to_string(col) + "r" + std::to_string(row) + (pairs ? (eye ? "R" : "L") : "");
                s.viewport = {col * stepX, row * stepY, sw, sh};
                s.outputWidth = sw;
                s.outputHeight = sh;
                if (overlap > 0) s.blend = {col > 0 ? overlap : 0, col + 1 < cols ? overlap : 0, row > 0 ? overlap : 0,
                                            row + 1 < rows ? overlap : 0};
                s.eye = pairs ? (eye ? Eye::Right : Eye::Left) : p.defaultEye;
                s.monitor = firstMonitor + eye * total + row * cols + col;
                s.window = {eye * cols * sw + col * sw, row * sh};
                s.line = int(t->source().begin.line);
                w.screens.push_back(s);
                p.viewportNodes.push_back(t);
            }
    const int gw = cols * stepX - (bezel[0] + bezel[1]) + overlap, gh = rows * stepY - (bezel[2] + bezel[3]) + overlap;
    if (w.width && w.width != gw) wr.fail(p.widthNode, "key 'width': " + std::to_string(w.width) + " differs from the grid's " + std::to_string(gw));
    if (w.height && w.height != gh) wr.fail(p.heightNode, "key 'height': " + std::to_string(w.height) + " differs from the grid's " + std::to_string(gh));
    w.width = gw;
    w.height = gh;
}

// One [[screen]] of an explicit list.
void readScreen(Reader& r, const toml::table& t, WallParse& p) {
    WallConfig& w = p.w;
    ScreenConfig s;
    s.line = int(t.source().begin.line);
    s.name = r.string("name", "screen" + std::to_string(w.screens.size() + 1));
    const std::array<int, 4> vp = intArray<4>(r, "viewport", {}, true);
    const toml::node* vpNode = r.find("viewport");
    s.viewport = {vp[0], vp[1], vp[2], vp[3]};
    if (vp[2] < 1 || vp[3] < 1) r.fail(vpNode, "key 'viewport': width and height must be at least 1");
    if (vp[0] + vp[2] > w.width || vp[1] + vp[3] > w.height)
        r.fail(vpNode, "key 'viewport': [" + std::to_string(vp[0]) + ", " + std::to_string(vp[1]) + ", " + std::to_string(vp[2]) +
                           ", " + std::to_string(vp[3]) + "] reaches outside the " + std::to_string(w.width) + "x" +
                           std::to_string(w.height) + " wall");
    const std::array<int, 2> res = intArray<2>(r, "resolution", {vp[2], vp[3]});
    s.outputWidth = res[0];
    s.outputHeight = res[1];
    s.blend = intArray<4>(r, "blend", s.blend);
    if (s.blend[0] + s.blend[1] > vp[2] || s.blend[2] + s.blend[3] > vp[3])
        r.fail(r.find("blend"), "key 'blend': the ramps are wider than the screen's viewport");
    readScreenCommon(r, s);
    s.eye = eyeFromName(r.choice("eye", eyeName(p.defaultEye)));
    s.monitor = r.integer("monitor", 0);
    s.window = intArray<2>(r, "window", s.window);
    const std::string shader = r.string("shader", "");
    if (!shader.empty()) {
        s.fragmentShader = std::filesystem::absolute(p.file.parent_path() / shader).lexically_normal();
        if (!std::filesystem::exists(s.fragmentShader))
            r.fail(r.find("shader"), "key 'shader': no such file " + s.fragmentShader.string());
    }
    const int corners = r.has("lower_left") + r.has("lower_right") + r.has("upper_left");
    if (corners > 0 && corners < 3)
        r.fail(r.find(r.has("lower_left") ? "lower_left" : r.has("lower_right") ? "lower_right" : "upper_left"),
               "give all three physical corners (lower_left, lower_right, upper_left; metres) or none");
    if (corners == 3) {
        s.hasCorners = true;
        s.lowerLeft = r.vec3("lower_left", {});
        s.lowerRight = r.vec3("lower_right", {});
        s.upperLeft = r.vec3("upper_left", {});
        checkRectangle(r, r.find("upper_left"), s.lowerLeft, s.lowerRight, s.upperLeft, "the screen's");
    }
    if (r.has("node")) {
        s.node = r.string("node", "");
        if (!validNodeName(s.node))
            r.fail(r.find("node"), "key 'node': '" + s.node + "' is not a node name (1 to 32 letters, digits, '-' or '_')");
    }
    for (size_t i = 0; i < w.screens.size(); ++i)
        if (w.screens[i].name == s.name) r.fail(r.find("name"), "key 'name': '" + s.name + "' is used by another screen");
    w.screens.push_back(s);
    p.viewportNodes.push_back(vpNode);
}

void readHeadless(Reader& top, WallConfig& w, const std::filesystem::path& file) {
    auto r = toml_reader::sectionReader(top, file, wall_keys::kHeadless);
    if (!r) return;
    w.writeEvery = r->integer("write_every", w.writeEvery);
    w.video = r->string("video", "");
    // The name goes to the ffmpeg program on a shell command line: a plain file name only.
    for (char ch : w.video)
        if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' || ch == '_'))
            r->fail(r->find("video"), "key 'video': a plain file name of letters, digits, '.', '-' and '_' (it goes to ffmpeg)");
    if (w.video.starts_with("-") || w.video.starts_with("."))
        r->fail(r->find("video"), "key 'video': a plain file name of letters, digits, '.', '-' and '_' (it goes to ffmpeg)");
    r->finish();
}

// [warp]: the calibration file and which screen each of its buffers drives (the file itself is
// read by checkWall and the wall, not here: a config loads without it).
void readWarp(Reader& top, WallConfig& w, const std::filesystem::path& file) {
    auto r = toml_reader::sectionReader(top, file, wall_keys::kWarp);
    if (!r) return;
    WarpConfig warp;
    const std::string mpcdi = r->string("mpcdi", "", true);
    if (mpcdi.empty()) r->fail(r->find("mpcdi"), "key 'mpcdi': an empty path");
    warp.mpcdi = std::filesystem::absolute(file.parent_path() / mpcdi).lexically_normal();
    warp.mode = r->choice("mode", "direct", {"direct", "post"}) == "post" ? WarpMode::Post : WarpMode::Direct;
    warp.regionYFromBottom = r->choice("region_y", "top", {"top", "bottom"}) == "bottom";
    if (r->has("eyepoint")) warp.eyepoint = r->vec3("eyepoint", {});
    warp.frustumDistance = r->number("frustum_distance", warp.frustumDistance, 0.01, 1e6);
    const toml::node* buffers = r->find("buffers");
    if (!buffers) r->fail(nullptr, "missing required key 'buffers' (each MPCDI buffer id to its screen)");
    const toml::table* t = buffers->as_table();
    if (!t) r->fail(buffers, "key 'buffers': a table of buffer id = \"screen name\", e.g. { proj0 = \"left\" }");
    if (t->empty()) r->fail(buffers, "key 'buffers': no buffer is mapped");
    std::set<std::string> screens;
    for (const auto& [id, node] : *t) {
        const auto* name = node.as_string();
        const std::string key(id.str());
        if (!name) r->fail(&node, "key 'buffers': buffer '" + key + "' must name a screen (a string)");
        const auto it = std::find_if(w.screens.begin(), w.screens.end(), [&](const ScreenConfig& sc) { return sc.name == name->get(); });
        if (it == w.screens.end()) r->fail(&node, "key 'buffers': buffer '" + key + "' names screen '" + name->get() + "', which the wall has not");
        if (!screens.insert(name->get()).second)
            r->fail(&node, "key 'buffers': screen '" + name->get() + "' is driven by two buffers");
        warp.buffers.emplace_back(key, name->get());
    }
    r->finish();
    w.warp = std::move(warp);
}

// The layout as a whole: corners and nodes on every screen or none, eyes that fit the stereo
// mode, overlaps only where blend ramps cover them, at most kMaxDisplayNodes nodes.
void checkLayout(const WallConfig& w, const toml::table& root, const WallParse& p) {
    bool left = false, right = false;
    for (size_t i = 0; i < w.screens.size(); ++i) {
        const ScreenConfig& s = w.screens[i];
        auto failAt = [&](const std::string& what) {
            throw InputError(toml_reader::where(p.file, p.viewportNodes[i]->source()) + ": screen '" + s.name + "': " + what);
        };
        left |= s.eye == Eye::Left;
        right |= s.eye == Eye::Right;
        if (s.hasCorners != w.screens.front().hasCorners)
            failAt("give the physical corners (lower_left, lower_right, upper_left) on every screen or on none");
        if (s.node.empty() != w.screens.front().node.empty())
            failAt(s.node.empty() ? "key 'node': missing; screen '" + w.screens.front().name + "' is on node '" +
                                        w.screens.front().node + "', so every screen needs a node"
                                  : "key 'node': screen '" + w.screens.front().name +
                                        "' has no node, so none may have one (give node = \"...\" on every screen or on none)");
        switch (w.stereo.mode) {
        case StereoMode::None:
            if (s.eye != Eye::Mono) failAt("key 'eye': '" + std::string(eyeName(s.eye)) + "' needs a [stereo] mode");
            break;
        case StereoMode::Passive:
            if (s.eye != Eye::Left && s.eye != Eye::Right) failAt("key 'eye': passive stereo needs 'left' or 'right' on every screen");
            break;
        default:
            if (s.eye != Eye::Both) failAt("key 'eye': side-by-side and quad-buffered stereo show 'both' eyes on every screen");
        }
        for (size_t j = 0; j < i; ++j) {
            const ScreenConfig& o = w.screens[j];
            if (!eyesMeet(s.eye, o.eye)) continue;
            const PixelRect &a = s.viewport, &b = o.viewport;
            const int x0 = std::max(a.x, b.x), x1 = std::min(a.x + a.width, b.x + b.width);
            const int y0 = std::max(a.y, b.y), y1 = std::min(a.y + a.height, b.y + b.height);
            if (x0 >= x1 || y0 >= y1) continue;
            const PixelRect in{x0, y0, x1 - x0, y1 - y0};
            if (!blended(s, in) || !blended(o, in))
                failAt("key 'viewport': overlaps screen '" + o.name + "' by " + std::to_string(in.width) + "x" +
                       std::to_string(in.height) + " wall pixels that no blend ramp of both screens covers");
        }
    }
    if (w.stereo.mode == StereoMode::Passive && (!left || !right))
        throw InputError(toml_reader::where(p.file, root.source()) + ": [stereo]: passive stereo needs screens for both eyes");
    if (w.nodes().size() > kMaxDisplayNodes)
        throw InputError(toml_reader::where(p.file, root.source()) + ": the screens name " + std::to_string(w.nodes().size()) +
                         " display nodes, at most " + std::to_string(kMaxDisplayNodes) + " are supported");
}

WallConfig parse(const toml::table& root, const std::filesystem::path& file) {
    WallConfig w;
    w.file = file;
    WallParse p(file, w);
    Reader top(file, root, "", wall_keys::kTop);
    Reader wr = readWall(top, p);
    readStereo(top, p);
    readTrackingSection(top, p);
    if (auto r = toml_reader::sectionReader(top, file, wall_keys::kNavigation)) readNavigation(*r, w.navigation);
    p.defaultEye = w.stereo.mode == StereoMode::SideBySide || w.stereo.mode == StereoMode::QuadBuffer ? Eye::Both : Eye::Mono;

    const bool hasGrid = top.has("grid"), hasScreens = top.has("screen");
    if (hasGrid && hasScreens) top.fail(top.find("screen"), "give either [grid] or [[screen]], not both");
    if (!hasGrid && !hasScreens) top.fail(nullptr, "a wall needs a [grid] or a list of [[screen]]");
    if (hasGrid) {
        readGrid(top, wr, p);
    } else {
        if (!w.width) wr.fail(nullptr, "missing required key 'width' (the wall image's size in pixels)");
        if (!w.height) wr.fail(nullptr, "missing required key 'height' (the wall image's size in pixels)");
        toml_reader::forEachTable(top, file, wall_keys::kScreen, [&](Reader& r, const toml::table& t) { readScreen(r, t, p); });
    }
    readNodeRegions(top, file, w, p.gridColumns, p.gridRows);
    readHeadless(top, w, file);
    readWarp(top, w, file);
    top.finish();
    checkLayout(w, root, p);
    return w;
}

}  // namespace

namespace {
bool eq3(Float3 a, Float3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
}  // namespace

bool ScreenConfig::operator==(const ScreenConfig& o) const {
    return name == o.name && viewport == o.viewport && outputWidth == o.outputWidth && outputHeight == o.outputHeight &&
           blend == o.blend && blendGamma == o.blendGamma && gamma == o.gamma && brightness == o.brightness &&
           eye == o.eye && monitor == o.monitor && window == o.window && fullscreen == o.fullscreen &&
           fragmentShader == o.fragmentShader && hasCorners == o.hasCorners && node == o.node &&
           (!hasCorners || (eq3(lowerLeft, o.lowerLeft) && eq3(lowerRight, o.lowerRight) && eq3(upperLeft, o.upperLeft)));
}

bool StereoConfig::operator==(const StereoConfig& o) const {
    auto eq = [](Float3 a, Float3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
    return mode == o.mode && eyeSeparation == o.eyeSeparation && eq(viewer, o.viewer) && eq(lowerLeft, o.lowerLeft) &&
           eq(lowerRight, o.lowerRight) && eq(upperLeft, o.upperLeft);
}

bool WallConfig::operator==(const WallConfig& o) const {
    return name == o.name && width == o.width && height == o.height && vsync == o.vsync && swapGroup == o.swapGroup &&
           swapBarrier == o.swapBarrier && reproject == o.reproject && reprojectDebug == o.reprojectDebug &&
           refreshHz == o.refreshHz && screens == o.screens &&
           stereo == o.stereo && tracking == o.tracking && writeEvery == o.writeEvery && video == o.video &&
           navigation == o.navigation && warp == o.warp;
}

WallConfig loadWallConfig(const std::filesystem::path& file) { return parse(toml_reader::parseFile(file), file); }

WallConfig parseWallConfig(const std::string& text, const std::filesystem::path& nameForMessages) {
    toml::table root;
    try {
        root = toml::parse(text, nameForMessages.string());
    } catch (const toml::parse_error& e) {
        throw InputError(toml_reader::where(nameForMessages, e.source()) + ": " + std::string(e.description()));
    }
    return parse(root, nameForMessages);
}

std::string writeWallConfig(const WallConfig& w) {
    std::ostringstream os;
    os << std::setprecision(17);
    auto quoted = [](const std::string& s) {
        std::string q = "\"";
        for (char c : s) {
            if (c == '"' || c == '\\') q += '\\';
            q += c;
        }
        return q + "\"";
    };
    auto f3 = [](Float3 v) {
        std::ostringstream o;
        o << std::setprecision(9) << "[" << v.x << ", " << v.y << ", " << v.z << "]";
        return o.str();
    };
    auto num = [](double v) {
        std::ostringstream o;
        o << std::setprecision(17) << v;
        std::string s = o.str();
        if (s.find_first_of(".eE") == std::string::npos) s += ".0";
        return s;
    };
    os << "[wall]\nname = " << quoted(w.name) << "\nwidth = " << w.width << "\nheight = " << w.height
       << "\nvsync = " << (w.vsync ? "true" : "false") << "\n";
    if (w.reproject) os << "reproject = \"" << (*w.reproject ? "on" : "off") << "\"\n";
    if (w.reprojectDebug) os << "reproject_debug = true\n";
    if (w.refreshHz != WallConfig{}.refreshHz) os << "refresh_hz = " << num(w.refreshHz) << "\n";
    if (w.swapGroup > 0) os << "swap_group = " << w.swapGroup << "\nswap_barrier = " << w.swapBarrier << "\n";
    os << "\n";
    if (w.stereo.mode != StereoMode::None || w.tracking.enabled || !(w.stereo == StereoConfig{})) {  // the viewer counts on mono walls too
        const StereoConfig& s = w.stereo;
        os << "[stereo]\nmode = \"" << stereoName(s.mode) << "\"\neye_separation = " << num(s.eyeSeparation)
           << "\nviewer = " << f3(s.viewer) << "\nlower_left = " << f3(s.lowerLeft) << "\nlower_right = " << f3(s.lowerRight)
           << "\nupper_left = " << f3(s.upperLeft) << "\n\n";
    }
    if (w.tracking.enabled) {
        const TrackingConfig& t = w.tracking;
        auto d3 = [&](const std::array<double, 3>& v) { return "[" + num(v[0]) + ", " + num(v[1]) + ", " + num(v[2]) + "]"; };
        os << "[tracking]\nsource = " << quoted(t.source);
        if (t.kind == TrackingSource::Vrpn)
            os << "\nserver = " << quoted(t.server) << "\nbuttons = " << quoted(t.buttonDevice) << "\nanalog = " << quoted(t.analogDevice);
        os << "\nhead_body = " << t.headBody << "\nflystick = " << t.flystick
           << "\nroom_scale = " << num(t.roomScale) << "\nroom_rotate = " << d3(t.roomRotate) << "\nroom_translate = "
           << d3(t.roomTranslate) << "\ntimeout_ms = " << t.timeoutMs << "\nprediction_ms = " << num(t.predictionMs) << "\n";
        if (t.filter == TrackingFilter::OneEuro)
            os << "filter = \"one_euro\"\nmin_cutoff = " << num(t.minCutoff) << "\nbeta = " << num(t.beta)
               << "\nderivative_cutoff = " << num(t.derivativeCutoff) << "\n";
        os << "button_pick = " << t.buttonPick << "\nbutton_mode = " << t.buttonMode << "\nbutton_home = " << t.buttonHome
           << "\njoystick_x = " << t.joystickX << "\njoystick_y = " << t.joystickY << "\nfly_speed = " << num(t.flySpeed)
           << "\nturn_speed = " << num(t.turnSpeed) << "\ndead_zone = " << num(t.deadZone) << "\nwand_direction = "
           << d3(t.wandDirection) << "\nwand_ray = " << (t.wandRay ? "true" : "false") << "\n\n";
    }
    if (!(w.navigation == NavigationConfig{})) os << "[navigation]\nscale = " << num(w.navigation.scale) << "\n\n";
    if (w.warp) {
        os << "[warp]\nmpcdi = " << quoted(w.warp->mpcdi.string()) << "\nmode = \"" << (w.warp->mode == WarpMode::Post ? "post" : "direct")
           << "\"\nregion_y = \"" << (w.warp->regionYFromBottom ? "bottom" : "top") << "\"\nfrustum_distance = "
           << num(w.warp->frustumDistance);
        if (w.warp->eyepoint) os << "\neyepoint = " << f3(*w.warp->eyepoint);
        os << "\nbuffers = { ";
        for (size_t i = 0; i < w.warp->buffers.size(); ++i)
            os << (i ? ", " : "") << quoted(w.warp->buffers[i].first) << " = " << quoted(w.warp->buffers[i].second);
        os << " }\n\n";
    }
    os << "[headless]\nwrite_every = " << w.writeEvery << "\nvideo = " << quoted(w.video) << "\n";
    for (const ScreenConfig& s : w.screens) {
        os << "\n[[screen]]\nname = " << quoted(s.name) << "\nviewport = [" << s.viewport.x << ", " << s.viewport.y << ", "
           << s.viewport.width << ", " << s.viewport.height << "]\nresolution = [" << s.outputWidth << ", " << s.outputHeight
           << "]\nblend = [" << s.blend[0] << ", " << s.blend[1] << ", " << s.blend[2] << ", " << s.blend[3]
           << "]\nblend_gamma = [" << num(s.blendGamma[0]) << ", " << num(s.blendGamma[1]) << ", " << num(s.blendGamma[2]) << ", "
           << num(s.blendGamma[3]) << "]\ngamma = " << num(s.gamma) << "\nbrightness = " << num(s.brightness) << "\neye = \""
           << eyeName(s.eye) << "\"\nmonitor = " << s.monitor << "\nwindow = [" << s.window[0] << ", " << s.window[1]
           << "]\nfullscreen = " << (s.fullscreen ? "true" : "false") << "\n";
        if (!s.fragmentShader.empty()) os << "shader = " << quoted(s.fragmentShader.string()) << "\n";
        if (!s.node.empty()) os << "node = " << quoted(s.node) << "\n";
        if (s.hasCorners)
            os << "lower_left = " << f3(s.lowerLeft) << "\nlower_right = " << f3(s.lowerRight) << "\nupper_left = " << f3(s.upperLeft) << "\n";
    }
    return os.str();
}

std::vector<std::string> WallConfig::nodes() const {
    std::vector<std::string> out;
    for (const ScreenConfig& s : screens)
        if (!s.node.empty() && std::find(out.begin(), out.end(), s.node) == out.end()) out.push_back(s.node);
    return out;
}

bool validNodeName(const std::string& name) {
    if (name.empty() || name.size() > 32) return false;
    return std::all_of(name.begin(), name.end(),
                       [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_'; });
}

WallConfig nodeWall(const WallConfig& wall, const std::string& node) {
    WallConfig w = wall;
    w.screens.clear();
    for (const ScreenConfig& s : wall.screens)
        if (s.node == node) w.screens.push_back(s);
    if (w.screens.empty()) {
        std::string known;
        for (const std::string& n : wall.nodes()) known += (known.empty() ? "" : ", ") + n;
        throw std::invalid_argument("the wall '" + wall.name + "' has no display node '" + node + "' (its nodes: " +
                                    (known.empty() ? std::string("none") : known) + ")");
    }
    return w;
}

WallConfig singleScreenWall(int width, int height) {
    WallConfig w;
    w.name = "desktop";
    w.width = width;
    w.height = height;
    ScreenConfig s;
    s.name = "main";
    s.viewport = {0, 0, width, height};
    s.outputWidth = width;
    s.outputHeight = height;
    s.window = {0, 0};
    w.screens.push_back(s);
    return w;
}

}  // namespace rtwall
