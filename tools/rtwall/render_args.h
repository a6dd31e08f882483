// `rtwall render`'s options and what they mean for the scene, the camera and the tracing.
#pragma once

#include <rtwall/engine.h>

#include <cstdint>
#include <string>

namespace rtwall::cli {

struct RenderOptions {
    std::string scene, out, camera, kernel, region, codec = "lz4", view, shading, shadows;
    std::string cameraPosition, cameraLookAt, cameraUp, cameraWindow, background, ambient, fault, denoise, denoiseIsa;
    int width = 0, height = 0, threads = -1, tile = 0, clients = 0, prefetch = 4;
    int samples = 0, maxDepth = 0, frames = 1, packetWidth = 0, supersample = 0;
    int64_t frame = -1, clientId = -1, triangles = 3'000'000;
    double prune = -1, fov = 0;
    double deflection = 0.1, angularDeflection = 0.5;  // STEP/IGES tessellation
    bool gi = false, noGi = false, cache = false;
    PartView parts;  // --hide, --isolate, --highlight
};


// The scene's settings with what the options override.
void applyOverrides(RenderSettings& s, const RenderOptions& o);
// How this process traces: packet width, the client id the client view shows, an injected fault.
TraceOptions traceOptionsOf(const RenderOptions& o);
// The camera: a scene camera by name (or the first), with what the options give instead.
CameraDesc chooseCamera(const SceneDesc& desc, const RenderOptions& o);
// --region "x0,y0,x1,y1" inside the image.
TileRect parseRegion(const std::string& text, const RenderSettings& s);

}  // namespace rtwall::cli
