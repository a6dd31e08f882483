// rtwall compare and rtwall reference (speed.h), and what the speed commands share: codec
// names, control values, error tables.
#include "speed.h"
#include "speed_util.h"
#include "tile_failure.h"

#include <rtwall/tune.h>
#include <rtwall/wall.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace rtwall::bench {

CodecSettings parseCodec(const std::string& text) {
    CodecSettings cs;
    const size_t colon = text.find(':');
    cs.codec = tileCodecFromName(text.substr(0, colon));
    if (colon != std::string::npos) {
        int v = 0;
        const std::string arg = text.substr(colon + 1);
        if (std::sscanf(arg.c_str(), "%d", &v) != 1) throw InputError("codec '" + text + "': expected NAME:NUMBER");
        if (cs.codec == TileCodec::Jpeg && v >= 1 && v <= 100) cs.jpegQuality = v;
        else if (cs.codec == TileCodec::Zstd && v >= 1 && v <= 19) cs.zstdLevel = v;
        else throw InputError("codec '" + text + "': only jpeg:1..100 and zstd:1..19 take a number");
    }
    return cs;
}

std::string codecLabel(const CodecSettings& cs) {
    if (cs.codec == TileCodec::Jpeg) return "jpeg:" + std::to_string(cs.jpegQuality);
    if (cs.codec == TileCodec::Zstd && cs.zstdLevel != 1) return "zstd:" + std::to_string(cs.zstdLevel);
    return tileCodecName(cs.codec);
}

std::optional<double> ControlValues::value(const std::string& name) const {
    auto it = given.find(name);
    return it == given.end() ? std::nullopt : it->second;
}

void ControlValues::apply(SceneDesc& desc) const {
    OperatingPoint p;
    p.name = "the command line";
    for (const auto& [name, v] : given)
        if (v) p.controls.emplace_back(name, *v);
    const Knobs k = knobsOf(p, desc.settings, {});
    desc.settings = k.settings;
    if (k.denoise) desc.denoise.mode = *k.denoise;
    if (k.volumeStep > 0)
        for (Material& m : desc.materials)
            if (m.type == MaterialType::Volume) m.volumeStep = k.volumeStep;
}

