// The wall as the people in front of it meet it: the presenters (GLFW windows, or per-screen
// PNGs where there is no display), keys and mouse, navigation, bookmarks, camera-path recording,
// picking and dragging objects, and the status overlay. Every change of the scene goes through
// the LiveScene. A new key binding goes into handle().
#pragma once

#include "live_scene.h"

#include <rtwall/display.h>
#include <rtwall/wall.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rtwall::wall {

class WallInput {
public:
    struct Options {
        bool forceHeadless = false;
        bool perScreenImages = false;  // headless: write what each screen would show (the wall's write_every)
        std::filesystem::path outDir = "out/frames";
        bool interactive = true;       // navigation and picking drive the camera (off while a path replays)
        std::string codec;             // for the status line
        // The wall's screens are on display nodes (issue 19): the master's one window is a small
        // console of the wall's aspect that shows the nodes' status and takes the keys and the
        // mouse (a click there is a click at that point of the wall); headless, nothing is written.
        bool console = false;
        // Per-screen stages after the mapping (a calibrated wall's blend), the caller's: run by
        // the windows or the headless presenter on every frame.
        std::vector<ScreenStage*> stages;
    };
    WallInput(const WallConfig& wall, const CameraDesc& start, const Options& options,
              std::function<void(const std::string&)> log);
    ~WallInput();

