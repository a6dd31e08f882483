// The MPCDI reader (rtwall/mpcdi.h): libzip for the archive, pugixml for mpcdi.xml, libpng's
// simplified API for the blend maps and a PFM parser of our own (a three-line header). Nothing
// is allocated for more than what was read: archive entries grow as they decompress, PFM
// samples are checked against the bytes present, PNG sizes against their region first.
#include <rtwall/input_error.h>
#include <rtwall/mpcdi.h>

#include <png.h>
#include <pugixml.hpp>
#include <zip.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>

namespace rtwall {

namespace {

// Control bytes of names and values from the file shown as \xNN: an error stays one line.
std::string printable(std::string_view s) {
    std::string out;
    for (char c : s) {
        const auto u = static_cast<unsigned char>(c);
        if (u < 0x20 || u == 0x7f) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", u);
            out += hex;
        } else {
            out += c;
        }
    }
    return out;
}
// A name or value from the file, quoted, at most 64 bytes of it.
std::string quote(std::string_view s) {
    return "'" + printable(s.substr(0, 64)) + (s.size() > 64 ? "...'" : "'");
}

std::string shortNumber(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", v);
    return text;
}

// An archive entry's name after the file's, for messages about what is inside it.
std::string within(const std::string& name, std::string_view entry) {
    return name + ": " + printable(entry.substr(0, 64)) + (entry.size() > 64 ? "..." : "");
}

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw InputError(printable(name + ": " + what)); }

bool sameName(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
           });
}

// Child elements and attributes whatever their case (writers differ: Xresolution, xResolution).
pugi::xml_node child(pugi::xml_node n, std::string_view name) {
    for (pugi::xml_node c : n.children())
        if (c.type() == pugi::node_element && sameName(c.name(), name)) return c;
    return {};
}
std::vector<pugi::xml_node> children(pugi::xml_node n, std::string_view name) {
    std::vector<pugi::xml_node> out;
    for (pugi::xml_node c : n.children())
        if (c.type() == pugi::node_element && sameName(c.name(), name)) out.push_back(c);
    return out;
}
pugi::xml_attribute attribute(pugi::xml_node n, std::string_view name) {
    for (pugi::xml_attribute a : n.attributes())
        if (sameName(a.name(), name)) return a;
    return {};
}
std::string trimmed(const char* text) {
    std::string_view s(text);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return std::string(s);
}
std::string lowered(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

double number(const std::string& text, const std::string& name, const std::string& what) {
    double v = 0;
    const char* end = text.data() + text.size();
    const auto [p, ec] = std::from_chars(text.data(), end, v);
    if (text.empty() || ec != std::errc() || p != end) fail(name, what + " is " + quote(text) + ", not a number");
    if (!std::isfinite(v)) fail(name, what + " is " + quote(text) + ", not a finite number");
    return v;
}
// An attribute or child element's text, as a number; `fallback` when neither is there.
std::optional<double> optionalNumber(pugi::xml_node n, std::string_view key, const std::string& name, const std::string& where) {
    if (pugi::xml_attribute a = attribute(n, key)) return number(trimmed(a.value()), name, where + " " + std::string(key));
    if (pugi::xml_node c = child(n, key)) return number(trimmed(c.text().get()), name, where + " <" + std::string(key) + ">");
    return std::nullopt;
}
int resolution(pugi::xml_node n, std::string_view key, const std::string& name, const std::string& where) {
    const std::optional<double> v = optionalNumber(n, key, name, where);
    if (!v) fail(name, where + " has no " + std::string(key));
    if (*v != std::floor(*v) || *v < 1 || *v > kMaxMpcdiSide)
        fail(name, where + " " + std::string(key) + " is " + shortNumber(*v) + " (a whole number of pixels, 1 to " +
                       std::to_string(kMaxMpcdiSide) + ")");
    return int(*v);
}

std::string describe(const std::string& kind, const std::string& id) { return kind + " " + quote(id); }

double metresPer(const std::string& unit, const std::string& name, const std::string& where) {
    static const std::map<std::string, double> units{{"", 1.0},      {"m", 1.0},    {"dm", 0.1},     {"cm", 0.01},
                                                     {"mm", 0.001},  {"in", 0.0254}, {"ft", 0.3048}, {"yd", 0.9144}};
    const auto it = units.find(lowered(unit));
    if (it == units.end()) fail(name, where + ": geometric unit " + quote(unit) + " is none of mm, cm, dm, m, in, ft, yd");
    return it->second;
}

// ---- PFM ----------------------------------------------------------------------------------

// One header token: non-space bytes after any spaces; `at` moves past it.
std::string_view token(std::span<const uint8_t> b, size_t& at) {
    while (at < b.size() && std::isspace(b[at])) ++at;
    const size_t start = at;
    while (at < b.size() && !std::isspace(b[at]) && at - start < 32) ++at;
    return {reinterpret_cast<const char*>(b.data()) + start, at - start};
}

}  // namespace

