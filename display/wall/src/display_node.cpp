// `rtwall display`: a display node of a wall on several PCs (issue 19). The cluster's
// runDisplayNode does the network and the tiles; this presents the node's own screens.
#include "gpu_warps.h"

#include <rtwall/mpcdi.h>
#include <rtwall/wall.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

namespace rtwall {

int runWallNode(const DisplayNodeOptions& options, const std::atomic<bool>* stop) {
    std::unique_ptr<GlPresenter> gl;
    std::unique_ptr<HeadlessPresenter> headless;
    WallConfig wall, whole;  // this node's screens; the whole wall (its denoise windows)
    std::unique_ptr<ProjectorBlendStage> blend;  // a calibrated wall's alpha and beta maps on this node's screens
    std::unique_ptr<PostWarpStage> postWarp;     // [warp] mode = "post": this node's screens resampled through the warp
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
        whole = parseWallConfig(text, "the master's wall config");
        wall = nodeWall(whole, options.name);
        if (whole.warp) {
            // A calibrated wall (issue 30): the clients trace through its warps (or render flat
            // for the post-warp, which this node does); this node applies its screens' blend
            // maps, from the file at the master's path (the same path on every display PC, as
            // the wall's shaders).
            WallConfig withWarp = wall;
            withWarp.warp = whole.warp;
            try {
                const MpcdiFile file = readMpcdi(whole.warp->mpcdi);
                if (whole.warp->mode == WarpMode::Post) postWarp = std::make_unique<PostWarpStage>(withWarp, file);
                blend = std::make_unique<ProjectorBlendStage>(withWarp, file);
            } catch (const InputError& e) {
                std::fprintf(stderr, "rtwall display: node '%s' shows its screens without the calibration's %s: %s\n",
                             options.name.c_str(), whole.warp->mode == WarpMode::Post ? "post-warp and blend" : "blend", e.what());
            }
        }
        std::string whyNot;
        if (!options.headless) gl = GlPresenter::open(wall, {}, &whyNot);
        if (!gl) {
            if (!options.headless) std::fprintf(stderr, "rtwall display: no window (%s): writing the screens to %s\n",
                                                whyNot.c_str(), options.out.string().c_str());
            headless = std::make_unique<HeadlessPresenter>(wall, options.out);
        }
    };
    // A frame to this node's screens: in its windows or to its files, with the left-out overlay.
    const auto show = [&](WallFrame& f, const std::vector<std::string>& leftOut) {
        Image overlay;
        PresentOptions po;
        if (postWarp) po.stages.push_back(postWarp.get());  // resampled first, then blended
        if (blend) po.stages.push_back(blend.get());
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
                    std::snprintf(name, sizeof name, "frame_%06u_%s.png", f.number, wall.screens[i].name.c_str());
                    writePng(shown[i], options.capture / name);
                }
            }
            gl->poll();
        } else if (headless) {
            headless->present(f, po);
        }
    };
    // Headless with nothing to write ([headless] write_every = 0, no video; the benchmark's
    // nodes): the frame would only be copied into a WallFrame and dropped. That copy of the
    // whole wall-sized frame took milliseconds at 4K and spread the nodes' swaps.
    const auto discards = [&] { return headless && wall.writeEvery <= 0 && wall.video.empty(); };
    // A denoised frame is filtered in the windows of this node's screens, as the single-PC wall
    // filters the whole wall's (issue 28).
    // Made again only when the frame's size, views' regions or eyes change (not per frame).
    struct WindowsKey {
        int width = -1, height = -1;
        std::vector<std::vector<ViewRegion>> regions;
        std::vector<std::pair<int, int>> references;  // each view's refWidth, refHeight
        std::vector<int> eyes;
        unsigned node = 0;
        bool operator==(const WindowsKey&) const = default;
    };
    WindowsKey windowsKey;
    std::vector<std::vector<TileRect>> windows;
    run.denoiseWindows = [&](int width, int height, const std::vector<FrameView>& views, const std::vector<int>& eyes,
                             unsigned node) {
        WindowsKey key{width, height, {}, {}, eyes, node};
        for (const FrameView& v : views) {
            key.regions.push_back(v.regions);
            key.references.emplace_back(v.refWidth, v.refHeight);
        }
        if (!(key == windowsKey)) {
            windows = denoiseWindowRects(denoiseWindows(TileRouting(whole, width, height), width, height, views, eyes), int(node));
            windowsKey = std::move(key);
        }
        return windows;
    };
    // The console's picture (issue 31): the pixels of this node's screens, each counted once.
    run.previewOwners = [&](int width, int height, int eye, uint64_t nodes) {
        return TileRouting(whole, width, height).owners(eye, nodes);
    };
    run.present = [&](uint32_t frame, const Image* left, const Image* right, const std::vector<std::string>& leftOut) {
        if (!left) return;  // released without this node: nothing new to show
        if (discards()) return;
        WallFrame f;
        f.number = frame;
        f.left = *left;
        if (right) f.right = *right;
        show(f, leftOut);
    };
    // The post-warp resamples from the eyes the frame (or the pose) was made for, as the master
    // says with each.
    run.roomEyes = [&](const std::array<Float3, 2>& eyes) {
        if (postWarp) postWarp->setEyes(eyes[0], eyes[1]);
    };
    // A re-projecting wall (issue 27): each refresh shows the newest frame warped to the master's
    // pose, on the GPU in windows, else by the CPU warp (which runs even when nothing is written:
    // it is the node's share of the refresh's work).
    WallFrame warped;
    run.refresh = [&](const NodeRefresh& r) {
        warped.number = r.frame;
        if (gl) {
            wall::setGpuWarps(warped, *r.compositor, r.targets, r.debug);
        } else {
            const EyeImages& eyes = r.compositor->reproject(r.targets, {}, r.debug);
            if (discards()) return;
            warped.left = eyes.left;  // copy-assigned: the buffers are reused
            warped.right = eyes.right;
        }
        show(warped, *r.leftOut);
    };
    return runDisplayNode(run);
}

}  // namespace rtwall
