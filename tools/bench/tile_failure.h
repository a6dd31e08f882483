// A tile that failed, as the commands that render say it: one line with the frame, the tile,
// why, and the command line that renders that tile again on its own.
#pragma once

#include <rtwall/engine.h>

#include <stdexcept>
#include <string>

namespace rtwall::bench {

// `replay` holds the scene, camera and settings that were rendered; the frame and the tile
// come from the error.
inline std::runtime_error withReplay(const TileError& e, TileReplay replay) {
    replay.frame = e.frame();
    replay.rect = e.rect();
    return std::runtime_error(std::string(e.what()) + " (replay: " + replayCommand(replay) + ")");
}

}  // namespace rtwall::bench