    bool windowed() const { return gl_ != nullptr; }
    // Polls the windows' input (and takes what inject() queued) and applies it to the scene:
    // camera, moved objects, the overlay and the views. False once the user closed the wall (Esc
    // or a window's close button).
    bool handle(LiveScene& scene, double dt);
    // Input as if from the windows, for the next handle(): scripted control and tests (it works
    // headless too).
    void inject(const InputState& input) { injected_.push_back(input); }
    bool showingStatus() const { return showStatus_; }
    bool showingTileOwners() const { return present_.falseColour; }
    // The viewer's camera, from the navigation pose, and the camera of one off-axis view of the
    // wall (wallViews: an eye's window in wall coordinates, carried into the world by the pose).
    CameraDesc camera() const;
    CameraDesc viewCamera(const EyeWindow& window) const;
    // The room in the world now (the map viewCamera carries its windows by): where a calibrated
    // screen's surface points are (issue 30).
    RoomToWorld roomToWorld() const;
    // Scene units per metre of the room ([navigation] scale; the keys [ and ] change it about
    // the head: setNavigationScale).
    double navigationScale() const { return scale_; }
    void setNavigationScale(double scale);
    // A line for the status overlay and the title (the tracker's state); empty: none.
    void setTrackerLine(const std::string& line) { trackerLine_ = line; }
    void setCamera(const CameraDesc& c);  // a camera path, orbit or scene edit moved it
    void showTileOwners(bool on) { present_.falseColour = on; }
    // Presses of J (the re-projection's debug colours) since the last call.
    int takeWarpDebugPresses() { return std::exchange(warpDebugPresses_, 0); }
    std::optional<PickResult> pick(LiveScene& scene, double wallX, double wallY);
    // The camera a click at wall pixel (x, y) picks with: the session's (setPickCamera: the view
    // that shows the pixel, off-axis and through its calibration), else the wall's camera.
    using PickCamera = std::function<std::optional<Camera>(double wallX, double wallY)>;
    void setPickCamera(PickCamera f) { pickCamera_ = std::move(f); }
    Camera pickCamera(double wallX, double wallY) const;
    // Measure mode (WallSession::setMeasuring and measurePick say what it does).
    void setMeasuring(bool on);
    bool measuring() const { return measuring_; }
    bool measurePick(LiveScene& scene, double wallX, double wallY);
    const std::optional<Measurement>& measurement() const { return measurement_; }
    // The complete measurements, oldest first (WallSession::measurements), and two picks as one.
    std::vector<Measurement>& kept() { return kept_; }
    std::optional<Measurement> measureBetween(LiveScene& scene, double ax, double ay, double bx, double by);
    // Section planes (WallSession::setSection): sets slot `index` and makes it the active plane,
    // the one the section keys (docs/design-review.md, "Section planes") move; -1: none.
    void setSection(LiveScene& scene, uint32_t index, const SectionPlane& plane);
    int activeSection() const { return activeSection_; }
    // Parts by name (WallSession::setPartView): applied to the scene, logged, on the overlay.
    void setPartView(LiveScene& scene, const PartView& view);
    void showAllParts(LiveScene& scene);
    // The tracked flystick (a wall with [tracking] and a `flystick`): navigation by its joystick,
    // its buttons (mode, home, pick and drag or measure: every press and release since the last
    // step, in order), and the ray's length; once per step, after handle(). It also takes the
    // tracked head, about which the world-scale keys scale. Then drawWand draws its ray into the
    // frame's eye images for `head` (of a frame the GL presenter warps: into its paints).
    void handleWand(LiveScene& scene, const TrackerState& tracker, double dt);
    void drawWand(WallFrame& frame, const HeadPose& head) const;
    const std::optional<WandPose>& wand() const { return wand_; }
    // Shows a frame the wall's size (or smaller: a frame rendered at a fraction of the
    // resolution is shown upscaled).
    void show(const WallFrame& frame, const FrameReport& report, double frameSeconds);
    // Options::console: the console window shows these lines (the nodes' status) and, when the
    // status overlay is on (H), the figures show() would show.
    void showConsole(const std::string& lines, const FrameReport& report, double frameSeconds);

private:
    WallConfig wall_;
    CameraDesc base_;
    PickCamera pickCamera_;
    Options options_;
    std::function<void(const std::string&)> log_;
    std::unique_ptr<GlPresenter> gl_;
    WallConfig console_;  // Options::console: the one window's layout
    std::unique_ptr<HeadlessPresenter> headless_;
    std::string whyHeadless_;
    std::unique_ptr<Navigator> nav_;
    PresentOptions present_;
    int warpDebugPresses_ = 0;
    bool showStatus_ = false;
    Image statusImage_;  // the overlay (H): frame rate, bytes, codec, per-client figures, counters
    double statusClock_ = 0;
    int recordings_ = 0;
    std::vector<InputState> injected_;
    std::string trackerLine_;
    bool apply(LiveScene& scene, const InputState& in, double dt);
    std::optional<PickResult> grabbed_;
    Transform grabbedStart_;
    std::optional<WandPose> wand_;
    uint64_t wandEvents_ = 0;  // the last button event acted on (WandState::events)
    void wandPress(LiveScene& scene, const WandPose& p);  // the trigger went down with the wand at p
    void wandRelease(LiveScene& scene);
    double scale_ = 1.0;  // scene units per metre of the room
    static constexpr double kScaleStep = 1.4142135623730951;  // a press of [ or ]: two double or halve
    HeadPose head_;       // the tracked head (or the config's viewer), about which the scale keys scale
    std::optional<PickResult> wandGrab_;
    WandPose wandGrabStart_;
    Transform wandGrabTransform_;
    std::optional<SectionPlane> wandPlaneStart_;  // the selected section plane as the trigger took it
    std::optional<Float3> orbitCentre_;  // the scene's centre, taken when the wand starts orbiting
    void dragHeld(LiveScene& scene, WandPose& p);  // the held object or section plane follows the wand
    bool measureHit(LiveScene& scene, const std::optional<PickResult>& hit, Float3 origin, Float3 direction);
    bool measuring_ = false;
    bool escapeHeld_ = false;  // the Esc that left measure mode: held on, it does not close the wall
    std::optional<Measurement> measurement_;
    std::vector<Measurement> kept_;
    std::string measureLine() const;  // for the status line and overlay while measuring
    int activeSection_ = -1;
    double sectionStep_ = 0;  // how far PageUp/PageDown move a plane: 1/100 of the scene's size
    void sectionKey(LiveScene& scene, int key, int mods);
    std::string sectionLine(const SceneDesc& scene) const;  // the active plane, for the overlay
    std::string overlayText_;  // measuring and the active plane: the overlay's line, kept by handle()
    void updateOverlay() {
        present_.overlay = (showStatus_ || measuring_ || activeSection_ >= 0 || !partsLine_.empty()) ? &statusImage_ : nullptr;
    }
    std::string selected_;            // the part (path, or mesh name) the last Ctrl+click picked
    std::string partsLine_;           // what is hidden, isolated, highlighted; empty: nothing
    void partKey(LiveScene& scene, int key);
    void refreshStatus() { statusClock_ = 1e9; }  // the overlay shows a change at the next frame
};

}  // namespace rtwall::wall
