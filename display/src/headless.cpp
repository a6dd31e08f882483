// The headless presenter: what each projector would get, as PNG files, and the wall as a video
// through the ffmpeg program when it is installed.
#include <rtwall/display.h>

#include <cstdio>
#include <optional>
#include <cstdlib>

namespace rtwall {

namespace {
bool haveProgram(const char* name) {
    const std::string cmd = std::string("command -v ") + name + " >/dev/null 2>&1";
    return std::system(cmd.c_str()) == 0;
}
}  // namespace

HeadlessPresenter::HeadlessPresenter(WallConfig wall, std::filesystem::path outDir)
    : wall_(std::move(wall)), out_(std::move(outDir)) {
    if (!wall_.video.empty()) {
        if (!haveProgram("ffmpeg")) {
            std::fprintf(stderr, "rtwall: note: ffmpeg is not installed, no video is written (%s)\n", wall_.video.c_str());
        } else {
            std::filesystem::create_directories(out_);
            const std::string cmd = "ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgb24 -s " + std::to_string(wall_.width) + "x" +
                                    std::to_string(wall_.height) + " -r 30 -i - -pix_fmt yuv420p '" +
                                    (out_ / wall_.video).string() + "'";
            video_ = popen(cmd.c_str(), "w");
        }
    }
}

HeadlessPresenter::~HeadlessPresenter() {
    if (video_) pclose(video_);
}

void HeadlessPresenter::present(const WallFrame& given, const PresentOptions& options) {
    // Paints (the GL presenter's way of drawing over eyes it makes itself) on a copy: a frame
    // comes here with its eye images, which the wand's ray is normally drawn into already.
    std::optional<WallFrame> painted;
    if (!given.paints.empty()) {
        painted = given;
        applyPaints(painted->paints, 0, painted->left);
        applyPaints(painted->paints, 1, painted->right);
    }
    const WallFrame& frame = painted ? *painted : given;
    ++count_;
    if (video_ && frame.left.width == wall_.width && frame.left.height == wall_.height)
        std::fwrite(frame.left.rgb.data(), 1, frame.left.rgb.size(), video_);
    if (wall_.writeEvery <= 0 || count_ % uint64_t(wall_.writeEvery) != 0) return;
    char stem[64];
    std::snprintf(stem, sizeof stem, "frame_%06u_", frame.number);
    for (size_t i = 0; i < wall_.screens.size(); ++i) {
        const ScreenConfig& s = wall_.screens[i];
        const bool quad = s.eye == Eye::Both && wall_.stereo.mode == StereoMode::QuadBuffer;
        for (int eye = 0; eye < (quad ? 2 : 1); ++eye) {
            PresentOptions o = options;
            o.quadBufferEye = eye;
            const std::filesystem::path file = out_ / (stem + s.name + (quad ? (eye ? "_right" : "_left") : "") + ".png");
            writePng(presentScreen(wall_, i, frame, o), file);
            written_.push_back(file);
        }
    }
}

}  // namespace rtwall
