// `rtwall display`: a display node of a wall on several PCs (issue 19). The cluster's
// runDisplayNode does the network and the tiles; this presents the node's own screens.
#include <rtwall/wall.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

namespace rtwall {

int runWallNode(const DisplayNodeOptions& options, const std::atomic<bool>* stop) {
    std::unique_ptr<GlPresenter> gl;
    std::unique_ptr<HeadlessPresenter> headless;
    WallConfig wall;
    DisplayNodeRun run;
    run.connect = options.connect;
    run.name = options.name;
    run.bind = options.bind;
    run.advertise = options.advertise;
    run.keyFile = options.keyFile;
    run.serverKeyFile = options.serverKeyFile;
    run.frames = options.frames;
    run.exitAfterIdleMs = options.exitAfterIdleMs;
    run.stop = stop;
    run.onWall = [&](const std::string& text) {
        // The same wall on every (re)join: the presenter is made once.
        if (gl || headless) return;
        wall = nodeWall(parseWallConfig(text, "the master's wall config"), options.name);
        std::string whyNot;
        if (!options.headless) gl = GlPresenter::open(wall, {}, &whyNot);
        if (!gl) {
            if (!options.headless) std::fprintf(stderr, "rtwall display: no window (%s): writing the screens to %s\n",
                                                whyNot.c_str(), options.out.string().c_str());
            headless = std::make_unique<HeadlessPresenter>(wall, options.out);
        }
    };
    run.present = [&](uint32_t frame, const Image* left, const Image* right, const std::vector<std::string>& leftOut) {
        if (!left) return;  // released without this node: nothing new to show
        // Headless with nothing to write ([headless] write_every = 0, no video; the benchmark's
        // nodes): the frame would only be copied into a WallFrame and dropped. That copy of the
        // whole wall-sized frame took milliseconds at 4K and spread the nodes' swaps.
        if (headless && wall.writeEvery <= 0 && wall.video.empty()) return;
        WallFrame f;
        f.number = frame;
        f.left = *left;
        if (right) f.right = *right;
        Image overlay;
        PresentOptions po;
        if (!leftOut.empty()) {
            std::string text = "display nodes left out:";
            for (const std::string& n : leftOut) text += " " + n;
            overlay = textImage(text);
            po.overlay = &overlay;
        }
        if (gl) {
            if (options.capture.empty()) {
                gl->present(f, po);
            } else {
                std::vector<Image> shown;
                gl->present(f, po, &shown);
                std::filesystem::create_directories(options.capture);
                for (size_t i = 0; i < shown.size(); ++i) {
                    char name[96];
                    std::snprintf(name, sizeof name, "frame_%06u_%s.png", frame, wall.screens[i].name.c_str());
                    writePng(shown[i], options.capture / name);
                }
            }
            gl->poll();
        } else if (headless) {
            headless->present(f, po);
        }
    };
    return runDisplayNode(run);
}

}  // namespace rtwall
