// rtwall cluster: test hooks. Nothing here is for a user of the cluster; the tests of faults,
// freezes and recovery make a master or a render client misbehave on purpose with it (a slow or
// lossy link, a slow PC, a tile that throws, a render thread that hangs). cluster.h names these
// types only through ClusterSettings::faults and ClientSettings::faults, which are null outside
// tests; the engine's own hook (InjectedTileFault) is in rtwall/engine_testing.h.
#pragma once

#include <rtwall/cluster.h>
#include <rtwall/engine_testing.h>

#include <cstdint>
#include <optional>

namespace rtwall {

// What a master does wrong on purpose (ClusterSettings::faults).
struct MasterFaults {
    int dropEveryNthUpdate = 0;  // lose every Nth update message per client (Master::injectedUpdateLosses counts them)
    int consumeDelayUs = 0;      // the network thread pauses this long per received message (a slow display PC)
};

// What a render client does wrong on purpose (ClientSettings::faults).
struct ClientFaults {
    int extraTileDelayMs = 0;    // emulate a slower PC
    int extraSceneBuildMs = 0;   // a PC slow to build the scene
    int dropEveryNthResult = 0;  // lose every Nth tile result on its way out
    int corruptEveryNthDepth = 0;  // cut every Nth tile's encoded depth in half (it no longer decodes)
    std::optional<InjectedTileFault> tileFault{};  // a tile that throws
    // A render thread that does not return: the first tile of frame stallFrame or later that this
    // client renders sleeps stallMs on its thread (once; cut short when the client stops).
    int stallMs = 0;
    uint32_t stallFrame = 0;
};

}  // namespace rtwall