MpcdiWarp parsePfm(std::span<const uint8_t> b, const std::string& name) {
    size_t at = 0;
    const std::string_view magic = token(b, at);
    if (magic == "Pf") fail(name, "a one-component PFM (Pf); a geometry warp has three components (PF)");
    if (magic != "PF") fail(name, "not a PFM file (it does not start with PF)");
    auto dimension = [&](const char* what) {
        const std::string_view t = token(b, at);
        int v = 0;
        const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        if (t.empty() || ec != std::errc() || p != t.data() + t.size() || v < 1 || v > kMaxMpcdiSide)
            fail(name, std::string("PFM header: ") + what + " " + quote(t) + " is not a whole number from 1 to " +
                           std::to_string(kMaxMpcdiSide));
        return v;
    };
    MpcdiWarp w;
    w.width = dimension("width");
    w.height = dimension("height");
    const std::string_view scaleText = token(b, at);
    double scale = 0;
    const auto [p, ec] = std::from_chars(scaleText.data(), scaleText.data() + scaleText.size(), scale);
    if (scaleText.empty() || ec != std::errc() || p != scaleText.data() + scaleText.size() || scale == 0 ||
        !std::isfinite(scale))
        fail(name, "PFM header: scale " + quote(scaleText) + " is not a non-zero number");
    if (at >= b.size() || !std::isspace(b[at])) fail(name, "PFM header: no samples after it");
    ++at;  // exactly one whitespace byte ends the header
    const size_t samples = size_t(w.width) * size_t(w.height);
    if (samples > kMaxMpcdiSamples)
        fail(name, "PFM header: " + std::to_string(w.width) + "x" + std::to_string(w.height) + " samples, more than " +
                       std::to_string(kMaxMpcdiSamples));
    const size_t need = samples * 12, have = b.size() - at;
    if (have != need)
        fail(name, "PFM header says " + std::to_string(w.width) + "x" + std::to_string(w.height) + " (" + std::to_string(need) +
                       " bytes of samples) but the file holds " + std::to_string(have));
    const bool little = scale < 0;
    w.samples.resize(samples);
    const uint8_t* data = b.data() + at;
    for (int row = 0; row < w.height; ++row) {  // PFM rows run bottom to top; ours top to bottom
        Float3* out = w.samples.data() + size_t(w.height - 1 - row) * size_t(w.width);
        for (int x = 0; x < w.width; ++x) {
            float c[3];
            for (int k = 0; k < 3; ++k) {
                uint8_t bytes[4];
                std::memcpy(bytes, data + ((size_t(row) * size_t(w.width) + size_t(x)) * 3 + size_t(k)) * 4, 4);
                if (!little) std::reverse(bytes, bytes + 4);
                std::memcpy(&c[k], bytes, 4);
            }
            if (std::isinf(c[0]) || std::isinf(c[1]) || std::isinf(c[2]))
                fail(name, "sample (" + std::to_string(x) + ", " + std::to_string(w.height - 1 - row) +
                               ") from the top left is infinite");
            out[x] = {c[0], c[1], c[2]};
            w.validSamples += !(std::isnan(c[0]) || std::isnan(c[1]) || std::isnan(c[2]));
        }
    }
    return w;
}

