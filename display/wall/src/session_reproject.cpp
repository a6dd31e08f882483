// The re-projecting wall (issue 27): WallSession's refresh loop. While the cluster renders a
// frame on the refresher's worker thread, this thread shows the newest complete frame at every
// refresh, each view warped from the pose it was rendered for to the pose read just before the
// presentation (late latching) by the Compositor's re-projection; the frame before it fills
// what the newest does not cover. A new frame replaces the warp's source as soon as it is in.
// On display nodes the nodes warp their own screens: this thread sends them the pose it read,
// every refresh (Master::presentPose).
#include "gpu_warps.h"
#include "session_impl.h"

namespace rtwall {

bool WallSession::Impl::reprojects() const { return config.reproject.value_or(wallConfig.reprojects()) && views; }

void WallSession::Impl::decideReprojection() {
    reproject = config.reproject.value_or(wallConfig.reprojects());
    warpDebug = wallConfig.reprojectDebug;
    if (!reproject) return;
    if (!views) {
        // One image without a head or screens given by their corners has no pose to warp to.
        log("reproject: off: this wall has no views to warp (it needs [stereo] corners, a stereo mode or [tracking])");
        reproject = false;
        return;
    }
    // On display nodes the nodes warp (routeToNodes asked for it, and for the ring of tiles
    // around each node's screens); the master sends them the pose at every refresh.
    config.cluster.depth = true;  // every tile comes with its depth
}

void WallSession::Impl::decideDenoising(const SceneDesc& desc, DenoiseSettings::Mode frontMost) {
    denoise = desc.denoise;
    const DenoiseSettings::Mode most = std::max(denoise.mode, frontMost);  // off < temporal < svgf
    if (most == DenoiseSettings::Mode::Off) return;
    if (!config.cluster.wideAccumulation) {
        log(format("denoise: off: it needs linear tiles (the cluster's wide accumulation; %s asks for %s)",
                   most == denoise.mode ? "the scene" : "the front", denoiseModeName(most)));
        denoise.mode = DenoiseSettings::Mode::Off;
        return;
    }
    sentFeatures = most;
    config.cluster.depth = true;
    config.cluster.features = featureBitsFor(most);
    // Screen by screen, each with the ring of pixels its filter reaches: the single-PC wall
    // as the display nodes, which get that ring of tiles around their screens (routeToNodes).
    // Levels raised later by an edit reach no further than this ring.
    DenoiseSettings widest = denoise;
    widest.mode = most;
    denoiseRing = rtwall::denoiseRing(widest);
    const std::string where = onNodes ? format(", on the display nodes (%d-pixel ring around each screen)", denoiseRing) : "";
    if (denoise.mode == DenoiseSettings::Mode::Svgf)
        log(format("denoise: svgf (%d levels, history %d), on the frames of a stochastic scene%s", denoise.levels,
                   denoise.history, where.c_str()));
    else if (denoise.mode == DenoiseSettings::Mode::Temporal)
        log(format("denoise: temporal (history %d), on the frames of a stochastic scene%s", denoise.history, where.c_str()));
    if (frontMost > denoise.mode)
        log(format("denoise: %s now; the operating points may switch it up to %s (the clients send its features)%s",
                   denoiseModeName(denoise.mode), denoiseModeName(frontMost), where.c_str()));
}

void WallSession::Impl::startRefresher() {
    if (!reproject) return;
    // In windows with vsync the swap waits for the retrace; headless (and without vsync) the
    // loop keeps the configured rate itself.
    // On display nodes the master's window is a console: the master keeps the rate and each node
    // presents the pose when it comes.
    const bool paced = onNodes || !(input->windowed() && wallConfig.vsync);
    refresher = std::make_unique<Refresher>(wallConfig.refreshHz, paced);
    log(format("reproject: on, %s%s%s", paced ? format("%.0f refreshes a second", wallConfig.refreshHz).c_str() : "at the retrace",
               onNodes ? ", warped on the display nodes (the master sends each refresh's pose)" : "",
               warpDebug ? ", debug colours" : ""));
}

std::vector<Image> WallSession::Impl::renderWhileRefreshing() {
    std::vector<Image> images;
    FrameReport pending;  // the worker's: `report` is the shown frame's while it renders
    const std::function<void()> render = [&] {
        images = master->renderViews(&pending, &viewLinear, &viewDepth, denoising() ? &viewFeatures : nullptr);
    };
    const std::function<void()> present = [&] { presentRefresh(); };
    // On nodes: once a frame was released to them (they hold it; the master holds no pixels).
    refresher->run(render, present, onNodes ? report.swapsReleased > 0 : compositor.reprojectViews() > 0);
    report = std::move(pending);
    return images;
}

void WallSession::Impl::latchTargets() {
    shownPosed = std::chrono::steady_clock::now();
    HeadPose latched = staticHead(wallConfig.stereo);
    uint64_t packets = 0;
    if (tracker) {
        const TrackerState t = tracker->state();  // the newest datagram, predicted as configured
        if (t.seen) latched = t.head;
        packets = t.packets;
    }
    targets.clear();  // refilled in place: no allocation per refresh once it has its size
    forEachView(latched, [&](int, const std::vector<WallView>& vs, size_t i) { targets.push_back(input->viewCamera(vs[i].window)); });
    shownHead = latched;
    shownTrackerPackets = packets;
}

void WallSession::Impl::latchAndWarp() {
    if (onNodes) {
        // The nodes warp: the pose goes to all of them (after the first release; before it the
        // master sends nothing).
        latchTargets();
        master->presentPose(targets, warpDebug, nodeEyes(shownHead));
        return;
    }
    // A frame that came without depth (none should) is shown as composed, for the pose it was made for.
    if (compositor.reprojectViews() == 0) return;
    latchTargets();
    if (input->windowed()) {
        warpOnGpu();
    } else {
        const EyeImages& eyes = compositor.reproject(targets, {}, warpDebug);
        shown.left = eyes.left;  // copy-assigned: the buffers are reused
        shown.right = eyes.right;
    }
}

// In windows the GL presenter warps: the frame carries the compositor's sources and the
// targets (WallFrame::warps), the same algorithm as the CPU's in shaders.
void WallSession::Impl::warpOnGpu() { wall::setGpuWarps(shown, compositor, targets, warpDebug); }

void WallSession::Impl::presentRefresh() {
    latchAndWarp();
    if (!onNodes) {
        if (tracker) input->drawWand(shown, shownHead);
        setPostWarpEyes();
        input->show(shown, report, frameTimes.empty() ? 0.0 : frameTimes.back());
    }
    recordPresentation(true);
}

void WallSession::Impl::recordPresentation(bool warped) {
    presentations.push_back({std::chrono::steady_clock::now(), shownPosed, shown.number, shownTrackerPackets, shownHead, warped});
    while (presentations.size() > 4096) presentations.pop_front();
}

bool WallSession::reprojecting() const { return impl_->reproject; }

void WallSession::Impl::collectNodeRefreshes() {
    if (!onNodes || !reproject) return;
    for (NodeRefreshDelay& d : master->takeNodeRefreshes()) nodeRefreshes.push_back(std::move(d));
    while (nodeRefreshes.size() > 4096) nodeRefreshes.pop_front();
}

std::vector<NodeRefreshDelay> WallSession::takeNodeRefreshes() {
    impl_->collectNodeRefreshes();
    std::vector<NodeRefreshDelay> out(impl_->nodeRefreshes.begin(), impl_->nodeRefreshes.end());
    impl_->nodeRefreshes.clear();
    return out;
}

std::vector<Presentation> WallSession::takePresentations() {
    std::vector<Presentation> out(impl_->presentations.begin(), impl_->presentations.end());
    impl_->presentations.clear();
    return out;
}

}  // namespace rtwall
