// WallTuning (tuning.h): the operating point of a running wall.
#include "tuning.h"

#include <algorithm>
#include <cstdio>
#include <tuple>

namespace rtwall::wall {

namespace {

std::string pointName(const CodecSettings& c, int tile) {
    std::string n = tileCodecName(c.codec);
    if (c.codec == TileCodec::Jpeg) n += " q" + std::to_string(c.jpegQuality);
    return n + ", tile " + std::to_string(tile);
}

}  // namespace

WallTuning::WallTuning(Master& master, LiveScene& live, RenderSettings baseSettings, CodecSettings baseCodec,
                       std::function<void(const std::string&)> log, std::function<void(DenoiseSettings::Mode)> setDenoise)
    : master_(master),
      live_(live),
      baseSettings_(baseSettings),
      baseCodec_(baseCodec),
      log_(std::move(log)),
      setDenoise_(std::move(setDenoise)) {}

// An operating point's settings, applied through the one scene state.
void WallTuning::apply(const OperatingPoint& p) {
    const Knobs k = knobsOf(p, baseSettings_, baseCodec_);
    live_.setRenderSettings(k.settings);
    master_.setCodec(k.codec);
    // A point of a front that names the filter elsewhere but not here: the scene's own mode.
    if (setDenoise_ && (k.denoise || frontNamesDenoise_)) setDenoise_(k.denoise.value_or(live_.desc().denoise.mode));
    if (k.volumeStep > 0)
        for (size_t m = 0; m < live_.desc().materials.size(); ++m)
            if (live_.desc().materials[m].type == MaterialType::Volume && live_.desc().materials[m].volumeStep != k.volumeStep) {
                Material mat = live_.desc().materials[m];
                mat.volumeStep = k.volumeStep;
                live_.setMaterial(uint32_t(m), mat);
            }
}

// Calibration: each codec and tile size, and four resolutions, for three frames of the first
// view; error = 1 - SSIM against the lossless frame (at the wall's resolution). Down to a
// quarter of the wall's width: on a 2-core PC the 1600x1200 reference wall (the default run)
// reaches an interactive rate only below half.
std::vector<OperatingPoint> WallTuning::calibrate() {
    log_("calibrating the operating points (codec x tile size, and resolution, 3 frames each)");
    const Image lossless = master_.renderFrame();
    std::vector<std::tuple<int, int, double>> grid;  // JPEG quality (0: LZ4), tile, scale
    for (int q : {0, 95, 90, 75, 50})
        for (int tile : {32, 64, 128}) grid.emplace_back(q, tile, 1.0);
    for (double scale : {0.75, 0.5, 0.35, 0.25}) grid.emplace_back(0, 64, scale);
    std::vector<OperatingPoint> points;
    for (const auto& [q, tile, scale] : grid) {
        OperatingPoint p;
        CodecSettings cs = baseCodec_;
        cs.codec = q == 0 ? TileCodec::Lz4 : TileCodec::Jpeg;
        if (q) cs.jpegQuality = q;
        p.name = pointName(cs, tile);
        p.controls = {{"tile", tile}, {"codec", double(int(cs.codec))}, {"scale", scale}};
        if (scale != 1.0) p.name += ", scale " + std::to_string(scale).substr(0, 4);
        if (q) p.controls.emplace_back("jpeg_quality", q);
        apply(p);
        std::vector<double> times;
        Image img;
        for (int i = 0; i < 3; ++i) {
            FrameReport r;
            img = master_.renderFrame(&r);
            if (i > 0) times.push_back(r.seconds);
        }
        p.frameSeconds = std::max(1e-6, *std::min_element(times.begin(), times.end()));
        p.error = std::max(0.0, 1.0 - ssimLuminance(resizeBilinear(img, lossless.width, lossless.height), lossless));
        char line[160];
        std::snprintf(line, sizeof line, "  %-20s %7.1f ms  1-SSIM %.5f", p.name.c_str(), p.frameSeconds * 1e3, p.error);
        log_(line);
        points.push_back(p);
    }
    return points;
}

void WallTuning::start(double targetFps, const std::vector<OperatingPoint>& givenFront, const std::filesystem::path& traceFile) {
    if (targetFps <= 0) return;
    targetFps_ = targetFps;
    const std::vector<OperatingPoint> points = givenFront.empty() ? calibrate() : givenFront;
    for (const OperatingPoint& p : points)
        for (const auto& [name, value] : p.controls) frontNamesDenoise_ |= name == "denoise";
    ControllerOptions co;
    co.targetFps = targetFps;
    controller_ = std::make_unique<OperatingPointController>(points, co);
    apply(controller_->current());
    char line[512];
    std::snprintf(line, sizeof line, "target %.1f fps: starting at '%s' (front of %zu points)", targetFps,
                  controller_->current().name.c_str(), controller_->front().size());
    log_(line);
    if (!traceFile.empty()) {
        trace_.open(traceFile);
        if (!trace_) throw InputError("--trace: cannot write " + traceFile.string());
        trace_ << "frame,seconds,clients,point_index,point\n";
    }
}

void WallTuning::observe(int frame, const FrameReport& report, bool moved) {
    if (!controller_) return;
    if (trace_.is_open())
        trace_ << frame << ',' << report.seconds << ',' << master_.connectedClients() << ',' << controller_->currentIndex()
               << ",\"" << controller_->current().name << "\"" << std::endl;
    framesOnTarget_ += report.seconds <= 1.0 / targetFps_;
    if (controller_->observe(report.seconds, moved)) {
        apply(controller_->current());
        char line[512];
        std::snprintf(line, sizeof line, "frame %d: %.1f ms (budget %.1f ms): operating point -> '%s'", frame, report.seconds * 1e3,
                      controller_->budgetSeconds() * 1e3, controller_->current().name.c_str());
        log_(line);
    }
}

}  // namespace rtwall::wall
