// rtwall bench display: what the GL presenter sustains (upload + draw + swap, no vsync) at
// 1600x1200 and 4K, with glTexSubImage2D against pixel-buffer streaming, on one window and on
// the 2x2 projector wall; and the end-to-end latency from a camera change to the first
// displayed frame that shows it, through a master and local clients, asynchronous on and off.
// Needs a display: on a machine without one, run it under xvfb-run (Mesa's llvmpipe).
#include "bench.h"
#include "bench_util.h"

#include <rtwall/cluster.h>
#include <rtwall/display.h>
#include <rtwall/engine.h>

#include <cstdio>
#include <memory>

namespace rtwall::bench {

namespace {

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

// A presenter without vsync (what it sustains, not the display's refresh rate).
std::unique_ptr<GlPresenter> openPresenter(const WallConfig& wall, GlPresenter::Options po, const char* hint) {
    std::string why;
    po.vsyncOverride = 0;
    auto gl = GlPresenter::open(wall, po, &why);
    if (!gl) throw InputError("bench display needs a display (" + why + ")" + hint);
    return gl;
}

// Presenter frames/s for each wall and upload method; `renderer` is set to the GL renderer.
toml::array presenterRows(const DisplayOptions& o, std::string& renderer) {
    struct Case {
        std::string wall;
        WallConfig config;
    };
    const std::vector<Case> cases = {
        {"1x1 1600x1200", singleScreenWall(1600, 1200)},
        {"1x1 3840x2160", singleScreenWall(3840, 2160)},
        {"2x2 1600x1200",
         parseWallConfig("[wall]\nname = \"2x2\"\n[grid]\ncolumns = 2\nrows = 2\nscreen_width = 800\nscreen_height = 600\n", "2x2")}};
    toml::array presenter;
    for (const Case& c : cases)
        for (UploadMethod m : {UploadMethod::TexSubImage, UploadMethod::Pbo}) {
            GlPresenter::Options po;
            po.upload = m;
            auto gl = openPresenter(c.config, po, "; without one: xvfb-run -a -s '-screen 0 4000x2400x24' rtwall bench display");
            renderer = gl->renderer();
            const WallFrame frames[2] = {noiseFrame(c.config.width, c.config.height, 1), noiseFrame(c.config.width, c.config.height, 2)};
            for (int i = 0; i < 5; ++i) gl->present(frames[i % 2]);  // warm-up
            const PresentStats before = gl->stats();
            const double t = secondsOf([&] {
                for (int i = 0; i < o.frames; ++i) gl->present(frames[i % 2]);
            });
            const PresentStats& s = gl->stats();
            const double n = double(o.frames);
            const double fps = n / t, up = (s.uploadSeconds - before.uploadSeconds) / n * 1e3,
                         draw = (s.drawSeconds - before.drawSeconds) / n * 1e3, swap = (s.swapSeconds - before.swapSeconds) / n * 1e3;
            presenter.push_back(toml::table{{"wall", c.wall}, {"upload", uploadMethodName(m)}, {"fps", fps},
                                            {"upload_ms", up}, {"draw_ms", draw}, {"swap_ms", swap},
                                            {"megapixels_per_s", fps * c.config.width * c.config.height * 1e-6}});
            if (o.text) {
                std::fprintf(o.text, "present %-14s %-12s %7.1f fps (upload %6.2f ms, draw %6.2f ms, swap %6.2f ms)\n",
                             c.wall.c_str(), uploadMethodName(m), fps, up, draw, swap);
                std::fflush(o.text);
            }
        }
    return presenter;
}

// Latency: a camera change, then frames until the displayed image changes.
toml::table latencyRow(const SceneDesc& desc, const DisplayOptions& o, bool async) {
    ClusterSettings cs;
    cs.async = async;
    Master master(desc, cs);
    LocalClients clients(o.clients, master.endpoint(), 1);
    if (!master.waitForClients(o.clients, 120'000)) throw InputError("local clients did not join");
    auto gl = openPresenter(singleScreenWall(o.width, o.height), {}, "");
    WallFrame shown;
    for (int i = 0; i < 3; ++i) {
        shown.left = master.renderFrame();
        gl->present(shown);
    }
    std::vector<double> ms, frames, frameMs;
    CameraDesc cam = desc.cameras.front();
    for (int trial = 0; trial < o.trials; ++trial) {
        cam = orbitCamera(cam, 5.0);
        const Image before = shown.left;
        const Stopwatch sinceChange;
        master.setCamera(cam);
        int n = 0;
        for (; n < 6; ++n) {
            frameMs.push_back(1e3 * secondsOf([&] {
                shown.left = master.renderFrame();
                gl->present(shown);
            }));
            if (shown.left.rgb != before.rgb) break;
        }
        ms.push_back(sinceChange.seconds() * 1e3);
        frames.push_back(n + 1);
    }
    if (o.text) {
        std::fprintf(o.text, "latency async %-3s: %7.1f ms from camera change to display (%.0f frames of %.1f ms)\n",
                     async ? "on" : "off", median(ms), median(frames), median(frameMs));
        std::fflush(o.text);
    }
    return toml::table{{"async", async}, {"latency_ms", median(ms)}, {"frames_until_shown", median(frames)},
                       {"frame_ms", median(frameMs)}};
}

}  // namespace

toml::table display(const DisplayOptions& o) {
    std::string renderer;
    const toml::array presenter = presenterRows(o, renderer);
    SceneDesc desc = builtinScene("knots", o.triangles);
    desc.settings.width = o.width;
    desc.settings.height = o.height;
    desc.settings.tileSize = 64;
    toml::array latency;
    for (bool async : {false, true}) latency.push_back(latencyRow(desc, o, async));
    if (o.text) std::fprintf(o.text, "renderer: %s\n", renderer.c_str());
    return toml::table{{"benchmark", "display"}, {"renderer", renderer}, {"frames", o.frames},
                       {"presenter", presenter}, {"latency_image", toml::array{o.width, o.height}},
                       {"latency_clients", o.clients}, {"latency", latency}};
}

}  // namespace rtwall::bench
