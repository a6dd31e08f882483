// rtwall check CONFIG: validates a wall config and compiles every shader it uses with glslang,
// before any window opens. Exit status 1 and one line per problem when anything is wrong.
#include "commands.h"

#include <rtwall/display.h>

#include <cstdio>
#include <memory>

namespace rtwall::cli {

void addCheck(CLI::App& app, Run& run) {
    auto config = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("check", "Validate a wall config and compile its shaders (glslang)");
    cmd->add_option("config", *config, "Wall config (.toml, see configs/README.md)")->required();
    cmd->callback([&run, config] {
        run = [config] {
            const std::vector<std::string> problems = checkWall(*config);  // config problems throw InputError
            for (const std::string& p : problems) std::fprintf(stderr, "rtwall: error: %s\n", p.c_str());
            if (!problems.empty()) return 1;
            const WallConfig wall = loadWallConfig(*config);
            std::printf("%s: ok: '%s', %dx%d wall pixels, %zu screen%s, shaders compile\n", config->c_str(), wall.name.c_str(),
                        wall.width, wall.height, wall.screens.size(), wall.screens.size() == 1 ? "" : "s");
            return 0;
        };
    });
}

}  // namespace rtwall::cli
