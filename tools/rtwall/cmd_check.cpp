// rtwall check CONFIG: validates a wall config and compiles every shader it uses with glslang,
// before any window opens. Exit status 1 and one line per problem when anything is wrong.
#include "commands.h"

#include <rtwall/display.h>

#include <cstdio>
#include <memory>
#include <string>

namespace rtwall::cli {

void addCheck(CLI::App& app, Run& run) {
    addCommandOfOneArgument(
        app, run, "check", "Validate a wall config, compile its shaders (glslang) and check its projector calibration ([warp])", "config",
        "Wall config (.toml, see configs/README.md)", [](const std::string& config) {
            const std::vector<std::string> problems = checkWall(config);  // config problems throw InputError
            for (const std::string& p : problems) std::fprintf(stderr, "rtwall: error: %s\n", p.c_str());
            if (!problems.empty()) return 1;
            const WallConfig wall = loadWallConfig(config);
            // With display nodes, which node drives which screens: what an installer wires up.
            std::string nodes;
            for (const std::string& n : wall.nodes()) {
                nodes += (nodes.empty() ? "; display nodes: " : "; ") + n + ":";
                for (const ScreenConfig& s : wall.screens)
                    if (s.node == n) nodes += " " + s.name;
            }
            // With [warp], the calibration that was checked against the screens.
            std::string warp;
            if (wall.warp)
                warp = "; warp (" + std::string(wall.warp->mode == WarpMode::Post ? "post" : "direct") + "): " +
                       std::to_string(wall.warp->buffers.size()) + " projector" + (wall.warp->buffers.size() == 1 ? "" : "s") +
                       " of " + wall.warp->mpcdi.filename().string();
            std::printf("%s: ok: '%s', %dx%d wall pixels, %zu screen%s, shaders compile%s%s\n", config.c_str(), wall.name.c_str(),
                        wall.width, wall.height, wall.screens.size(), wall.screens.size() == 1 ? "" : "s", nodes.c_str(),
                        warp.c_str());
            return 0;
        });
}

}  // namespace rtwall::cli
