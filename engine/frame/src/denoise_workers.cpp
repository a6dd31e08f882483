// DenoiseWorkerPool (rtwall/denoise.h): a copied Denoiser starts threads of its own.
#include "denoise_workers.h"

namespace rtwall {

DenoiseWorkerPool::DenoiseWorkerPool() = default;
DenoiseWorkerPool::DenoiseWorkerPool(const DenoiseWorkerPool&) {}
DenoiseWorkerPool& DenoiseWorkerPool::operator=(const DenoiseWorkerPool&) { return *this; }
DenoiseWorkerPool::DenoiseWorkerPool(DenoiseWorkerPool&&) noexcept = default;
DenoiseWorkerPool& DenoiseWorkerPool::operator=(DenoiseWorkerPool&&) noexcept = default;
DenoiseWorkerPool::~DenoiseWorkerPool() = default;

}  // namespace rtwall
