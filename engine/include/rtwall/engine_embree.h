// Access to the Embree objects behind a Scene, for benchmarks that compare the engine with
// bare Embree loops and for tests. Applications do not need this header.
#pragma once

#include <rtwall/engine.h>

#include <embree3/rtcore.h>

namespace rtwall {

RTCScene embreeScene(const Scene& scene);

// Whether the scene's shadow packets ask Embree for its coherent occlusion traversal (off where
// Embree runs its AVX-512 kernels: that path can hang there; kernel.cpp says why).
bool coherentOcclusion(const Scene& scene);

}  // namespace rtwall
