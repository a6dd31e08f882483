// Helpers shared by the test programs.
#pragma once

#include "scratch.h"

#include <rtwall/engine.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace rtwall::test {

// A camera at `position` looking at `lookAt`.
inline CameraDesc cameraAt(Float3 position, Float3 lookAt, float fovY = 45.0f, Float3 up = {0, 1, 0}) {
    return CameraDesc{.position = position, .lookAt = lookAt, .up = up, .fovY = fovY, .window = {}};
}

// The image size and tile size of `settings`.
inline void setImage(RenderSettings& settings, int width, int height, int tileSize) {
    settings.width = width;
    settings.height = height;
    settings.tileSize = tileSize;
}

// `d` seen from its first camera, rendered on this machine (`frame` of a stochastic render): what
// a cluster or a wall showing the same scene must give, byte for byte.
inline Image renderFirstCamera(const SceneDesc& d, uint32_t frame = 0) {
    const Scene scene(d);
    return renderFrame(scene, Camera(d.cameras.front(), d.settings.width, d.settings.height), d.settings, frame);
}

// The |z| above which one of `tests` independent two-sided z-tests fails, for an overall level
// `alpha` (Sidak correction): the normal quantile by bisection on erfc (about 3.9 for 144 tests
// at 0.01).
inline double sidakThreshold(double alpha, size_t tests) {
    const double perTest = 1.0 - std::pow(1.0 - alpha, 1.0 / double(tests));
    double lo = 0, hi = 10;
    for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (std::erfc(mid / std::sqrt(2.0)) > perTest ? lo : hi) = mid;
    }
    return lo;
}

// configs/demo.toml at width x height; `supersample` 0 keeps the file's.
inline SceneDesc demoScene(int width, int height, int supersample = 0) {
    SceneDesc desc = loadSceneFile(sourceDir() / "configs/demo.toml");
    desc.settings.width = width;
    desc.settings.height = height;
    if (supersample > 0) desc.settings.supersample = supersample;
    return desc;
}

// Runs f, expects an InputError, returns its message.
template <class F> std::string inputErrorOf(F&& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an InputError";
    return {};
}

}  // namespace rtwall::test
