// Speed against accuracy (issue #8): the work behind the commands that measure both sides.
//   rtwall compare A.png B.png      error metrics and a false-colour difference image
//   rtwall reference SCENE          a converged reference image (many samples, lossless)
//   rtwall bench tiles SCENE        per-tile render/encode/decode times (a tile profile) and
//                                   every codec's error against a reference
//   rtwall bench codecs IMAGE       size and error of any image through each tile codec
//   rtwall simulate --profile P     the real TileScheduler against simulated clients and links
// As in bench.h: one options struct and one function each, lines to `text` as they go, the
// JSON that --json prints as the result. The libraries do the measuring (rtwall::tune,
// rtwall::cluster).
#pragma once

#include "bench.h"

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <map>
#include <optional>
#include <string>

namespace rtwall::bench {

// "jpeg:75" -> JPEG at quality 75; "zstd:3" -> zstd level 3; "lz4", "raw".
CodecSettings parseCodec(const std::string& text);
// The inverse: "jpeg:75", "zstd:3", "lz4" ("zstd" at the default level 1).
std::string codecLabel(const CodecSettings& cs);

// Values of the controls (rtwall/wall.h's table) given on a command line, by control name: a
// value given is applied to the scene as `rtwall run` applies a front's point.
struct ControlValues {
    std::map<std::string, std::optional<double>> given;

    std::optional<double> value(const std::string& name) const;
    // `desc.settings` at the wall's resolution on entry; the scale control makes it a fraction of it.
    void apply(SceneDesc& desc) const;
};

struct CompareOptions : Common {
    std::string test, reference, diff;
    int scale = 0;  // error in levels shown as full red in `diff` (0: the largest error)
};
toml::table compare(const CompareOptions& o);

struct ReferenceOptions : Common {
    std::string scene, out, camera;
    int width = 0, height = 0, threads = 0, frames = 1;
    uint32_t firstFrame = 1u << 20;  // independent of the frames the sweep renders (1, 2, ...)
    ControlValues controls;          // supersample: 8 x 8 unless given
    int64_t triangles = 3'000'000;
    std::string progressOut;
};
toml::table reference(const ReferenceOptions& o);

struct TilesOptions : Common {
    std::string scene, camera, codecs = "raw,lz4,zstd,jpeg:50,jpeg:75,jpeg:90,jpeg:95", reference, profileOut, saveImage,
        shading;
    int width = 0, height = 0, frames = 1;
    double orbitDegrees = 1.0;
    ControlValues controls;
    int64_t triangles = 3'000'000;
    // With the denoise control: the frames of the orbit that arrives at the scored view, and its
    // speed (the filter's temporal reuse needs a history; issue 28).
    int denoiseFrames = 8;
    double denoiseDegrees = 0.5;
};
toml::table tiles(const TilesOptions& o);

struct CodecsOptions : Common {
    std::string image, codecs = "lz4,zstd,jpeg:50,jpeg:75,jpeg:90,jpeg:95", diffDir;
    int tile = 64;
};
toml::table codecs(const CodecsOptions& o);

struct SimulateOptions : Common {
    std::string profile, codec, clients = "1,2,4,8,16,32,64,128,256", clientLink = "100mbit", masterLink = "1gbit";
    int threads = 1, prefetch = 4, frames = 10, decodeThreads = 2, overhead = 40;
    double hostCores = 0;
    double clientUsPerResult = 0, clientNsPerByte = 0, masterUsPerResult = 0, masterNsPerByte = 0, masterMsPerFrame = 0;
    double latencyMs = 0.1, hostLoad = 0, spikeProb = 0, spikeMs = 0, masterUs = 28, clientSpeed = 1, decodeSpeed = 1, straggler = 4;
    bool noAffinity = false;
    uint64_t seed = 1;
    int displayNodes = 0, nodeDecodeThreads = 1;  // > 0: a wall split into that many column runs (columnNodeMasks)
    std::string nodeLink = "1gbit";                // each display node's link
};
toml::table simulate(const SimulateOptions& o);

}  // namespace rtwall::bench
