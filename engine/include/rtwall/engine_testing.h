// rtwall engine: test hooks. Nothing here is for a user of the engine; tests (and the CLI's
// --inject-tile-fault, which the tests drive) make failures happen on purpose with it, so that
// failure reports and their replays can be checked. engine.h names these types only through
// TraceOptions::fault, which is null outside tests.
#pragma once

#include <rtwall/engine.h>

#include <cstdint>
#include <memory>

namespace rtwall {

// The tile of `frame` that holds pixel (x, y) throws instead of rendering, as a bug or a failed
// allocation would.
struct InjectedTileFault {
    uint32_t frame = 0;
    int x = 0, y = 0;
};

// The TraceOptions::fault that fails `f`'s tile.
inline std::shared_ptr<const InjectedTileFault> injectFault(const InjectedTileFault& f) {
    return std::make_shared<const InjectedTileFault>(f);
}

}  // namespace rtwall
