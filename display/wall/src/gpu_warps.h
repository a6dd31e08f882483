// A frame for the GL presenter's warp (issue 27): the compositor's re-projection sources, view
// by view, with the cameras to warp them to (WallFrame::warps). The master's refresh loop and a
// display node's refresh both hand their compositor's sources to the GPU this way.
#pragma once

#include <rtwall/display.h>
#include <rtwall/frame.h>

#include <span>

namespace rtwall::wall {

inline void setGpuWarps(WallFrame& frame, const Compositor& compositor, std::span<const CameraDesc> targets, bool debug) {
    frame.warps.resize(targets.size());
    for (size_t v = 0; v < targets.size(); ++v) {
        const Compositor::WarpSlot& newest = compositor.newestSource(v);
        const Compositor::WarpSlot* older = compositor.olderSource(v);
        const FrameView& view = compositor.sourceView(v);
        ViewWarp& w = frame.warps[v];
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
    frame.warpDebug = debug;
}

}  // namespace rtwall::wall
