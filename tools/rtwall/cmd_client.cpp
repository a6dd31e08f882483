#include "commands.h"

#include <rtwall/cluster.h>

#include <cstdio>
#include <memory>

namespace rtwall::cli {

void addClient(CLI::App& app, Run& run) {
    auto o = std::make_shared<ClientSettings>();
    CLI::App* cmd = app.add_subcommand("client", "Join a master as a render client");
    cmd->add_option("--connect", o->connect, "The master's endpoint, tcp://HOST:PORT")->required();
    cmd->add_option("--threads", o->threads, "Render threads (0 = one per hardware thread)")->check(CLI::Range(0, 1024));
    cmd->add_option("--packet-width", o->packetWidth, "Rays per Embree packet (0 = this CPU's widest; 4, 8, 16 force one)")
        ->check(CLI::IsMember({0, 4, 8, 16}));
    cmd->add_option("--cache", o->cacheDir, "Directory for meshes, textures and volumes received from the master (by content hash)");
    cmd->add_option("--exit-after-idle", o->exitAfterIdleMs, "Exit when the master says goodbye or none answers for this many ms (0 = wait for a master forever)")
        ->check(CLI::Range(0, 86'400'000));
    cmd->add_option("--max-reconnect", o->maxReconnectMs, "Longest pause between reconnection attempts, in ms (jittered, doubling from 100)")
        ->check(CLI::Range(100, 3'600'000));
    cmd->add_option("--key", o->keyFile, "This client's CURVE key pair (rtwall keys): encrypt and authenticate");
    cmd->add_option("--server-key", o->serverKeyFile, "The master's public key file; the client checks the master with it");
    cmd->add_flag("--replay", o->replay, "Benchmarks: render each tile once, then resend its bytes (measures master and link)");
    cmd->callback([&run, o] {
        run = [o] {
            if (!o->connect.starts_with("tcp://")) throw InputError("--connect '" + o->connect + "': expected tcp://HOST:PORT");
            return runClient(*o);
        };
    });
}

void addKeys(CLI::App& app, Run& run) {
    addCommandOfOneArgument(app, run, "keys", "Make a CURVE key pair: STEM.key (secret, mode 0600) and STEM.pub", "stem",
                            "Path without extension, e.g. keys/master", [](const std::string& stem) {
                                writeNewKeyPair(stem);
                                std::printf("wrote %s.key (keep it secret) and %s.pub\n", stem.c_str(), stem.c_str());
                                return 0;
                            });
}

}  // namespace rtwall::cli
