#include "commands.h"

#include <rtwall/wall.h>

#include <atomic>
#include <csignal>
#include <memory>

namespace rtwall::cli {

namespace {
std::atomic<bool> gStopNode{false};
}

void addDisplay(CLI::App& app, Run& run) {
    auto o = std::make_shared<DisplayNodeOptions>();
    auto isa = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("display", "Run one display node of a wall on several PCs (the screens its wall config gives it)");
    cmd->add_option("--connect", o->connect, "The master's endpoint, tcp://HOST:PORT")->required();
    cmd->add_option("--node", o->name, "This node's name in the wall config (node = \"...\" or [[node]] name)")->required();
    cmd->add_option("--bind", o->bind, "Where the render clients send this node's tiles (port 0: a free one)");
    cmd->add_option("--advertise", o->advertise,
                    "The host the render clients reach this node at (default: the --bind address; required when it is 0.0.0.0 or *)");
    cmd->add_option("--key", o->keyFile, "This node's CURVE key pair (rtwall keys): encrypt and authenticate, as rtwall client --key");
    cmd->add_option("--server-key", o->serverKeyFile, "The master's public key file; the node checks the master with it");
    cmd->add_flag("--headless", o->headless, "Write the screens as images instead of opening windows");
    cmd->add_option("--out", o->out, "Folder for the headless screens");
    cmd->add_option("--capture", o->capture, "Tests: in windows, also write each presented frame's screens as read back from OpenGL to this folder");
    cmd->add_option("--frames", o->frames, "Exit after presenting this many frames (0: until the master ends)")->check(CLI::Range(0, 1 << 30));
    cmd->add_option("--exit-after-idle", o->exitAfterIdleMs, "Exit when no master answers for this many ms (0: wait for ever)")
        ->check(CLI::Range(0, 86'400'000));
    addDenoiseIsaOption(cmd, *isa);
    cmd->callback([&run, o, isa] {
        run = [o, isa] {
            applyDenoiseIsa(*isa);
            if (!o->connect.starts_with("tcp://")) throw InputError("--connect '" + o->connect + "': expected tcp://HOST:PORT");
            if (!o->bind.starts_with("tcp://")) throw InputError("--bind '" + o->bind + "': expected tcp://HOST:PORT");
            std::signal(SIGINT, [](int) { gStopNode = true; });
            std::signal(SIGTERM, [](int) { gStopNode = true; });
            return runWallNode(*o, &gStopNode);
        };
    });
}

}  // namespace rtwall::cli
