// The controls: every setting the operating point (`rtwall run --target-fps`) and the
// speed/accuracy sweep (tools/speed_accuracy.py, through `rtwall bench tiles` and `rtwall
// reference`) change, in one table. Adding one is one entry here; the sweep learns of it from
// `rtwall controls --json`.
#include <rtwall/toml_reader.h>
#include <rtwall/wall.h>

#include <toml++/toml.h>

#include <cmath>
#include <sstream>

namespace rtwall {

namespace {

void setTile(Knobs& k, const RenderSettings&, double v) { k.settings.tileSize = int(v); }
void setCodec(Knobs& k, const RenderSettings&, double v) { k.codec.codec = TileCodec(int(v)); }
void setJpegQuality(Knobs& k, const RenderSettings&, double v) { k.codec.jpegQuality = int(v); }
void setScale(Knobs& k, const RenderSettings& base, double v) {
    // A fraction of the wall's resolution; the wall shows the frame upscaled (bilinear).
    k.settings.width = std::max(16, int(std::lround(base.width * v)));
    k.settings.height = std::max(16, int(std::lround(base.height * v)));
}
void setSupersample(Knobs& k, const RenderSettings&, double v) { k.settings.supersample = int(v); }
void setPrune(Knobs& k, const RenderSettings&, double v) { k.settings.pruneThreshold = float(v); }
void setGiSpp(Knobs& k, const RenderSettings&, double v) {  // 0: no GI; n: path tracing, n samples per pixel sample
    k.settings.gi = v > 0;
    k.settings.samples = std::max(1, int(v));
}
void setVolumeStep(Knobs& k, const RenderSettings&, double v) { k.volumeStep = float(v); }
void setDenoise(Knobs& k, const RenderSettings&, double v) { k.denoise = DenoiseSettings::Mode(int(v)); }

}  // namespace

const std::vector<Control>& controls() {
    static const std::vector<Control> table = {
        {"tile", "--tile", "Tile size in pixels", 4, 1024, {32, 64, 128}, "{}", setTile, {}},
        {"codec", "", "Tile codec: 0 raw, 1 LZ4, 2 zstd, 3 JPEG (TileCodec)", 0, 3, {}, "{}", setCodec, {}},
        {"jpeg_quality", "", "JPEG quality of the tiles", 1, 100, {}, "q{}", setJpegQuality, {}},
        {"scale", "--scale", "Render at this fraction of the wall's resolution; the wall shows it upscaled", 0.05, 1.0,
         {0.5, 0.75, 1.0}, "{}x", setScale, {}},
        {"supersample", "--supersample", "n x n samples per pixel", 1, 32, {1, 2}, "{}x{}", setSupersample, {}},
        {"prune", "--prune", "Ray-tree pruning threshold (0: never prune)", 0, 1, {0.0005, 0.002, 0.01, 0.05}, "{}",
         setPrune, {}},
        {"gi_spp", "--gi-spp", "Path-traced GI samples per pixel sample (0: GI off)", 0, 4096, {1, 4, 16}, "{} spp", setGiSpp, {}},
        {"volume_step", "--volume-step", "Ray-march step of every volume material, in voxels", 0.01, 100,
         {0.25, 1.0, 4.0}, "{} voxels", setVolumeStep, {}},
        // Scored over a moving sequence, not one frame (temporal reuse needs history): `rtwall
        // bench tiles --denoise` renders the frames of a short orbit that ends at the scored view.
        {"denoise", "--denoise", "Denoise the frames on the display side: 0 off, 1 temporal, 2 svgf (GI scenes)", 0, 2,
         {0, 1, 2}, "{}", setDenoise, {"off", "temporal", "svgf"}},
    };
    return table;
}

const Control& control(const std::string& name, const std::string& point) {
    std::string known;
    for (const Control& c : controls()) {
        if (c.name == name) return c;
        known += (known.empty() ? "" : ", ") + std::string(c.name);
    }
    throw InputError("operating point '" + point + "': this build cannot set control '" + name + "' (it can: " + known + ")");
}

std::string controlsJson() {
    toml::array out;
    for (const Control& c : controls()) {
        toml::array sweep;
        for (double v : c.sweep) sweep.push_back(v);
        out.push_back(toml::table{{"name", c.name}, {"option", c.option}, {"help", c.help}, {"min", c.min},
                                  {"max", c.max}, {"sweep", std::move(sweep)}, {"label", c.label}});
        if (!c.names.empty()) {
            toml::array names;
            for (const std::string& n : c.names) names.push_back(n);
            out.back().as_table()->insert("names", std::move(names));
        }
    }
    std::ostringstream os;
    os << toml::json_formatter{toml::table{{"controls", std::move(out)}}};
    return os.str();
}

Knobs knobsOf(const OperatingPoint& p, const RenderSettings& base, const CodecSettings& baseCodec) {
    Knobs k{base, baseCodec, 0, std::nullopt};
    for (const auto& [name, v] : p.controls) {
        const Control& c = control(name, p.name);
        if (!(v >= c.min && v <= c.max))
            throw InputError("operating point '" + p.name + "': control '" + name + "' = " + std::to_string(v) +
                             " is outside [" + std::to_string(c.min) + ", " + std::to_string(c.max) + "]");
        if (!c.names.empty() && v != std::floor(v))
            throw InputError("operating point '" + p.name + "': control '" + name + "' = " + std::to_string(v) +
                             " is not a whole number (" + [&] {
                                 std::string list;
                                 for (size_t i = 0; i < c.names.size(); ++i)
                                     list += (i ? ", " : "") + std::to_string(i) + " " + c.names[i];
                                 return list;
                             }() + ")");
        c.apply(k, base, v);
    }
    return k;
}

std::vector<OperatingPoint> readFront(const std::filesystem::path& file) {
    using namespace toml_reader;
    const toml::table root = parseFile(file);
    Reader top(file, root, "");
    std::vector<OperatingPoint> points;
    top.string("scene", "");
    top.number("target_fps_hint", 0, 0, 1e6);
    forEachTable(top, file, "point", [&](Reader& r, const toml::table& t) {
        OperatingPoint p;
        p.name = r.string("name", "", true);
        p.frameSeconds = r.number("frame_s", 0, 1e-9, 1e6);
        p.error = r.number("error", 0, 0, 1e9);
        r.number("psnr_db", 0, -1e9, 1e9);
        if (const toml::table* c = t["controls"].as_table()) {
            for (const auto& [key, value] : *c) {
                const std::optional<double> v = value.value<double>();
                if (!v) r.fail(&value, "point '" + p.name + "': control '" + std::string(key.str()) + "' must be a number");
                p.controls.emplace_back(std::string(key.str()), *v);
            }
            r.find("controls");
        }
        points.push_back(p);
    });
    top.finish();
    return points;
}

}  // namespace rtwall
