// rtwall bench display: what the GL presenter sustains (upload + draw + swap, no vsync) at
// 1600x1200 and 4K, with glTexSubImage2D against pixel-buffer streaming, on one window and on
// the 2x2 projector wall; and the end-to-end latency from a camera change to the first
// displayed frame that shows it, through a master and local clients, asynchronous on and off.
// Needs a display: on a machine without one, run it under xvfb-run (Mesa's llvmpipe).
#include "commands.h"
#include "bench_util.h"

#include <rtwall/cluster.h>
#include <rtwall/display.h>
#include <rtwall/engine.h>

#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>

namespace rtwall::cli {

namespace {

double seconds() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

WallFrame noiseFrame(int w, int h, uint32_t seed) {
    WallFrame f;
    f.left.width = w;
    f.left.height = h;
    f.left.rgb.resize(size_t(w) * h * 3);
    uint32_t x = seed * 2654435761u + 1;
    for (uint8_t& b : f.left.rgb) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        b = uint8_t(x);
    }
    return f;
}

}  // namespace

void addBenchDisplay(CLI::App& bench, Run& run) {
    struct Options {
        int frames = 60, trials = 8, width = 800, height = 600, clients = 2;
        int64_t triangles = 200'000;
        bool json = false;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = bench.add_subcommand("display", "Presenter frames/s (upload methods, 1600x1200 and 4K) and camera-to-display latency");
    cmd->add_option("--frames", o->frames, "Frames per presenter measurement")->check(CLI::Range(5, 100000));
    cmd->add_option("--trials", o->trials, "Camera changes per latency measurement (median reported)")->check(CLI::Range(1, 1000));
    cmd->add_option("--width", o->width, "Image width of the latency runs")->check(CLI::Range(16, 16384));
    cmd->add_option("--height", o->height, "Image height of the latency runs")->check(CLI::Range(16, 16384));
    cmd->add_option("--clients", o->clients, "Local clients of the latency runs")->check(CLI::Range(1, 64));
    cmd->add_option("--triangles", o->triangles, "Triangles of the built-in scene")->check(CLI::Range(int64_t(1000), int64_t(100'000'000)));
    cmd->add_flag("--json", o->json, "Print JSON");
    cmd->callback([&run, o] {
        run = [o] {
            std::string renderer;
            toml::array presenter;
            struct Case {
                std::string wall;
                WallConfig config;
            };
            std::vector<Case> cases = {{"1x1 1600x1200", singleScreenWall(1600, 1200)},
                                       {"1x1 3840x2160", singleScreenWall(3840, 2160)}};
            {
                WallConfig w = parseWallConfig("[wall]\nname = \"2x2\"\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = 800\nscreen_height = 600\n",
                                               "2x2");
                cases.push_back({"2x2 1600x1200", w});
            }
            for (const Case& c : cases)
                for (UploadMethod m : {UploadMethod::TexSubImage, UploadMethod::Pbo}) {
                    std::string why;
                    GlPresenter::Options po;
                    po.upload = m;
                    po.vsyncOverride = 0;
                    auto gl = GlPresenter::open(c.config, po, &why);
                    if (!gl) throw InputError("bench display needs a display (" + why + "); without one: xvfb-run -a -s '-screen 0 4000x2400x24' rtwall bench display");
                    renderer = gl->renderer();
                    const WallFrame frames[2] = {noiseFrame(c.config.width, c.config.height, 1), noiseFrame(c.config.width, c.config.height, 2)};
                    for (int i = 0; i < 5; ++i) gl->present(frames[i % 2]);  // warm-up
                    const PresentStats before = gl->stats();
                    const double t0 = seconds();
                    for (int i = 0; i < o->frames; ++i) gl->present(frames[i % 2]);
                    const double t = seconds() - t0;
                    const PresentStats& s = gl->stats();
                    const double n = double(o->frames);
                    const double fps = n / t, up = (s.uploadSeconds - before.uploadSeconds) / n * 1e3,
                                 draw = (s.drawSeconds - before.drawSeconds) / n * 1e3, swap = (s.swapSeconds - before.swapSeconds) / n * 1e3;
                    presenter.push_back(toml::table{{"wall", c.wall}, {"upload", uploadMethodName(m)}, {"fps", fps},
                                                    {"upload_ms", up}, {"draw_ms", draw}, {"swap_ms", swap},
                                                    {"megapixels_per_s", fps * c.config.width * c.config.height * 1e-6}});
                    if (!o->json) {
                        std::printf("present %-14s %-12s %7.1f fps (upload %6.2f ms, draw %6.2f ms, swap %6.2f ms)\n", c.wall.c_str(),
                                    uploadMethodName(m), fps, up, draw, swap);
                        std::fflush(stdout);
                    }
                }

            // Latency: a camera change, then frames until the displayed image changes.
            SceneDesc desc = builtinScene("knots", o->triangles);
            desc.settings.width = o->width;
            desc.settings.height = o->height;
            desc.settings.tileSize = 64;
            const WallConfig wall = singleScreenWall(o->width, o->height);
            toml::array latency;
            for (bool async : {false, true}) {
                ClusterSettings cs;
                cs.async = async;
                Master master(desc, cs);
                LocalClients clients(o->clients, master.endpoint(), 1);
                if (!master.waitForClients(o->clients, 120'000)) throw InputError("local clients did not join");
                std::string why;
                GlPresenter::Options po;
                po.vsyncOverride = 0;
                auto gl = GlPresenter::open(wall, po, &why);
                if (!gl) throw InputError("bench display needs a display (" + why + ")");
                WallFrame shown;
                for (int i = 0; i < 3; ++i) {
                    shown.left = master.renderFrame();
                    gl->present(shown);
                }
                std::vector<double> ms, frames, frameMs;
                CameraDesc cam = desc.cameras.front();
                for (int trial = 0; trial < o->trials; ++trial) {
                    const double a = 5.0 * std::numbers::pi / 180.0;
                    const float x = cam.position.x - cam.lookAt.x, z = cam.position.z - cam.lookAt.z;
                    cam.position.x = cam.lookAt.x + float(std::cos(a) * x + std::sin(a) * z);
                    cam.position.z = cam.lookAt.z + float(-std::sin(a) * x + std::cos(a) * z);
                    const Image before = shown.left;
                    const double t0 = seconds();
                    master.setCamera(cam);
                    int n = 0;
                    for (; n < 6; ++n) {
                        const double f0 = seconds();
                        shown.left = master.renderFrame();
                        gl->present(shown);
                        frameMs.push_back((seconds() - f0) * 1e3);
                        if (shown.left.rgb != before.rgb) break;
                    }
                    ms.push_back((seconds() - t0) * 1e3);
                    frames.push_back(n + 1);
                }
                latency.push_back(toml::table{{"async", async}, {"latency_ms", median(ms)}, {"frames_until_shown", median(frames)},
                                              {"frame_ms", median(frameMs)}});
                if (!o->json) {
                    std::printf("latency async %-3s: %7.1f ms from camera change to display (%.0f frames of %.1f ms)\n",
                                async ? "on" : "off", median(ms), median(frames), median(frameMs));
                    std::fflush(stdout);
                }
            }
            if (o->json) {
                toml::table out{{"benchmark", "display"}, {"renderer", renderer}, {"frames", o->frames},
                                {"presenter", presenter}, {"latency_image", toml::array{o->width, o->height}},
                                {"latency_clients", o->clients}, {"latency", latency}};
                std::cout << toml::json_formatter{out} << "\n";
            } else {
                std::printf("renderer: %s\n", renderer.c_str());
            }
            return 0;
        };
    });
}

}  // namespace rtwall::cli
