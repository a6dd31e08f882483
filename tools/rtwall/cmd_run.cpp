// rtwall run: the display master with local render clients (rtwall/wall.h's WallSession), frame
// after frame; and rtwall controls, the table the operating point and the sweep share.
#include "commands.h"

#include <rtwall/wall.h>
#include <rtwall/web.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>

namespace rtwall::cli {

namespace {
std::atomic<bool> gStop{false};

// --web [ADDR:]PORT over the run config's [web].
WebSettings webFromOption(WebSettings w, const std::string& text) {
    w.enabled = true;
    std::string port = text;
    if (const size_t colon = text.rfind(':'); colon != std::string::npos) {
        w.address = text.substr(0, colon);
        if (w.address.size() > 2 && w.address.front() == '[' && w.address.back() == ']') w.address = w.address.substr(1, w.address.size() - 2);
        port = text.substr(colon + 1);
        if (w.address.empty()) throw InputError("--web " + text + ": the address before ':' is empty");
    }
    if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos || std::stoi(port) > 65535)
        throw InputError("--web " + text + ": expected [ADDR:]PORT with PORT in 0..65535");
    w.port = std::stoi(port);
    return w;
}
}  // namespace

void addRun(CLI::App& app, Run& run) {
    struct Options {
        std::string config;
        int frames = -1, clients = -1, writeEvery = -1;
        std::string out, bind, cameraPath, wall, front, trace, reproject, denoise, denoiseIsa, web, session;
        bool insecure = false, headless = false, watch = false, noLocalNodes = false, webInsecure = false;
        double targetFps = -1;  // not given
        PartView parts;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("run", "Run the display master with local render clients (default: a built-in demo)");
    cmd->add_option("config", o->config, "Run config (.toml, see configs/README.md); none: the embedded default");
    cmd->add_option("--frames", o->frames, "Frames to render (0 = until Ctrl-C)")->check(CLI::Range(0, 100'000'000));
    cmd->add_option("--clients", o->clients, "Local client processes to start")->check(CLI::Range(0, 256));
    cmd->add_option("--write-every", o->writeEvery, "Write every Nth frame as PNG (0 = never)")->check(CLI::Range(0, 100'000'000));
    cmd->add_option("--out", o->out, "Directory for the PNG frames");
    cmd->add_option("--camera-path", o->cameraPath, "Camera path file (.toml keyframes, see configs/README.md)");
    cmd->add_option("--wall", o->wall, "Wall config (configs/wall/*.toml; default: one window of the image's size)");
    cmd->add_flag("--headless", o->headless, "Never open windows, even where a display is available");
    cmd->add_flag("--watch", o->watch,
                  "Reload the scene file when it changes on disk and send what changed (materials, lights, instance "
                  "transforms, render settings, the camera) as differential updates");
    cmd->add_flag("--no-local-nodes", o->noLocalNodes,
                  "A wall on display nodes: start none on this PC (each runs `rtwall display --connect ... --node NAME` on its own PC)");
    cmd->add_option("--reproject", o->reproject,
                    "Re-projection: every refresh shows the newest frame warped to the newest head pose (default: the "
                    "wall config's `reproject`, on for a tracked wall)")
        ->check(CLI::IsMember({"on", "off"}));
    cmd->add_option("--denoise", o->denoise,
                    "Denoise the frames of a stochastic scene: off, temporal or svgf (default: the run config's [run] "
                    "denoise, else the scene's [denoise] mode)")
        ->check(CLI::IsMember({"off", "temporal", "svgf"}));
    addDenoiseIsaOption(cmd, o->denoiseIsa);
    cmd->add_flag("--insecure", o->insecure, "Allow a non-loopback bind without CURVE keys (says so loudly)");
    cmd->add_option("--bind", o->bind, "Endpoint for clients, e.g. tcp://0.0.0.0:7700 (default: loopback, any port)");
    cmd->add_option("--target-fps", o->targetFps,
                    "Hold this frame rate: pick the most accurate settings on the front that do (codec, JPEG quality, tile "
                    "size, resolution); 0: none (the embedded default holds " + std::to_string(int(kDefaultTargetFps)) + ")")
        ->check(CLI::Range(0.0, 10000.0));
    cmd->add_option("--front", o->front,
                    "Measured front for --target-fps (.toml from tools/speed_accuracy.py); default: calibrate codecs and tile "
                    "sizes on the first frames");
    cmd->add_option("--trace", o->trace, "With --target-fps: write one CSV line per frame (frame, seconds, clients, operating point)");
    cmd->add_option("--hide", o->parts.hide, "Hide the parts (or meshes) this pattern names: a name, or a path a/b/c when it has a '/'; '*' is any text (repeatable)");
    cmd->add_option("--isolate", o->parts.isolate, "Show only the parts (or meshes) these patterns name (repeatable)");
    cmd->add_option("--highlight", o->parts.highlight, "Highlight the parts (or meshes) this pattern names (repeatable)");
    cmd->add_option("--web", o->web,
                    "Serve the operator console at [ADDR:]PORT (docs/web-console.md; default address 127.0.0.1, PORT 0: any free port)");
    cmd->add_flag("--web-insecure", o->webInsecure, "Allow --web on a non-loopback address without TLS (says so loudly)");
    cmd->add_option("--session", o->session, "Restore a session file (the console's \"save\") before the first frame");
    cmd->callback([&run, o] {
        run = [o] {
            RunConfig c = o->config.empty() ? defaultRunConfig() : readRunConfig(o->config);
            if (o->frames >= 0) {
                c.frames = o->frames;
                c.framesGiven = true;
            }
            if (o->clients >= 0) c.cluster.localClients = o->clients;
            if (o->writeEvery >= 0) {
                c.writeEvery = o->writeEvery;
                if (c.loadedWall) c.loadedWall->writeEvery = o->writeEvery;  // the default's projector images too
            }
            if (!o->out.empty()) c.out = o->out;
            if (!o->bind.empty()) c.cluster.bind = o->bind;
            if (!o->cameraPath.empty()) c.cameraPath = o->cameraPath;
            if (o->insecure) c.cluster.insecure = true;
            if (o->noLocalNodes) c.localDisplayNodes = false;
            if (!o->wall.empty()) {
                c.wall = o->wall;
                c.loadedWall.reset();
            }
            if (!o->reproject.empty()) c.reproject = o->reproject == "on";
            if (!o->denoise.empty()) c.denoise = denoiseModeFromName(o->denoise);
            applyDenoiseIsa(o->denoiseIsa);
            c.headless = o->headless;
            c.watch = o->watch;
            if (o->targetFps >= 0) c.targetFps = o->targetFps;
            c.front = o->front;
            c.trace = o->trace;
            c.parts = o->parts;
            if (!o->session.empty()) c.session = o->session;
            if (!o->web.empty()) c.web = webFromOption(c.web, o->web);
            if (o->webInsecure) c.web.insecure = true;
            if (c.web.enabled) checkWebSettings(c.web);  // refused before anything starts
            // Ctrl-C and SIGTERM end the run between frames, and interrupt a frame that cannot
            // finish (Cancelled: "interrupted", exit status 130).
            std::signal(SIGINT, [](int) { gStop = true; });
            std::signal(SIGTERM, [](int) { gStop = true; });
            WallSession session(c, &gStop);
            // What was rendered and what the master dropped, refused or lost: said however the run ends.
            struct SummaryAtExit {
                const WallSession& session;
                double targetFps;
                ~SummaryAtExit() { std::printf("%s\n", describeSummary(session.summary(), targetFps).c_str()); }
            } summaryAtExit{session, c.targetFps};
            // The operator console: its backend taps the session after each step, its server
            // answers on its own threads; both go before the session does.
            std::unique_ptr<ConsoleBackend> backend;
            std::unique_ptr<WebApi> api;
            std::unique_ptr<WebServer> server;
            if (c.web.enabled) {
                backend = sessionBackend(session, c.web);
                api = std::make_unique<WebApi>(*backend, c.web.token.empty() ? makeWebToken() : c.web.token);
                server = std::make_unique<WebServer>(*api, c.web, [](const std::string& line) {
                    std::printf("%s\n", line.c_str());
                    std::fflush(stdout);
                });
                std::printf("web console: %s\n", server->url().c_str());
                std::fflush(stdout);
            }
            // Stopped between frames, the run ends normally; a frame that could not finish
            // throws Cancelled from step() (exit status 130).
            while (session.step()) {
            }
            return 0;
        };
    });
}

void addControls(CLI::App& app, Run& run) {
    auto json = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand("controls", "List the controls an operating point and the speed/accuracy sweep set");
    cmd->add_flag("--json", *json, "Print JSON (tools/speed_accuracy.py reads it)");
    cmd->callback([&run, json] {
        run = [json] {
            if (*json) {
                std::printf("%s\n", controlsJson().c_str());
                return 0;
            }
            for (const Control& c : controls())
                std::printf("%-13s %-14s [%g, %g]  %s\n", c.name, *c.option ? c.option : "-", c.min, c.max, c.help);
            return 0;
        };
    });
}

}  // namespace rtwall::cli
