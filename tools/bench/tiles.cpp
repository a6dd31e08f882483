// rtwall bench tiles and rtwall bench codecs (speed.h): per-tile times, bytes and each codec's
// error.
#include "speed.h"
#include "speed_util.h"
#include "tile_failure.h"

#include <rtwall/tune.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>

namespace rtwall::bench {

namespace {

double sum(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s;
}

// The reference image of --reference, which must be the wall's size.
std::optional<Image> readReference(const std::string& file, int wallW, int wallH) {
    if (file.empty()) return std::nullopt;
    Image reference = readPng(file);
    if (reference.width != wallW || reference.height != wallH)
        throw InputError(file + " is " + std::to_string(reference.width) + "x" + std::to_string(reference.height) +
                         ", the wall " + std::to_string(wallW) + "x" + std::to_string(wallH));
    return reference;
}

// One row per codec: bytes, encode and decode time, and the error (upscaled to the wall) against
// the reference if there is one.
toml::array codecRows(const TileProfile& profile, const std::vector<CodecSettings>& codecs, const std::vector<Image>& decoded,
                      const std::optional<Image>& reference, int wallW, int wallH, std::FILE* text) {
    toml::array rows;
    for (size_t i = 0; i < codecs.size(); ++i) {
        const auto& cc = profile.codecs[i];
        double bytes = 0;
        for (uint32_t b : cc.bytes) bytes += b;
        toml::table row{{"codec", codecLabel(codecs[i])},
                        {"bytes_per_frame", bytes},
                        {"encode_s", sum(cc.encodeSeconds)},
                        {"decode_s", sum(cc.decodeSeconds)}};
        if (reference) {
            const Image shown = resizeBilinear(decoded[i], wallW, wallH);
            row.insert("error", errorTable(compareImages(shown, *reference)));
        }
        if (text)
            std::fprintf(text, "%-8s %8.3f MB/frame, encode %.3f s, decode %.3f s%s\n", codecLabel(codecs[i]).c_str(),
                         bytes * 1e-6, sum(cc.encodeSeconds), sum(cc.decodeSeconds),
                         reference ? (", PSNR " + std::to_string((*row["error"].as_table())["psnr_db"].value_or(0.0)) +
                                      " dB").c_str()
                                   : "");
        rows.push_back(std::move(row));
    }
    return rows;
}

}  // namespace

toml::table tiles(const TilesOptions& o) {
    SceneDesc desc = loadSized(o.scene, o.triangles, o.width, o.height);
    RenderSettings& s = desc.settings;
    const int wallW = s.width, wallH = s.height;
    o.controls.apply(desc);
    if (!o.shading.empty()) s.shading = o.shading == "eyelight" ? ShadingMode::EyeLight : ShadingMode::Full;
    s.threads = 1;
    std::vector<CodecSettings> codecs;
    for (const std::string& c : splitList(o.codecs)) codecs.push_back(parseCodec(c));
    if (codecs.empty()) throw InputError("--codecs: no codec given");
    const std::optional<Image> reference = readReference(o.reference, wallW, wallH);
    const CameraDesc start = pickCamera(desc, o.scene, o.camera);
    std::vector<CameraDesc> cameras;
    for (int f = 0; f < o.frames; ++f) cameras.push_back(orbitCamera(start, o.orbitDegrees * f));
    const Scene scene(desc);
    Image lossless;
    std::vector<Image> decoded;
    TileProfile profile;
    try {
        profile = profileTiles(scene, cameras, s, codecs, &lossless, &decoded);
    } catch (const TileError& e) {
        // Frame f + 1 is cameras[f] (frame 1's eye-light warm-up pass is reported as frame 1).
        const size_t f = std::min<size_t>(std::max<uint32_t>(e.frame(), 1) - 1, cameras.size() - 1);
        throw withReplay(e, {o.scene, o.triangles, desc.origin, cameras[f], s, {}, 0, {}});
    }
    profile.scene = o.scene;
    if (!o.profileOut.empty()) writeTileProfile(profile, o.profileOut);
    if (!o.saveImage.empty()) writePng(lossless, o.saveImage);

    toml::array rows = codecRows(profile, codecs, decoded, reference, wallW, wallH, o.text);
    std::vector<double> frameRender;
    toml::array renderArray;
    for (const auto& f : profile.renderSeconds) {
        frameRender.push_back(sum(f));
        renderArray.push_back(sum(f));
    }
    toml::table out{{"benchmark", "tiles"},
                    {"scene", o.scene},
                    {"wall_width", wallW},
                    {"wall_height", wallH},
                    {"width", s.width},
                    {"height", s.height},
                    {"scale", o.controls.value("scale").value_or(1.0)},
                    {"tile", s.tileSize},
                    {"supersample", s.supersample},
                    {"tiles", int64_t(profile.tileCount())},
                    {"render_s_per_frame", renderArray},
                    {"codecs", rows}};
    if (!o.profileOut.empty()) out.insert("profile", o.profileOut);
    if (o.text)
        std::fprintf(o.text, "%s at %dx%d (wall %dx%d), tile %d, %dx%d samples: %zu tiles, %.3f s per frame on one thread\n",
                     o.scene.c_str(), s.width, s.height, wallW, wallH, s.tileSize, s.supersample, s.supersample,
                     profile.tileCount(), frameRender.front());
    return out;
}

toml::table codecs(const CodecsOptions& o) {
    const Image img = readPng(o.image);
    toml::array rows;
    for (const std::string& c : splitList(o.codecs)) {
        const CodecSettings cs = parseCodec(c);
        uint64_t bytes = 0;
        const Image out = codecRoundTrip(img, o.tile, cs, &bytes);
        const ImageError e = compareImages(out, img);
        if (!o.diffDir.empty()) {
            std::string stem = codecLabel(cs);
            for (char& ch : stem) if (ch == ':') ch = '_';
            writePng(out, std::filesystem::path(o.diffDir) / (stem + ".png"));
            writePng(differenceImage(out, img, 32), std::filesystem::path(o.diffDir) / (stem + "_diff.png"));
        }
        toml::table row{{"codec", codecLabel(cs)}, {"bytes", int64_t(bytes)},
                        {"bits_per_pixel", 8.0 * double(bytes) / (double(img.width) * img.height)},
                        {"error", errorTable(e)}};
        if (o.text)
            std::fprintf(o.text, "%-8s %9llu bytes (%.2f bit/pixel), PSNR %6.2f dB, SSIM %.4f, largest error %d\n",
                        codecLabel(cs).c_str(), (unsigned long long)bytes,
                        8.0 * double(bytes) / (double(img.width) * img.height), e.psnrDb, e.ssim, e.maxError);
        rows.push_back(std::move(row));
    }
    return toml::table{{"benchmark", "codecs"}, {"image", o.image}, {"width", img.width},
                       {"height", img.height}, {"tile", o.tile}, {"codecs", rows}};
}

}  // namespace rtwall::bench
