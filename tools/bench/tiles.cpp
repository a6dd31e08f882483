// rtwall bench tiles and rtwall bench codecs (speed.h): per-tile times, bytes and each codec's
// error.
#include "speed.h"
#include "speed_util.h"
#include "bench_util.h"
#include "tile_failure.h"

#include <rtwall/denoise.h>
#include <rtwall/tune.h>

#include <algorithm>
#include <chrono>
#include <thread>
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

// What the wall shows of the scored view with the scene's [denoise] mode (issue 28), when the
// camera arrives at it turning `degrees` a frame about the look-at point: each of `frames` frames
// rendered whole with its features (all threads), quantised as the cluster sends them and
// filtered by one Denoiser; the last is the view (frame time aside: the tile profile's).
toml::table denoisedRow(const Scene& scene, const SceneDesc& desc, const CameraDesc& view, int frames, double degrees,
                        const std::optional<Image>& reference, int wallW, int wallH, std::FILE* text) {
    const RenderSettings& s = desc.settings;
    RenderSettings rs = s;
    rs.threads = 0;
    const uint8_t bits = featureBitsFor(desc.denoise.mode);
    Denoiser dn;
    std::vector<double> ms;
    std::vector<float> shown;
    for (int k = 0; k < frames; ++k) {
        const CameraDesc cd = k == frames - 1 ? view : orbitCamera(view, degrees * (frames - 1 - k));
        FeatureFrame f = renderFrameFeatures(scene, Camera(cd, s.width, s.height), rs, uint32_t(k + 1));
        quantiseAsSent(f, bits);
        const auto t0 = std::chrono::steady_clock::now();
        const std::span<const float> out = dn.denoise({s.width, s.height, f.linear, f.depth, f.albedo, f.normal, f.id, cd, 0}, desc.denoise);
        ms.push_back(1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        if (k == frames - 1) shown.assign(out.begin(), out.end());
    }
    const Image img = srgbImage(shown, s.width, s.height);
    const size_t pixels = size_t(s.width) * size_t(s.height);
    // Linear half-float colour, the 16-bit depth code and the mode's features, before any compression.
    const double bytes = double(pixels * (6 + 2) + encodedFeatureBytes(pixels, bits));
    std::sort(ms.begin(), ms.end());
    toml::table row{{"denoise", denoiseModeName(desc.denoise.mode)},
                    {"frames", frames},
                    {"degrees_per_frame", degrees},
                    {"filter_ms", ms[ms.size() / 2]},
                    {"threads", int(std::max(1u, std::thread::hardware_concurrency()))},
                    {"bytes_per_frame", bytes}};
    if (reference) row.insert("error", errorTable(compareImages(resizeBilinear(img, wallW, wallH), *reference)));
    if (text)
        std::fprintf(text, "denoise %s after %d frames of %g degrees: filter %.1f ms a frame, %.3f MB/frame%s\n",
                     denoiseModeName(desc.denoise.mode), frames, degrees, ms[ms.size() / 2], bytes * 1e-6,
                     reference ? (", PSNR " + std::to_string((*row["error"].as_table())["psnr_db"].value_or(0.0)) + " dB").c_str()
                               : "");
    return row;
}

}  // namespace

toml::table tiles(const TilesOptions& o) {
    SceneDesc desc = loadSized(o.scene, o.triangles, o.width, o.height);
    RenderSettings& s = desc.settings;
    const int wallW = s.width, wallH = s.height;
    o.controls.apply(desc);
    if (!o.shading.empty()) s.shading = o.shading == "eyelight" ? ShadingMode::EyeLight : ShadingMode::Full;
    s.threads = 1;
    // The scene's [denoise] or --denoise; only path-traced frames are filtered (as on the wall).
    const bool denoised = desc.denoise.mode != DenoiseSettings::Mode::Off && s.gi;
    if (o.controls.value("denoise").value_or(0) > 0 && !s.gi)
        throw InputError("bench tiles: --denoise filters path-traced frames; this scene renders without GI (--gi-spp)");
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
    if (denoised)
        out.insert("denoised", denoisedRow(scene, desc, start, o.denoiseFrames, o.denoiseDegrees, reference, wallW, wallH, o.text));
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
