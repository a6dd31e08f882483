// The glue between the cluster master and the wall display: frames from Master::renderFrame go
// to the GL presenter (or the headless one where there is no display); navigation, bookmarks,
// recording and object picking turn into Master::setCamera / setInstanceTransform updates.
// The display library knows nothing of the engine or the cluster; this is where they meet.
#pragma once

#include <rtwall/cluster.h>
#include <rtwall/display.h>
#include <rtwall/engine.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace rtwall::cli {

class WallView {
public:
    struct Options {
        bool forceHeadless = false;
        bool perScreenImages = false;  // headless: write what each screen would show (wall's write_every)
        std::filesystem::path outDir = "out/frames";
        bool interactive = true;       // navigation and picking drive the camera (off while a path replays)
        std::string codec;             // for the status line
    };
    WallView(const WallConfig& wall, const SceneDesc& scene, const CameraDesc& start, const Options& options);
    ~WallView();

    bool windowed() const { return gl_ != nullptr; }
    const std::string& headlessReason() const { return whyHeadless_; }
    // Polls input and sends what changed to the master: camera, moved objects. False once the
    // user closed the wall (Esc or a window's close button).
    bool handleInput(Master& master, double dt);
    // The cameras each eye needs for the next frame (one for mono walls).
    CameraDesc camera() const;
    CameraDesc eyeCamera(int eye) const;  // stereo: off-axis window from the wall corners (0 left, 1 right)
    void setCamera(const CameraDesc& c);  // a camera path or orbit moved it
    void show(WallFrame& frame, const FrameReport& report, double frameSeconds);

private:
    WallConfig wall_;
    SceneDesc scene_;
    CameraDesc base_;
    Options options_;
    std::unique_ptr<GlPresenter> gl_;
    std::unique_ptr<HeadlessPresenter> headless_;
    std::string whyHeadless_;
    std::unique_ptr<Navigator> nav_;
    PresentOptions present_;
    bool showStatus_ = false;
    Image statusImage_;  // the overlay (H): frame rate, bytes, codec, per-client figures
    double statusClock_ = 0;
    int recordings_ = 0;
    // Picking: a local copy of the scene (built on the first pick) to cast rays into.
    std::unique_ptr<Scene> pickScene_;
    std::optional<PickResult> grabbed_;
    Transform grabbedStart_;
};

}  // namespace rtwall::cli
