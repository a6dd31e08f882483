// Tile profiles: what each tile costs to render, encode and decode, measured on this PC, for
// the cluster simulation. Stored as TOML so that the C++ side reads it with the project's one
// config parser and Python's tomllib reads it too.
//
// Times are the calling thread's CPU time, not wall-clock time: on a PC shared with other jobs
// a tile's wall time includes whatever ran in between, and the simulation would replay that
// load as if it were the tile's cost. Frame 0 is rendered once untimed first (primary rays only), so that first-touch
// costs (page faults in the BVH and textures, cold caches) are not recorded either: the clients
// the profile stands for render frame after frame.
#include "codec.h"

#include <rtwall/cluster.h>

#include <toml++/toml.h>

#include <ctime>
#include <fstream>

namespace rtwall {

using namespace cluster;

namespace {

double threadCpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

template <class T> toml::array arrayOf(const std::vector<T>& v) {
    toml::array a;
    for (const T& x : v) {
        if constexpr (std::is_floating_point_v<T>) a.push_back(double(x));
        else a.push_back(int64_t(x));
    }
    return a;
}

}  // namespace

TileProfile profileTiles(const Scene& scene, const std::vector<CameraDesc>& cameras, const RenderSettings& settings,
                         const std::vector<CodecSettings>& codecs, Image* lossless, std::vector<Image>* decoded) {
    if (cameras.empty()) throw InputError("tile profile: no camera");
    TileProfile p;
    p.width = settings.width;
    p.height = settings.height;
    p.tileSize = settings.tileSize;
    const std::vector<TileRect> tiles = makeTiles(settings.width, settings.height, settings.tileSize);
    Image frame0{settings.width, settings.height, std::vector<uint8_t>(size_t(settings.width) * settings.height * 3)};
    Image scratch = frame0;
    {
        // Primary rays only: they touch the visible part of the BVH and textures at a fraction
        // of a full frame's cost (the sweep profiles every setting).
        RenderSettings eye = settings;
        eye.shading = ShadingMode::EyeLight;
        eye.supersample = 1;
        eye.gi = false;
        eye.samples = 1;
        const Camera warm(cameras.front(), settings.width, settings.height);
        for (const TileRect& r : tiles) renderTile(scene, warm, r, 1, eye, {scratch.pixel(r.x0, r.y0), size_t(scratch.width) * 3});
    }
    for (size_t f = 0; f < cameras.size(); ++f) {
        Image& img = f == 0 ? frame0 : scratch;
        const Camera camera(cameras[f], settings.width, settings.height);
        std::vector<double> times;
        times.reserve(tiles.size());
        for (const TileRect& r : tiles) {
            const double t0 = threadCpuSeconds();
            renderTile(scene, camera, r, uint32_t(f + 1), settings, {img.pixel(r.x0, r.y0), size_t(img.width) * 3});
            times.push_back(threadCpuSeconds() - t0);
        }
        p.renderSeconds.push_back(std::move(times));
    }
    if (decoded) decoded->clear();
    std::vector<uint8_t> bytes;
    for (const CodecSettings& cs : codecs) {
        TileProfile::CodecCost cost;
        cost.codec = cs;
        Image out = frame0;
        for (const TileRect& r : tiles) {
            bytes.clear();
            double t0 = threadCpuSeconds();
            encodeTile(cs, frame0.pixel(r.x0, r.y0), r.width(), r.height(), size_t(frame0.width) * 3, bytes);
            cost.encodeSeconds.push_back(threadCpuSeconds() - t0);
            cost.bytes.push_back(uint32_t(bytes.size()));
            t0 = threadCpuSeconds();
            decodeTile(cs.codec, bytes.data(), bytes.size(), r.width(), r.height(), out.pixel(r.x0, r.y0), size_t(out.width) * 3);
            cost.decodeSeconds.push_back(threadCpuSeconds() - t0);
        }
        p.codecs.push_back(std::move(cost));
        if (decoded) decoded->push_back(std::move(out));
    }
    if (lossless) *lossless = std::move(frame0);
    return p;
}

Image codecRoundTrip(const Image& image, int tileSize, const CodecSettings& codec, uint64_t* total) {
    Image out = image;
    std::vector<uint8_t> bytes;
    uint64_t sum = 0;
    for (const TileRect& r : makeTiles(image.width, image.height, tileSize)) {
        bytes.clear();
        encodeTile(codec, image.pixel(r.x0, r.y0), r.width(), r.height(), size_t(image.width) * 3, bytes);
        sum += bytes.size();
        decodeTile(codec.codec, bytes.data(), bytes.size(), r.width(), r.height(), out.pixel(r.x0, r.y0), size_t(out.width) * 3);
    }
    if (total) *total = sum;
    return out;
}

void writeTileProfile(const TileProfile& p, const std::filesystem::path& file) {
    toml::table root{{"scene", p.scene}, {"width", p.width}, {"height", p.height}, {"tile", p.tileSize}};
    toml::array frames;
    for (const auto& f : p.renderSeconds) frames.push_back(toml::table{{"render_s", arrayOf(f)}});
    root.insert("frame", std::move(frames));
    toml::array codecs;
    for (const auto& c : p.codecs)
        codecs.push_back(toml::table{{"codec", tileCodecName(c.codec.codec)},
                                     {"jpeg_quality", c.codec.jpegQuality},
                                     {"jpeg_subsample", c.codec.jpegSubsample},
                                     {"zstd_level", c.codec.zstdLevel},
                                     {"bytes", arrayOf(c.bytes)},
                                     {"encode_s", arrayOf(c.encodeSeconds)},
                                     {"decode_s", arrayOf(c.decodeSeconds)}});
    root.insert("codec", std::move(codecs));
    std::ofstream out(file);
    out << root << "\n";
    if (!out) throw InputError(file.string() + ": cannot write the tile profile");
}

TileProfile readTileProfile(const std::filesystem::path& file) {
    toml::table root;
    try {
        root = toml::parse_file(file.string());
    } catch (const toml::parse_error& e) {
        throw InputError(file.string() + ": not a tile profile: " + std::string(e.description()));
    }
    auto fail = [&](const std::string& what) -> void { throw InputError(file.string() + ": tile profile: " + what); };
    TileProfile p;
    p.scene = root["scene"].value_or(std::string());
    p.width = int(root["width"].value_or(int64_t(0)));
    p.height = int(root["height"].value_or(int64_t(0)));
    p.tileSize = int(root["tile"].value_or(int64_t(0)));
    if (p.width <= 0 || p.height <= 0 || p.tileSize <= 0) fail("width, height and tile must be positive integers");
    const size_t tiles = makeTiles(p.width, p.height, p.tileSize).size();
    auto numbers = [&](const toml::node_view<toml::node>& n, const char* what) {
        std::vector<double> v;
        const toml::array* a = n.as_array();
        if (!a) fail(std::string("missing array '") + what + "'");
        for (const toml::node& e : *a) {
            const std::optional<double> x = e.value<double>();
            if (!x || *x < 0) fail(std::string("'") + what + "' holds a value that is not a non-negative number");
            v.push_back(*x);
        }
        if (v.size() != tiles) fail(std::string("'") + what + "' has " + std::to_string(v.size()) + " values for " +
                                    std::to_string(tiles) + " tiles");
        return v;
    };
    toml::array* frames = root["frame"].as_array();
    if (!frames || frames->empty()) fail("no [[frame]]");
    for (toml::node& f : *frames) {
        if (!f.is_table()) fail("[[frame]] must be tables");
        p.renderSeconds.push_back(numbers(toml::node_view<toml::node>(f)["render_s"], "render_s"));
    }
    toml::array* codecs = root["codec"].as_array();
    if (!codecs || codecs->empty()) fail("no [[codec]]");
    for (toml::node& c : *codecs) {
        if (!c.is_table()) fail("[[codec]] must be tables");
        toml::node_view<toml::node> v(c);
        TileProfile::CodecCost cc;
        cc.codec.codec = tileCodecFromName(v["codec"].value_or(std::string()));
        cc.codec.jpegQuality = int(v["jpeg_quality"].value_or(int64_t(90)));
        cc.codec.jpegSubsample = v["jpeg_subsample"].value_or(false);
        cc.codec.zstdLevel = int(v["zstd_level"].value_or(int64_t(1)));
        for (double b : numbers(v["bytes"], "bytes")) cc.bytes.push_back(uint32_t(b));
        cc.encodeSeconds = numbers(v["encode_s"], "encode_s");
        cc.decodeSeconds = numbers(v["decode_s"], "decode_s");
        p.codecs.push_back(std::move(cc));
    }
    return p;
}

}  // namespace rtwall