std::vector<std::string> splitList(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream ss(text);
    for (std::string item; std::getline(ss, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

toml::table errorTable(const ImageError& e) {
    return toml::table{{"rmse", e.rmse},        {"psnr_db", e.psnrDb}, {"ssim", e.ssim},       {"flip", e.flip},
                       {"max_error", e.maxError}, {"mean_abs_error", e.meanAbs}, {"identical", e.identical()}};
}

SceneDesc loadSized(const std::string& name, int64_t triangles, int width, int height) {
    SceneLoadOptions load;
    load.builtinTriangles = triangles;
    SceneDesc desc = loadScene(name, load);
    if (width) desc.settings.width = width;
    if (height) desc.settings.height = height;
    return desc;
}

const CameraDesc& pickCamera(const SceneDesc& desc, const std::string& scene, const std::string& name) {
    if (name.empty()) return desc.cameras.front();
    if (const CameraDesc* c = desc.findCamera(name)) return *c;
    throw InputError(scene + ": no camera named '" + name + "'");
}

toml::table compare(const CompareOptions& o) {
    const Image a = readPng(o.test), b = readPng(o.reference);
    if (a.width != b.width || a.height != b.height)
        throw InputError(o.test + " is " + std::to_string(a.width) + "x" + std::to_string(a.height) + " but " +
                         o.reference + " is " + std::to_string(b.width) + "x" + std::to_string(b.height));
    const ImageError e = compareImages(a, b);
    if (!o.diff.empty()) writePng(differenceImage(a, b, o.scale), o.diff);
    toml::table t = errorTable(e);
    t.insert("image", o.test);
    t.insert("reference", o.reference);
    t.insert("width", a.width);
    t.insert("height", a.height);
    t.insert("max_error_at", toml::array{e.maxX, e.maxY});
    t.insert("ssim_method", "mean SSIM of luminance (0.299 R + 0.587 G + 0.114 B), 11x11 Gaussian window, "
                            "sigma 1.5, K1 0.01, K2 0.03, valid windows");
    t.insert("flip_method", "mean LDR-FLIP (Andersson et al. 2020), 67 pixels per degree, edges extended");
    if (!o.diff.empty()) t.insert("diff", o.diff);
    if (o.text)
        std::fprintf(o.text, "%s against %s (%dx%d): RMSE %.3f levels, PSNR %s dB, SSIM %.5f, FLIP %.4f, largest error %d "
                     "levels at (%d, %d)%s\n",
                     o.test.c_str(), o.reference.c_str(), a.width, a.height, e.rmse,
                     e.identical() ? "inf" : std::to_string(e.psnrDb).c_str(), e.ssim, e.flip, e.maxError, e.maxX, e.maxY,
                     o.diff.empty() ? "" : (", difference in " + o.diff).c_str());
    return t;
}

toml::table reference(const ReferenceOptions& o) {
    SceneDesc desc = loadSized(o.scene, o.triangles, o.width, o.height);
    RenderSettings& s = desc.settings;
    o.controls.apply(desc);
    s.supersample = int(o.controls.value("supersample").value_or(8));
    s.threads = o.threads;
    const CameraDesc cam = pickCamera(desc, o.scene, o.camera);
    const Scene scene(desc);
    const Camera camera(cam, s.width, s.height);
    // A tile that fails is reported with the command that renders it again.
    auto replayable = [&](auto&& render) {
        try {
            return render();
        } catch (const TileError& e) {
            throw withReplay(e, {o.scene, o.triangles, desc.origin, cam, s, {}, 0, {}});
        }
    };
    if (o.frames == 1 && o.progressOut.empty() && o.firstFrame == 1u << 20) {
        writePng(replayable([&] { return renderFrame(scene, camera, s); }), o.out);
        if (o.text)
            std::fprintf(o.text, "wrote %s (%dx%d, %dx%d samples per pixel)\n", o.out.c_str(), s.width, s.height,
                         s.supersample, s.supersample);
        return toml::table{{"out", o.out}, {"frames", 1}};
    }
    Accumulator all, half[2];
    for (int f = 0; f < o.frames; ++f) {
        const std::vector<float> linear =
            replayable([&] { return renderFrameLinear(scene, camera, s, o.firstFrame + uint32_t(f)); });
        all.addLinear(linear.data(), s.width, s.height);
        half[2 * f < o.frames ? 0 : 1].addLinear(linear.data(), s.width, s.height);
        if (!o.progressOut.empty() && (all.frames() & (all.frames() - 1)) == 0)
            writePng(all.resolve(), o.progressOut + "-" + std::to_string(all.frames()) + ".png");
    }
    writePng(all.resolve(), o.out);
    // Two independent halves: their difference has twice one half's variance, and the
    // whole has half of it, so the whole's own error is a quarter of the halves' squared
    // difference: 6.02 dB above their PSNR (noise only; a bias both share is not seen).
    toml::table out{{"out", o.out}, {"frames", o.frames}};
    if (o.frames % 2 == 0) {
        const ImageError e = compareImages(half[0].resolve(), half[1].resolve());
        out.insert("halves_psnr_db", e.psnrDb);
        out.insert("own_psnr_db_estimate", e.psnrDb + 20 * std::log10(2.0));
    }
    if (o.text) {
        std::fprintf(o.text, "wrote %s (%dx%d, %dx%d samples per pixel x %d frames)\n", o.out.c_str(), s.width, s.height,
                     s.supersample, s.supersample, o.frames);
        if (auto e = out["own_psnr_db_estimate"].value<double>())
            std::fprintf(o.text, "its own error, from its two halves: about %.1f dB PSNR\n", *e);
    }
    return out;
}

}  // namespace rtwall::bench
