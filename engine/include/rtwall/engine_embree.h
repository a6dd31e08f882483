// Access to the Embree objects behind a Scene, for benchmarks that compare the engine with
// bare Embree loops and for tests. Applications do not need this header.
#pragma once

#include <rtwall/engine.h>

#include <embree3/rtcore.h>

namespace rtwall {

RTCScene embreeScene(const Scene& scene);

}  // namespace rtwall
