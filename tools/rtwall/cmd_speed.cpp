// Speed against accuracy (issue #8): the commands that measure both sides.
//   rtwall compare A.png B.png      error metrics and a false-colour difference image
//   rtwall reference SCENE          a converged reference image (many samples, lossless)
//   rtwall bench tiles SCENE        per-tile render/encode/decode times (a tile profile) and
//                                   every codec's error against a reference
//   rtwall simulate --profile P     the real TileScheduler against simulated clients and links
// The libraries do the work (rtwall::tune, rtwall::cluster); this file parses and prints.
#include "commands.h"
#include "tile_failure.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>
#include <rtwall/tune.h>
#include <rtwall/wall.h>

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numbers>
#include <sstream>

namespace rtwall::cli {

namespace {

const CameraDesc& pickCamera(const SceneDesc& desc, const std::string& scene, const std::string& name) {
    if (name.empty()) return desc.cameras.front();
    if (const CameraDesc* c = desc.findCamera(name)) return *c;
    throw InputError(scene + ": no camera named '" + name + "'");
}

// "jpeg:75" -> JPEG at quality 75; "zstd:3" -> zstd level 3; "lz4", "raw".
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

std::vector<std::string> splitList(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream ss(text);
    for (std::string item; std::getline(ss, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

// "100mbit", "1gbit", "10gbit", "2.5gbit", "800kbit", "0" or "unlimited" -> bits/s.
double parseRate(const std::string& text) {
    if (text == "0" || text == "unlimited") return 0;
    double v = 0;
    char unit[16] = {};
    if (std::sscanf(text.c_str(), "%lf%15s", &v, unit) < 1 || v <= 0)
        throw InputError("rate '" + text + "': expected e.g. 100mbit, 1gbit, 10gbit or unlimited");
    const std::string u(unit);
    if (u == "gbit") return v * 1e9;
    if (u == "mbit") return v * 1e6;
    if (u == "kbit") return v * 1e3;
    if (u == "bit" || u.empty()) return v;
    throw InputError("rate '" + text + "': unknown unit '" + u + "' (bit, kbit, mbit, gbit)");
}

toml::table errorTable(const ImageError& e) {
    return toml::table{{"rmse", e.rmse},        {"psnr_db", e.psnrDb}, {"ssim", e.ssim},       {"flip", e.flip},
                       {"max_error", e.maxError}, {"mean_abs_error", e.meanAbs}, {"identical", e.identical()}};
}

// The controls (rtwall/wall.h's table) as options of a command: a value given on the command line
// is applied to the scene as `rtwall run` applies a front's point.
struct ControlOptions {
    std::map<std::string, std::optional<double>> given;

    void add(CLI::App* cmd, std::initializer_list<std::string> only) {
        for (const Control& c : controls())
            if (*c.option && std::find(only.begin(), only.end(), c.name) != only.end())
                cmd->add_option(c.option, given[c.name], std::string(c.help) + " (overrides the scene)")->check(CLI::Range(c.min, c.max));
    }
    std::optional<double> value(const std::string& name) const {
        auto it = given.find(name);
        return it == given.end() ? std::nullopt : it->second;
    }
    // `desc.settings` at the wall's resolution on entry; the scale control makes it a fraction of it.
    void apply(SceneDesc& desc) const {
        OperatingPoint p;
        p.name = "the command line";
        for (const auto& [name, v] : given)
            if (v) p.controls.emplace_back(name, *v);
        const Knobs k = knobsOf(p, desc.settings, {});
        desc.settings = k.settings;
        if (k.volumeStep > 0)
            for (Material& m : desc.materials)
                if (m.type == MaterialType::Volume) m.volumeStep = k.volumeStep;
    }
};

double sum(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s;
}

}  // namespace

void addCompare(CLI::App& app, Run& run) {
    struct Options {
        std::string test, reference, diff;
        int scale = 0;
        bool json = false;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("compare", "Error of an image against a reference: RMSE, PSNR, SSIM, largest error");
    cmd->add_option("image", o->test, "The image to judge (PNG)")->required();
    cmd->add_option("reference", o->reference, "The reference (PNG, same size)")->required();
    cmd->add_option("--diff", o->diff, "Write a false-colour difference image (PNG)");
    cmd->add_option("--diff-scale", o->scale, "Error in levels shown as full red (default: the largest error)")
        ->check(CLI::Range(1, 255));
    cmd->add_flag("--json", o->json, "Print JSON");
    cmd->callback([&run, o] {
        run = [o] {
            const Image a = readPng(o->test), b = readPng(o->reference);
            if (a.width != b.width || a.height != b.height)
                throw InputError(o->test + " is " + std::to_string(a.width) + "x" + std::to_string(a.height) + " but " +
                                 o->reference + " is " + std::to_string(b.width) + "x" + std::to_string(b.height));
            const ImageError e = compareImages(a, b);
            if (!o->diff.empty()) writePng(differenceImage(a, b, o->scale), o->diff);
            if (o->json) {
                toml::table t = errorTable(e);
                t.insert("image", o->test);
                t.insert("reference", o->reference);
                t.insert("width", a.width);
                t.insert("height", a.height);
                t.insert("max_error_at", toml::array{e.maxX, e.maxY});
                t.insert("ssim_method", "mean SSIM of luminance (0.299 R + 0.587 G + 0.114 B), 11x11 Gaussian window, "
                                        "sigma 1.5, K1 0.01, K2 0.03, valid windows");
                t.insert("flip_method", "mean LDR-FLIP (Andersson et al. 2020), 67 pixels per degree, edges extended");
                if (!o->diff.empty()) t.insert("diff", o->diff);
                std::cout << toml::json_formatter{t} << "\n";
            } else {
                std::printf("%s against %s (%dx%d): RMSE %.3f levels, PSNR %s dB, SSIM %.5f, FLIP %.4f, largest error %d "
                            "levels at (%d, %d)%s\n",
                            o->test.c_str(), o->reference.c_str(), a.width, a.height, e.rmse,
                            e.identical() ? "inf" : std::to_string(e.psnrDb).c_str(), e.ssim, e.flip, e.maxError, e.maxX, e.maxY,
                            o->diff.empty() ? "" : (", difference in " + o->diff).c_str());
            }
            return 0;
        };
    });
}

void addReference(CLI::App& app, Run& run) {
    struct Options {
        std::string scene, out, camera;
        int width = 0, height = 0, threads = 0, frames = 1;
        uint32_t firstFrame = 1u << 20;  // independent of the frames the sweep renders (1, 2, ...)
        ControlOptions controls;
        int64_t triangles = 3'000'000;
        bool json = false;
        std::string progressOut;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand(
        "reference", "Render a converged reference image: many samples per pixel, on this PC (lossless, no cluster)");
    cmd->add_option("scene", o->scene, "Scene file (.toml), mesh file or builtin:NAME")->required();
    cmd->add_option("--out,-o", o->out, "Output PNG")->required();
    cmd->add_option("--width", o->width, "Image width (overrides the scene)")->check(CLI::Range(1, 16384));
    cmd->add_option("--height", o->height, "Image height (overrides the scene)")->check(CLI::Range(1, 16384));
    cmd->add_option("--camera", o->camera, "Scene camera (default: the first)");
    o->controls.add(cmd, {"supersample", "prune", "gi_spp", "volume_step"});  // supersample: 8 x 8 unless given
    cmd->add_option("--triangles", o->triangles, "Triangles of a builtin scene")->check(CLI::Range(int64_t(1000), int64_t(100'000'000)));
    cmd->add_option("--frames", o->frames,
                    "Average this many frames in linear light (path tracing jitters samples per frame; an even count "
                    "also reports the error between its two halves, an estimate of the reference's own error)")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--first-frame", o->firstFrame, "Frame number of the first frame (seeds its random numbers)");
    cmd->add_option("--progress-out", o->progressOut,
                    "Also write the mean of the first 1, 2, 4, 8, ... frames to PREFIX-N.png (progressive refinement)");
    cmd->add_flag("--json", o->json, "Print JSON");
    cmd->callback([&run, o] {
        run = [o] {
            SceneLoadOptions load;
            load.builtinTriangles = o->triangles;
            SceneDesc desc = loadScene(o->scene, load);
            RenderSettings& s = desc.settings;
            if (o->width) s.width = o->width;
            if (o->height) s.height = o->height;
            o->controls.apply(desc);
            s.supersample = int(o->controls.value("supersample").value_or(8));
            s.threads = o->threads;
            const CameraDesc cam = pickCamera(desc, o->scene, o->camera);
            const Scene scene(desc);
            const Camera camera(cam, s.width, s.height);
            // A tile that fails is reported with the command that renders it again.
            auto replayable = [&](auto&& render) {
                try {
                    return render();
                } catch (const TileError& e) {
                    throw withReplay(e, {o->scene, o->triangles, desc.origin, cam, s, {}, 0, {}});
                }
            };
            if (o->frames == 1 && o->progressOut.empty() && o->firstFrame == 1u << 20) {
                writePng(replayable([&] { return renderFrame(scene, camera, s); }), o->out);
                if (o->json) std::cout << toml::json_formatter{toml::table{{"out", o->out}, {"frames", 1}}} << "\n";
                else std::printf("wrote %s (%dx%d, %dx%d samples per pixel)\n", o->out.c_str(), s.width, s.height,
                                 s.supersample, s.supersample);
                return 0;
            }
            Accumulator all, half[2];
            for (int f = 0; f < o->frames; ++f) {
                const std::vector<float> linear =
                    replayable([&] { return renderFrameLinear(scene, camera, s, o->firstFrame + uint32_t(f)); });
                all.addLinear(linear.data(), s.width, s.height);
                half[2 * f < o->frames ? 0 : 1].addLinear(linear.data(), s.width, s.height);
                if (!o->progressOut.empty() && (all.frames() & (all.frames() - 1)) == 0)
                    writePng(all.resolve(), o->progressOut + "-" + std::to_string(all.frames()) + ".png");
            }
            writePng(all.resolve(), o->out);
            // Two independent halves: their difference has twice one half's variance, and the
            // whole has half of it, so the whole's own error is a quarter of the halves' squared
            // difference: 6.02 dB above their PSNR (noise only; a bias both share is not seen).
            toml::table out{{"out", o->out}, {"frames", o->frames}};
            if (o->frames % 2 == 0) {
                const ImageError e = compareImages(half[0].resolve(), half[1].resolve());
                out.insert("halves_psnr_db", e.psnrDb);
                out.insert("own_psnr_db_estimate", e.psnrDb + 20 * std::log10(2.0));
            }
            if (o->json) {
                std::cout << toml::json_formatter{out} << "\n";
            } else {
                std::printf("wrote %s (%dx%d, %dx%d samples per pixel x %d frames)\n", o->out.c_str(), s.width, s.height,
                            s.supersample, s.supersample, o->frames);
                if (auto e = out["own_psnr_db_estimate"].value<double>())
                    std::printf("its own error, from its two halves: about %.1f dB PSNR\n", *e);
            }
            return 0;
        };
    });
}

void addBenchTiles(CLI::App& bench, Run& run) {
    struct Options {
        std::string scene, camera, codecs = "raw,lz4,zstd,jpeg:50,jpeg:75,jpeg:90,jpeg:95", reference, profileOut, saveImage,
            shading;
        int width = 0, height = 0, frames = 1;
        double orbitDegrees = 1.0;
        ControlOptions controls;
        int64_t triangles = 3'000'000;
        bool json = false;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = bench.add_subcommand(
        "tiles", "Per-tile render, encode and decode times (a tile profile for 'rtwall simulate') and each codec's error");
    cmd->add_option("scene", o->scene, "Scene file (.toml), mesh file or builtin:NAME")->required();
    cmd->add_option("--width", o->width, "Wall image width (overrides the scene)")->check(CLI::Range(16, 16384));
    cmd->add_option("--height", o->height, "Wall image height (overrides the scene)")->check(CLI::Range(16, 16384));
    o->controls.add(cmd, {"scale", "tile", "supersample", "prune", "gi_spp", "volume_step"});  // scale: upscaled for the error
    cmd->add_option("--shading", o->shading, "full or eyelight (overrides the scene)")->check(CLI::IsMember({"full", "eyelight"}));
    cmd->add_option("--camera", o->camera, "Scene camera (default: the first)");
    cmd->add_option("--frames", o->frames, "Frames to time, the camera orbiting --orbit degrees per frame")->check(CLI::Range(1, 1000));
    cmd->add_option("--orbit", o->orbitDegrees, "Degrees per frame around the camera's look-at point")->check(CLI::Range(-360.0, 360.0));
    cmd->add_option("--codecs", o->codecs, "Comma-separated codecs: raw, lz4, zstd[:LEVEL], jpeg[:QUALITY]");
    cmd->add_option("--reference", o->reference, "Reference PNG at the wall's resolution (rtwall reference): errors are reported");
    cmd->add_option("--profile-out", o->profileOut, "Write the tile profile (TOML) for 'rtwall simulate'");
    cmd->add_option("--save-image", o->saveImage, "Write frame 0 as rendered (lossless, at the render resolution)");
    cmd->add_option("--triangles", o->triangles, "Triangles of a builtin scene")->check(CLI::Range(int64_t(1000), int64_t(100'000'000)));
    cmd->add_flag("--json", o->json, "Print JSON");
    cmd->callback([&run, o] {
        run = [o] {
            SceneLoadOptions load;
            load.builtinTriangles = o->triangles;
            SceneDesc desc = loadScene(o->scene, load);
            RenderSettings& s = desc.settings;
            if (o->width) s.width = o->width;
            if (o->height) s.height = o->height;
            const int wallW = s.width, wallH = s.height;
            o->controls.apply(desc);
            if (!o->shading.empty()) s.shading = o->shading == "eyelight" ? ShadingMode::EyeLight : ShadingMode::Full;
            s.threads = 1;
            std::vector<CodecSettings> codecs;
            for (const std::string& c : splitList(o->codecs)) codecs.push_back(parseCodec(c));
            if (codecs.empty()) throw InputError("--codecs: no codec given");
            std::optional<Image> reference;
            if (!o->reference.empty()) {
                reference = readPng(o->reference);
                if (reference->width != wallW || reference->height != wallH)
                    throw InputError(o->reference + " is " + std::to_string(reference->width) + "x" +
                                     std::to_string(reference->height) + ", the wall " + std::to_string(wallW) + "x" +
                                     std::to_string(wallH));
            }
            const CameraDesc start = pickCamera(desc, o->scene, o->camera);
            std::vector<CameraDesc> cameras;
            for (int f = 0; f < o->frames; ++f) cameras.push_back(orbitCamera(start, o->orbitDegrees * f));
            const Scene scene(desc);
            Image lossless;
            std::vector<Image> decoded;
            TileProfile profile;
            try {
                profile = profileTiles(scene, cameras, s, codecs, &lossless, &decoded);
            } catch (const TileError& e) {
                // Frame f + 1 is cameras[f] (frame 1's eye-light warm-up pass is reported as frame 1).
                const size_t f = std::min<size_t>(std::max<uint32_t>(e.frame(), 1) - 1, cameras.size() - 1);
                throw withReplay(e, {o->scene, o->triangles, desc.origin, cameras[f], s, {}, 0, {}});
            }
            profile.scene = o->scene;
            if (!o->profileOut.empty()) writeTileProfile(profile, o->profileOut);
            if (!o->saveImage.empty()) writePng(lossless, o->saveImage);

            std::vector<double> frameRender;
            for (const auto& f : profile.renderSeconds) frameRender.push_back(sum(f));
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
                if (!o->json)
                    std::printf("%-8s %8.3f MB/frame, encode %.3f s, decode %.3f s%s\n", codecLabel(codecs[i]).c_str(),
                                bytes * 1e-6, sum(cc.encodeSeconds), sum(cc.decodeSeconds),
                                reference ? (", PSNR " + std::to_string((*row["error"].as_table())["psnr_db"].value_or(0.0)) +
                                             " dB").c_str()
                                          : "");
                rows.push_back(std::move(row));
            }
            toml::array renderArray;
            for (double r : frameRender) renderArray.push_back(r);
            if (o->json) {
                toml::table out{{"benchmark", "tiles"},
                                {"scene", o->scene},
                                {"wall_width", wallW},
                                {"wall_height", wallH},
                                {"width", s.width},
                                {"height", s.height},
                                {"scale", o->controls.value("scale").value_or(1.0)},
                                {"tile", s.tileSize},
                                {"supersample", s.supersample},
                                {"tiles", int64_t(profile.tileCount())},
                                {"render_s_per_frame", renderArray},
                                {"codecs", rows}};
                if (!o->profileOut.empty()) out.insert("profile", o->profileOut);
                std::cout << toml::json_formatter{out} << "\n";
            } else {
                std::printf("%s at %dx%d (wall %dx%d), tile %d, %dx%d samples: %zu tiles, %.3f s per frame on one thread\n",
                            o->scene.c_str(), s.width, s.height, wallW, wallH, s.tileSize, s.supersample, s.supersample,
                            profile.tileCount(), frameRender.front());
            }
            return 0;
        };
    });
}

void addBenchCodecs(CLI::App& bench, Run& run) {
    struct Options {
        std::string image, codecs = "lz4,zstd,jpeg:50,jpeg:75,jpeg:90,jpeg:95", diffDir;
        int tile = 64;
        bool json = false;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = bench.add_subcommand("codecs", "Size and error of any image (PNG) through each tile codec");
    cmd->add_option("image", o->image, "The image (PNG)")->required();
    cmd->add_option("--codecs", o->codecs, "Comma-separated codecs: raw, lz4, zstd[:LEVEL], jpeg[:QUALITY]");
    cmd->add_option("--tile", o->tile, "Tile size")->check(CLI::Range(4, 1024));
    cmd->add_option("--diff-dir", o->diffDir, "Write each codec's decoded image and false-colour difference here");
    cmd->add_flag("--json", o->json, "Print JSON");
    cmd->callback([&run, o] {
        run = [o] {
            const Image img = readPng(o->image);
            toml::array rows;
            for (const std::string& c : splitList(o->codecs)) {
                const CodecSettings cs = parseCodec(c);
                uint64_t bytes = 0;
                const Image out = codecRoundTrip(img, o->tile, cs, &bytes);
                const ImageError e = compareImages(out, img);
                if (!o->diffDir.empty()) {
                    std::string stem = codecLabel(cs);
                    for (char& ch : stem) if (ch == ':') ch = '_';
                    writePng(out, std::filesystem::path(o->diffDir) / (stem + ".png"));
                    writePng(differenceImage(out, img, 32), std::filesystem::path(o->diffDir) / (stem + "_diff.png"));
                }
                toml::table row{{"codec", codecLabel(cs)}, {"bytes", int64_t(bytes)},
                                {"bits_per_pixel", 8.0 * double(bytes) / (double(img.width) * img.height)},
                                {"error", errorTable(e)}};
                if (!o->json)
                    std::printf("%-8s %9llu bytes (%.2f bit/pixel), PSNR %6.2f dB, SSIM %.4f, largest error %d\n",
                                codecLabel(cs).c_str(), (unsigned long long)bytes,
                                8.0 * double(bytes) / (double(img.width) * img.height), e.psnrDb, e.ssim, e.maxError);
                rows.push_back(std::move(row));
            }
            if (o->json) {
                toml::table out{{"benchmark", "codecs"}, {"image", o->image}, {"width", img.width},
                                {"height", img.height}, {"tile", o->tile}, {"codecs", rows}};
                std::cout << toml::json_formatter{out} << "\n";
            }
            return 0;
        };
    });
}

void addSimulate(CLI::App& app, Run& run) {
    struct Options {
        std::string profile, codec, clients = "1,2,4,8,16,32,64,128,256", clientLink = "100mbit", masterLink = "1gbit";
        int threads = 1, prefetch = 4, frames = 10, decodeThreads = 2, overhead = 40;
        double hostCores = 0;
        double clientUsPerResult = 0, clientNsPerByte = 0, masterUsPerResult = 0, masterNsPerByte = 0, masterMsPerFrame = 0;
        double latencyMs = 0.1, hostLoad = 0, spikeProb = 0, spikeMs = 0, masterUs = 28, clientSpeed = 1, decodeSpeed = 1, straggler = 4;
        bool noAffinity = false, json = false;
        uint64_t seed = 1;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("simulate", "Frames/s, utilisation and link load of N clients: the real tile scheduler "
                                                   "against simulated clients and links, fed with a tile profile");
    cmd->add_option("--profile", o->profile, "Tile profile (rtwall bench tiles --profile-out)")->required();
    cmd->add_option("--codec", o->codec, "Which of the profile's codecs, e.g. lz4 or jpeg:75 (default: the first)");
    cmd->add_option("--clients", o->clients, "Comma-separated client counts");
    cmd->add_option("--threads", o->threads, "Render threads per client")->check(CLI::Range(1, 1024));
    cmd->add_option("--client-speed", o->clientSpeed, "Client speed relative to the PC that recorded the profile")->check(CLI::Range(0.001, 1000.0));
    cmd->add_option("--prefetch", o->prefetch, "Tiles each client keeps in flight")->check(CLI::Range(1, 64));
    cmd->add_flag("--no-affinity", o->noAffinity, "Tiles start in the shared queue every frame");
    cmd->add_option("--straggler-factor", o->straggler, "Re-issue tiles outstanding this many median latencies")->check(CLI::Range(1.0, 1000.0));
    cmd->add_option("--client-link", o->clientLink, "Each client's link: 100mbit, 1gbit, 10gbit, unlimited");
    cmd->add_option("--master-link", o->masterLink, "The master's uplink, shared by all results");
    cmd->add_option("--latency-ms", o->latencyMs, "One-way latency of every link")->check(CLI::Range(0.0, 10000.0));
    cmd->add_option("--spike-probability", o->spikeProb, "Chance that a message is delayed by --spike-ms")->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--spike-ms", o->spikeMs, "Extra delay of a spiking message")->check(CLI::Range(0.0, 100000.0));
    cmd->add_option("--master-us-per-message", o->masterUs, "Master network thread's cost per message (µs)")->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--decode-threads", o->decodeThreads, "Master decode threads")->check(CLI::Range(1, 1024));
    cmd->add_option("--decode-speed", o->decodeSpeed, "Master decode speed relative to the recording PC")->check(CLI::Range(0.001, 1000.0));
    cmd->add_option("--overhead-bytes", o->overhead, "Protocol bytes per result message")->check(CLI::Range(0, 100000));
    cmd->add_option("--host-cores", o->hostCores,
                    "Clients and master share this many cores (local clients on one PC); 0: each has its own")
        ->check(CLI::Range(0.0, 100000.0));
    cmd->add_option("--host-load", o->hostLoad, "With --host-cores: other jobs' runnable threads on those cores")
        ->check(CLI::Range(0.0, 100000.0));
    // Host costs besides rendering, from `rtwall bench cluster --json` (cpu_per_frame); see
    // docs/speed-accuracy.md, Validation, for how they are measured and calibrated.
    cmd->add_option("--client-us-per-result", o->clientUsPerResult,
                    "A client's CPU per result outside its render threads (network, ZeroMQ, kernel TCP), µs")
        ->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--client-ns-per-byte", o->clientNsPerByte, "... and per result byte, ns")->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--master-us-per-result", o->masterUsPerResult,
                    "The master's CPU per result before its network thread (ZeroMQ I/O thread, kernel TCP), µs")
        ->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--master-ns-per-byte", o->masterNsPerByte, "... and per result byte, ns")->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--master-ms-per-frame", o->masterMsPerFrame, "The master's CPU per frame after the last decode, ms")
        ->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--frames", o->frames, "Simulated frames per client count (after one warm-up frame)")->check(CLI::Range(1, 100000));
    cmd->add_option("--seed", o->seed, "Seed for latency spikes and steal victims");
    cmd->add_flag("--json", o->json, "Print JSON");
    cmd->callback([&run, o] {
        run = [o] {
            const TileProfile profile = readTileProfile(o->profile);
            SimConfig cfg;
            if (!o->codec.empty()) {
                const CodecSettings want = parseCodec(o->codec);
                bool found = false;
                for (size_t i = 0; i < profile.codecs.size() && !found; ++i)
                    if (codecLabel(profile.codecs[i].codec) == codecLabel(want)) {
                        cfg.codec = i;
                        found = true;
                    }
                if (!found) throw InputError(o->profile + ": the profile has no codec '" + o->codec + "'");
            }
            cfg.threadsPerClient = o->threads;
            cfg.clientSpeed = o->clientSpeed;
            cfg.prefetch = o->prefetch;
            cfg.affinity = !o->noAffinity;
            cfg.stragglerFactor = o->straggler;
            cfg.clientLink = {parseRate(o->clientLink), o->latencyMs * 1e-3, o->spikeProb, o->spikeMs * 1e-3};
            cfg.masterBitsPerSecond = parseRate(o->masterLink);
            cfg.masterSecondsPerMessage = o->masterUs * 1e-6;
            cfg.decodeThreads = o->decodeThreads;
            cfg.decodeSpeed = o->decodeSpeed;
            cfg.messageOverheadBytes = uint32_t(o->overhead);
            cfg.frames = o->frames;
            cfg.seed = o->seed;
            cfg.hostCores = o->hostCores;
            cfg.hostBackgroundThreads = o->hostLoad;
            cfg.clientSecondsPerResult = o->clientUsPerResult * 1e-6;
            cfg.clientSecondsPerByte = o->clientNsPerByte * 1e-9;
            cfg.masterSecondsPerResult = o->masterUsPerResult * 1e-6;
            cfg.masterSecondsPerByte = o->masterNsPerByte * 1e-9;
            cfg.masterSecondsPerFrame = o->masterMsPerFrame * 1e-3;
            double bytes = 0, render = 0;
            for (uint32_t b : profile.codecs[cfg.codec].bytes) bytes += b + o->overhead;
            for (double r : profile.renderSeconds.front()) render += r;
            toml::array rows;
            for (const std::string& n : splitList(o->clients)) {
                int clients = 0;
                if (std::sscanf(n.c_str(), "%d", &clients) != 1 || clients < 1 || clients > 100000)
                    throw InputError("--clients: '" + n + "' is not a client count");
                cfg.clients = clients;
                const SimReport r = simulateCluster(profile, cfg);
                // The link-bound ceiling: results of one frame over the master's link, or over
                // all client links together, whichever is slower.
                double ceiling = 0;
                if (cfg.masterBitsPerSecond > 0) ceiling = cfg.masterBitsPerSecond / (8 * bytes);
                if (cfg.clientLink.bitsPerSecond > 0) {
                    const double c = clients * cfg.clientLink.bitsPerSecond / (8 * bytes);
                    ceiling = ceiling > 0 ? std::min(ceiling, c) : c;
                }
                toml::table row{{"clients", clients},
                                {"fps", r.fps},
                                {"link_ceiling_fps", ceiling},
                                {"render_bound_fps", clients * o->threads * o->clientSpeed / render},
                                {"bytes_per_frame", r.bytesPerFrame},
                                {"master_link_load", r.masterLinkLoad},
                                {"max_client_link_load", r.maxClientLinkLoad},
                                {"master_cpu_load", r.masterCpuLoad},
                                {"mean_client_utilisation", r.meanUtilisation},
                                {"stolen_per_frame", r.stolenPerFrame},
                                {"reissued_per_frame", r.reissuedPerFrame},
                                {"affinity_hit_fraction", r.affinityHitFraction}};
                if (!o->json)
                    std::printf("%4d clients: %8.2f fps (link ceiling %8.2f), master link %5.1f%%, clients busy %5.1f%%, "
                                "%.1f stolen/frame\n",
                                clients, r.fps, ceiling, 100 * r.masterLinkLoad, 100 * r.meanUtilisation, r.stolenPerFrame);
                rows.push_back(std::move(row));
            }
            if (o->json) {
                toml::table out{{"benchmark", "simulate"},      {"profile", o->profile},
                                {"codec", codecLabel(profile.codecs[cfg.codec].codec)},
                                {"client_link_bps", cfg.clientLink.bitsPerSecond},
                                {"master_link_bps", cfg.masterBitsPerSecond},
                                {"latency_ms", o->latencyMs},   {"prefetch", o->prefetch},
                                {"threads", o->threads},        {"affinity", !o->noAffinity},
                                {"results", rows}};
                std::cout << toml::json_formatter{out} << "\n";
            }
            return 0;
        };
    });
}

}  // namespace rtwall::cli
