// The re-projecting wall (issue 27): WallSession's refresh loop. While the cluster renders a
// frame on the refresher's worker thread, this thread shows the newest complete frame at every
// refresh, each view warped from the pose it was rendered for to the pose read just before the
// presentation (late latching) by the Compositor's re-projection; the frame before it fills
// what the newest does not cover. A new frame replaces the warp's source as soon as it is in.
#include "session_impl.h"

namespace rtwall {

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
    if (onNodes) {
        log("reproject: off: the display nodes show each frame as rendered (re-projection on the nodes is not built yet)");
        reproject = false;
        return;
    }
    config.cluster.depth = true;  // every tile comes with its depth
}

void WallSession::Impl::startRefresher() {
    if (!reproject) return;
    // In windows with vsync the swap waits for the retrace; headless (and without vsync) the
    // loop keeps the configured rate itself.
    const bool paced = !(input->windowed() && wallConfig.vsync);
    refresher = std::make_unique<Refresher>(wallConfig.refreshHz, paced);
    log(format("reproject: on, %s%s", paced ? format("%.0f refreshes a second", wallConfig.refreshHz).c_str() : "at the retrace",
               warpDebug ? ", debug colours" : ""));
}

std::vector<Image> WallSession::Impl::renderWhileRefreshing() {
    std::vector<Image> images;
    FrameReport pending;  // the worker's: `report` is the shown frame's while it renders
    const std::function<void()> render = [&] { images = master->renderViews(&pending, &viewLinear, &viewDepth); };
    const std::function<void()> present = [&] { presentRefresh(); };
    refresher->run(render, present, compositor.reprojectViews() > 0);
    report = std::move(pending);
    return images;
}

void WallSession::Impl::latchAndWarp() {
    // A frame that came without depth (none should) is shown as composed, for the pose it was made for.
    if (compositor.reprojectViews() == 0) return;
    shownPosed = std::chrono::steady_clock::now();
    HeadPose latched = staticHead(wallConfig.stereo);
    uint64_t packets = 0;
    if (tracker) {
        const TrackerState t = tracker->state();  // the newest datagram, predicted as configured
        if (t.seen) latched = t.head;
        packets = t.packets;
    }
    targets.clear();
    for (int eye : stereo ? std::vector<int>{0, 1} : std::vector<int>{-1})
        for (const WallView& v : wallViews(wallConfig, latched, eye)) targets.push_back(input->viewCamera(v.window));
    if (input->windowed()) {
        warpOnGpu();
    } else {
        const EyeImages& eyes = compositor.reproject(targets, {}, warpDebug);
        shown.left = eyes.left;  // copy-assigned: the buffers are reused
        shown.right = eyes.right;
    }
    shownHead = latched;
    shownTrackerPackets = packets;
}

// In windows the GL presenter warps: the frame carries the compositor's sources and the
// targets (WallFrame::warps), the same algorithm as the CPU's in shaders.
void WallSession::Impl::warpOnGpu() {
    shown.warps.resize(targets.size());
    for (size_t v = 0; v < targets.size(); ++v) {
        const Compositor::WarpSlot& newest = compositor.newestSource(v);
        const Compositor::WarpSlot* older = compositor.olderSource(v);
        const FrameView& view = compositor.sourceView(v);
        ViewWarp& w = shown.warps[v];
        w.eye = compositor.sourceEye(v) == 1 ? 1 : 0;
        w.regions.clear();
        for (const ViewRegion& g : view.regions)
            w.regions.push_back(scaledRegion(g, view.refWidth, view.refHeight, newest.image.width, newest.image.height));
        w.image = &newest.image;
        w.depth = &newest.depth;
        w.camera = newest.camera;
        w.olderImage = older ? &older->image : nullptr;
        w.olderDepth = older ? &older->depth : nullptr;
        w.olderCamera = older ? older->camera : CameraDesc{};
        w.target = targets[v];
    }
    shown.warpDebug = warpDebug;
}

void WallSession::Impl::presentRefresh() {
    latchAndWarp();
    if (tracker) input->drawWand(shown, shownHead);
    input->show(shown, report, frameTimes.empty() ? 0.0 : frameTimes.back());
    recordPresentation(true);
}

void WallSession::Impl::recordPresentation(bool warped) {
    presentations.push_back({std::chrono::steady_clock::now(), shownPosed, shown.number, shownTrackerPackets, shownHead, warped});
    while (presentations.size() > 4096) presentations.pop_front();
}

bool WallSession::reprojecting() const { return impl_->reproject; }

std::vector<Presentation> WallSession::takePresentations() {
    std::vector<Presentation> out(impl_->presentations.begin(), impl_->presentations.end());
    impl_->presentations.clear();
    return out;
}

}  // namespace rtwall
