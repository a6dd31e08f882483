// rtwall tracker-sim PATH: plays a head path as ART DTrack datagrams to a port on 127.0.0.1 (and
// nowhere else), for demos, tests and benchmarks of a tracked wall without a tracker.
#include "commands.h"

#include <rtwall/tracking.h>

#include <csignal>
#include <cstdio>
#include <memory>

namespace rtwall::cli {

namespace {
std::atomic<bool> simStop{false};
extern "C" void onSimSignal(int) { simStop = true; }
}  // namespace

void addTrackerSim(CLI::App& app, Run& run) {
    struct Options {
        std::string path;
        int port = 5000;
        double rate = 60;
        double seconds = 0;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("tracker-sim", "Play a head path as DTrack datagrams to 127.0.0.1 (a tracker simulator)");
    cmd->add_option("path", o->path, "Head path (.toml, configs/README.md \"Head paths\"), e.g. configs/wall/paths/stroll.toml")->required();
    cmd->add_option("--port", o->port, "UDP port on 127.0.0.1 (the wall's [tracking] source port)")->check(CLI::Range(1, 65535));
    cmd->add_option("--rate", o->rate, "Frames per second (DTrack runs at 60 to 300)")->check(CLI::Range(0.1, 10000.0));
    cmd->add_option("--seconds", o->seconds, "How long to play, looping the path (0: until Ctrl-C)")->check(CLI::Range(0.0, 1e7));
    cmd->callback([&run, o] {
        run = [o] {
            const HeadPath path = readHeadPath(o->path);
            std::signal(SIGINT, onSimSignal);
            std::signal(SIGTERM, onSimSignal);
            std::printf("tracker-sim: %s (%zu keys, %.1f s, body %d) to udp 127.0.0.1:%d at %.0f Hz%s\n", o->path.c_str(),
                        path.keys.size(), path.duration(), path.body, o->port, o->rate, o->seconds > 0 ? "" : ", until Ctrl-C");
            std::fflush(stdout);
            const uint64_t sent = playHeadPath(path, o->port, o->rate, o->seconds > 0 ? o->seconds : 1e300, &simStop);
            std::printf("tracker-sim: sent %llu frames\n", (unsigned long long)sent);
            return 0;
        };
    });
}

}  // namespace rtwall::cli