namespace {

// ---- PNG blend maps -------------------------------------------------------------------------

MpcdiMap readMap(std::span<const uint8_t> bytes, int components, int width, int height, const std::string& name) {
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&png, bytes.data(), bytes.size())) {
        const std::string why = png.message;
        png_image_free(&png);
        fail(name, "not a readable PNG (" + why + ")");
    }
    if (int(png.width) != width || int(png.height) != height) {
        const std::string size = std::to_string(png.width) + "x" + std::to_string(png.height);
        png_image_free(&png);
        fail(name, "a blend map of " + size + ", its region has " + std::to_string(width) + "x" + std::to_string(height) +
                       " pixels");
    }
    // A region may be large, and a blank map compresses a thousandfold: bounded like a warp.
    if (size_t(width) * size_t(height) * size_t(components) > kMaxMpcdiSamples) {
        png_image_free(&png);
        fail(name, "a blend map of " + std::to_string(width) + "x" + std::to_string(height) + "x" + std::to_string(components) +
                       " values, more than " + std::to_string(kMaxMpcdiSamples));
    }
    const bool wide = png.format & PNG_FORMAT_FLAG_LINEAR;
    png.format = components == 3 ? (wide ? PNG_FORMAT_LINEAR_RGB : PNG_FORMAT_RGB) : (wide ? PNG_FORMAT_LINEAR_Y : PNG_FORMAT_GRAY);
    MpcdiMap m;
    m.width = width;
    m.height = height;
    m.components = components;
    const size_t count = size_t(width) * size_t(height) * size_t(components);
    m.values.resize(count);
    bool ok = false;
    if (wide) {
        std::vector<uint16_t> raw(count);
        ok = png_image_finish_read(&png, nullptr, raw.data(), 0, nullptr);
        for (size_t i = 0; ok && i < count; ++i) m.values[i] = float(raw[i]) / 65535.0f;
    } else {
        std::vector<uint8_t> raw(count);
        ok = png_image_finish_read(&png, nullptr, raw.data(), 0, nullptr);
        for (size_t i = 0; ok && i < count; ++i) m.values[i] = float(raw[i]) / 255.0f;
    }
    if (!ok) {
        const std::string why = png.message;
        png_image_free(&png);
        fail(name, "a damaged PNG (" + why + ")");
    }
    return m;
}

// ---- the archive ----------------------------------------------------------------------------

struct ZipDeleter {
    void operator()(zip_t* z) const { zip_discard(z); }
};
struct ZipFileDeleter {
    void operator()(zip_file_t* f) const { zip_fclose(f); }
};

class Archive {
public:
    Archive(std::span<const uint8_t> bytes, const std::string& name) : name_(name) {
        zip_error_t error;
        zip_error_init(&error);
        zip_source_t* source = zip_source_buffer_create(bytes.data(), bytes.size(), 0, &error);
        if (!source) fail(name_, std::string("cannot read it as a zip archive: ") + zip_error_strerror(&error));
        zip_t* z = zip_open_from_source(source, ZIP_RDONLY | ZIP_CHECKCONS, &error);
        if (!z) {
            zip_source_free(source);
            const std::string why = zip_error_strerror(&error);
            zip_error_fini(&error);
            fail(name_, "not a readable zip archive (" + why + ")");
        }
        zip_error_fini(&error);
        zip_.reset(z);
    }

    // The entry's bytes: by its exact name, else by its name without folders; nullopt when absent.
    std::optional<std::vector<uint8_t>> entry(const std::string& wanted) const {
        zip_int64_t index = zip_name_locate(zip_.get(), wanted.c_str(), 0);
        if (index < 0) index = zip_name_locate(zip_.get(), wanted.c_str(), ZIP_FL_NODIR);
        if (index < 0) return std::nullopt;
        std::unique_ptr<zip_file_t, ZipFileDeleter> f(zip_fopen_index(zip_.get(), zip_uint64_t(index), 0));
        if (!f) fail(name_, "entry " + quote(wanted) + " cannot be opened (" + zip_strerror(zip_.get()) + ")");
        std::vector<uint8_t> out;
        for (;;) {  // grows with what decompresses, never with what a header claims
            const size_t at = out.size();
            if (at >= kMaxMpcdiEntry) fail(name_, "entry " + quote(wanted) + " is larger than " + std::to_string(kMaxMpcdiEntry >> 20) + " MiB");
            out.resize(at + std::min<size_t>(size_t(1) << 20, kMaxMpcdiEntry - at));
            const zip_int64_t n = zip_fread(f.get(), out.data() + at, out.size() - at);
            if (n < 0) fail(name_, "entry " + quote(wanted) + " is damaged (" + zip_file_strerror(f.get()) + ")");
            out.resize(at + size_t(n));
            if (n == 0) break;
        }
        return out;
    }

private:
    std::string name_;
    std::unique_ptr<zip_t, ZipDeleter> zip_;
};

