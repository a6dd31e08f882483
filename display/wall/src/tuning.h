// The automatic operating point of a running wall (--target-fps): the operating points (given
// with --front, or calibrated on the wall's own clients), the controller that picks one frame
// by frame, and its trace (--trace).
#pragma once

#include "live_scene.h"

#include <rtwall/cluster.h>
#include <rtwall/tune.h>
#include <rtwall/wall.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace rtwall::wall {

class WallTuning {
public:
    // `setDenoise`: a point naming the denoise control switches the display side's filter.
    WallTuning(Master& master, LiveScene& live, RenderSettings baseSettings, CodecSettings baseCodec,
               std::function<void(const std::string&)> log, std::function<void(DenoiseSettings::Mode)> setDenoise);
    // With targetFps > 0: the controller starts at its front's first point (the front calibrated
    // now when none is given), and the trace file is opened when one is named. Else nothing.
    void start(double targetFps, const std::vector<OperatingPoint>& givenFront, const std::filesystem::path& traceFile);
    // After a frame: traced, counted against the budget, and the operating point changed when the
    // controller says so (it favours speed while the view `moved`).
    void observe(int frame, const FrameReport& report, bool moved);
    const OperatingPointController* controller() const { return controller_.get(); }  // null without --target-fps
    size_t framesOnTarget() const { return framesOnTarget_; }

private:
    Master& master_;
    LiveScene& live_;
    RenderSettings baseSettings_;  // the wall's resolution and the scene's settings before any operating point
    CodecSettings baseCodec_;
    std::function<void(const std::string&)> log_;
    std::function<void(DenoiseSettings::Mode)> setDenoise_;
    bool frontNamesDenoise_ = false;  // a point without the control then means the scene's mode
    double targetFps_ = 0;
    std::unique_ptr<OperatingPointController> controller_;
    std::ofstream trace_;
    size_t framesOnTarget_ = 0;

    void apply(const OperatingPoint& p);
    std::vector<OperatingPoint> calibrate();
};

}  // namespace rtwall::wall