// ---- mpcdi.xml ------------------------------------------------------------------------------

// A fileset's file element's path: its <path>, or its own text (some writers).
std::string pathOf(pugi::xml_node file) {
    if (pugi::xml_node p = child(file, "path")) return trimmed(p.text().get());
    return trimmed(file.text().get());
}

MpcdiMap blendMap(pugi::xml_node map, const MpcdiRegion& region, const MpcdiEntries& entries, const std::string& name,
                  const char* kind, double defaultGamma) {
    const std::string where = describe("region", region.id) + " " + kind;
    const std::string path = pathOf(map);
    if (path.empty()) fail(name, where + " names no file");
    int components = 1;
    if (const std::optional<double> c = optionalNumber(map, "componentDepth", name, where)) {
        if (*c != 1 && *c != 3) fail(name, where + " componentDepth is " + shortNumber(*c) + " (1 or 3)");
        components = int(*c);
    }
    if (const std::optional<double> d = optionalNumber(map, "bitDepth", name, where); d && *d != 8 && *d != 16)
        fail(name, where + " bitDepth is " + shortNumber(*d) + " (8 or 16)");
    const std::optional<std::vector<uint8_t>> bytes = entries(path);
    if (!bytes) fail(name, where + " " + quote(path) + " is not in the archive");
    MpcdiMap m = readMap(*bytes, components, region.xResolution, region.yResolution, within(name, path));
    if (const std::optional<double> g = optionalNumber(map, "gammaEmbedded", name, where)) {
        if (*g <= 0 || *g > 10) fail(name, where + " gammaEmbedded is " + shortNumber(*g) + " (above 0, at most 10)");
        m.gammaEmbedded = *g;
    } else {
        m.gammaEmbedded = defaultGamma;
    }
    return m;
}

}  // namespace

const char* mpcdiProfileName(MpcdiProfile p) {
    switch (p) {
    case MpcdiProfile::Flat2d: return "2d";
    case MpcdiProfile::Simulation3d: return "3d";
    case MpcdiProfile::Advanced3d: return "a3";
    case MpcdiProfile::ShaderLamp: return "sl";
    }
    return "?";
}

FrustumAxes frustumAxes(const MpcdiFrustum& f) {
    constexpr double kDegree = 3.14159265358979323846 / 180.0;
    const double l = std::tan(f.leftAngle * kDegree), r = std::tan(f.rightAngle * kDegree);
    const double d = std::tan(f.downAngle * kDegree), t = std::tan(f.upAngle * kDegree);
    // In the frustum's own frame (x right, y up, -z its axis), then turned: roll about z,
    // pitch about x, yaw about y, negated or not so that positive yaw turns right, positive
    // pitch up and positive roll lowers the right side: R = Ry(-yaw) Rx(pitch) Rz(-roll).
    const double cr = std::cos(-f.roll * kDegree), sr = std::sin(-f.roll * kDegree);
    const double cp = std::cos(f.pitch * kDegree), sp = std::sin(f.pitch * kDegree);
    const double cy = std::cos(-f.yaw * kDegree), sy = std::sin(-f.yaw * kDegree);
    const auto turned = [&](double x, double y, double z) {
        const double x1 = cr * x - sr * y, y1 = sr * x + cr * y;     // Rz(-roll)
        const double y2 = cp * y1 - sp * z, z2 = sp * y1 + cp * z;   // Rx(pitch)
        return std::array<double, 3>{cy * x1 + sy * z2, y2, -sy * x1 + cy * z2};  // Ry(-yaw)
    };
    return {turned(l, d, -1.0), turned(r - l, 0.0, 0.0), turned(0.0, t - d, 0.0)};
}

Float3 FrustumAxes::direction(double u, double v) const {
    return {float(corner[0] + u * right[0] + v * up[0]), float(corner[1] + u * right[1] + v * up[1]),
            float(corner[2] + u * right[2] + v * up[2])};
}

const MpcdiBuffer* MpcdiFile::buffer(const std::string& id) const {
    for (const MpcdiBuffer& b : buffers)
        if (b.id == id) return &b;
    return nullptr;
}

MpcdiFile parseMpcdiXml(std::string_view xml, const MpcdiEntries& entries, const std::string& name) {
    pugi::xml_document doc;
    const pugi::xml_parse_result parsed = doc.load_buffer(xml.data(), xml.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!parsed) fail(name, "mpcdi.xml at byte " + std::to_string(parsed.offset) + ": " + parsed.description());
    const pugi::xml_node root = child(doc, "MPCDI");
    if (!root) fail(name, "mpcdi.xml has no <MPCDI> element");
    MpcdiFile file;
    file.version = trimmed(attribute(root, "version").value());
    const std::string profile = lowered(trimmed(attribute(root, "profile").value()));
    if (profile == "2d") file.profile = MpcdiProfile::Flat2d;
    else if (profile == "3d") file.profile = MpcdiProfile::Simulation3d;
    else if (profile == "a3") file.profile = MpcdiProfile::Advanced3d;
    else if (profile == "sl") file.profile = MpcdiProfile::ShaderLamp;
    else fail(name, "mpcdi.xml: profile " + quote(profile) + " is none of 2d, 3d, a3, sl");
    if (const std::optional<double> level = optionalNumber(root, "geometry", name, "<MPCDI>")) {
        if (*level != std::floor(*level) || *level < 1 || *level > 4)
            fail(name, "mpcdi.xml: geometry level " + shortNumber(*level) + " is none of 1, 2, 3, 4");
        file.level = int(*level);
    }

    const pugi::xml_node display = child(root, "display");
    if (!display) fail(name, "mpcdi.xml has no <display>");
    // Filesets: under <files> by their region attribute, or inside their region.
    std::map<std::string, pugi::xml_node> filesets;
    for (pugi::xml_node files : children(root, "files"))
        for (pugi::xml_node set : children(files, "fileset")) filesets[trimmed(attribute(set, "region").value())] = set;
    std::set<std::string> regionIds, bufferIds;
    for (pugi::xml_node bufferNode : children(display, "buffer")) {
        MpcdiBuffer& buffer = file.buffers.emplace_back();
        buffer.id = trimmed(attribute(bufferNode, "id").value());
        if (buffer.id.empty()) buffer.id = "buffer" + std::to_string(file.buffers.size() - 1);  // unnamed: by position
        if (!bufferIds.insert(buffer.id).second) fail(name, "mpcdi.xml: two buffers are called " + quote(buffer.id));
        const std::string bufferWhere = describe("buffer", buffer.id);
        buffer.xResolution = resolution(bufferNode, "Xresolution", name, bufferWhere);
        buffer.yResolution = resolution(bufferNode, "Yresolution", name, bufferWhere);
        for (pugi::xml_node regionNode : children(bufferNode, "region")) {
            MpcdiRegion& region = buffer.regions.emplace_back();
            region.id = trimmed(attribute(regionNode, "id").value());
            if (region.id.empty()) fail(name, bufferWhere + ": a region without an id");
            if (!regionIds.insert(region.id).second) fail(name, "mpcdi.xml: two regions are called " + quote(region.id));
            const std::string where = describe("region", region.id);
            region.xResolution = resolution(regionNode, "Xresolution", name, where);
            region.yResolution = resolution(regionNode, "Yresolution", name, where);
            region.x = optionalNumber(regionNode, "x", name, where).value_or(0);
            region.y = optionalNumber(regionNode, "y", name, where).value_or(0);
            region.xSize = optionalNumber(regionNode, "xsize", name, where).value_or(1);
            region.ySize = optionalNumber(regionNode, "ysize", name, where).value_or(1);
            constexpr double eps = 1e-6;
            if (region.x < 0 || region.y < 0 || region.xSize <= 0 || region.ySize <= 0 || region.x + region.xSize > 1 + eps ||
                region.y + region.ySize > 1 + eps)
                fail(name, where + " is not inside its buffer (x, y, xsize, ysize must lie in [0, 1])");
            if (pugi::xml_node f = child(regionNode, "frustum")) {
                MpcdiFrustum fr;
                const std::string fw = where + " frustum";
                for (auto [key, out] : {std::pair{"yaw", &fr.yaw}, {"pitch", &fr.pitch}, {"roll", &fr.roll}, {"leftAngle", &fr.leftAngle},
                                        {"rightAngle", &fr.rightAngle}, {"upAngle", &fr.upAngle}, {"downAngle", &fr.downAngle}}) {
                    const std::optional<double> v = optionalNumber(f, key, name, fw);
                    // The angles bound the view: a frustum without one is no frustum (the
                    // MPCDI SDK's -1 defaults would pass for a 1-degree view). Turns default to 0.
                    if (!v && std::string_view(key).ends_with("Angle")) fail(name, fw + " has no " + key);
                    if (v && std::abs(*v) > 360) fail(name, fw + " " + key + " is " + shortNumber(*v) + " degrees (at most 360 either way)");
                    *out = v.value_or(0);
                }
                const auto inside = [](double a) { return a > -90 && a < 90; };
                if (fr.leftAngle >= fr.rightAngle || fr.downAngle >= fr.upAngle || !inside(fr.leftAngle) || !inside(fr.rightAngle) ||
                    !inside(fr.upAngle) || !inside(fr.downAngle))
                    fail(name, fw + ": its angles span no view (left < right, down < up, each between -90 and 90 degrees)");
                region.frustum = fr;
            }
            if (file.profile == MpcdiProfile::Simulation3d && !region.frustum)
                fail(name, where + " has no <frustum> (profile 3d: its warp holds coordinates in that frustum)");
            pugi::xml_node set = filesets.count(region.id) ? filesets[region.id] : pugi::xml_node{};
            if (!set) set = child(regionNode, "fileset");
            if (!set)
                if (pugi::xml_node inner = child(regionNode, "files")) set = child(inner, "fileset");
            if (!set) fail(name, where + " has no fileset (its geometry warp)");
            const pugi::xml_node warpNode = child(set, "geometryWarpFile");
            if (!warpNode) fail(name, where + " has no geometryWarpFile");
            const std::string warpPath = pathOf(warpNode);
            if (warpPath.empty()) fail(name, where + " geometryWarpFile names no file");
            if (pugi::xml_node interp = child(warpNode, "interpolation")) {
                const std::string method = lowered(trimmed(interp.text().get()));
                if (method != "linear" && !method.empty())
                    fail(name, where + " geometryWarpFile: interpolation " + quote(method) + " is not supported (linear)");
            }
            const std::string unit = trimmed(child(warpNode, "geometricUnit").text().get());
            const std::optional<std::vector<uint8_t>> warpBytes = entries(warpPath);
            if (!warpBytes) fail(name, where + " geometry warp " + quote(warpPath) + " is not in the archive");
            region.warp = parsePfm(*warpBytes, within(name, warpPath));
            region.warp.geometricUnit = unit;
            region.warp.metresPerUnit = warpsToSurface(file.profile) ? metresPer(unit, name, where) : 1.0;
            if (region.warp.validSamples == 0)
                fail(name, where + " geometry warp " + quote(warpPath) + ": every sample is NaN (the projector lands on no screen)");
            if (pugi::xml_node a = child(set, "alphaMap")) region.alpha = blendMap(a, region, entries, name, "alpha map", 2.2);
            if (pugi::xml_node b = child(set, "betaMap")) region.beta = blendMap(b, region, entries, name, "beta map", 1.0);
        }
        if (buffer.regions.empty()) fail(name, bufferWhere + " has no region");
    }
    if (file.buffers.empty()) fail(name, "mpcdi.xml: <display> has no buffer");
    return file;
}

MpcdiFile parseMpcdi(std::span<const uint8_t> bytes, const std::string& name) {
    const Archive archive(bytes, name);
    const std::optional<std::vector<uint8_t>> xml = archive.entry("mpcdi.xml");
    if (!xml) fail(name, "the archive has no mpcdi.xml");
    return parseMpcdiXml(std::string_view(reinterpret_cast<const char*>(xml->data()), xml->size()),
                         [&](const std::string& entry) { return archive.entry(entry); }, name);
}

MpcdiFile readMpcdi(const std::filesystem::path& file) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(file, ec);
    if (ec) fail(file.string(), "cannot read it (" + ec.message() + ")");
    if (size > kMaxMpcdiEntry) fail(file.string(), "larger than " + std::to_string(kMaxMpcdiEntry >> 20) + " MiB");
    std::ifstream in(file, std::ios::binary);
    std::vector<uint8_t> bytes(size);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size))) fail(file.string(), "cannot read it");
    return parseMpcdi(bytes, file.string());
}

}  // namespace rtwall
