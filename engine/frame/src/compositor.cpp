// Compositor (rtwall/frame.h): the one place where views become the eyes' images.
#include <rtwall/frame.h>

#include <algorithm>

namespace rtwall {

namespace {

// The pixels of `view`'s regions, from its image into the eye's (same size).
void copyRegions(Image& eye, const Image& from, const FrameView& view) {
    for (const ViewRegion& g : view.regions) {
        const TileRect r = scaledRegion(g, view.refWidth, view.refHeight, from.width, from.height);
        for (int y = r.y0; y < r.y1; ++y) {
            const size_t row = (size_t(y) * size_t(from.width) + size_t(r.x0)) * 3;
            std::copy(from.rgb.begin() + long(row), from.rgb.begin() + long(row + size_t(r.width()) * 3), eye.rgb.begin() + long(row));
        }
    }
}

}  // namespace

void Compositor::accumulate(const ComposeFrame& f, std::vector<Image>& images, std::span<const std::vector<float>> linear) {
    auto add = [&](Accumulator& sum, size_t v) {
        if (f.linear && v < linear.size()) sum.addLinear(linear[v].data(), images[v].width, images[v].height);
        else sum.add(images[v]);
        images[v] = sum.resolve();
    };
    if (f.views.empty()) {
        if (f.stateSeq != progressiveSeq_) {
            progressive_.reset();
            ++progressiveRestarts_;
        }
        progressiveSeq_ = f.stateSeq;
        add(progressive_, 0);
    } else {
        // A still view refines, view by view: a view restarts when the state changed (any scene
        // change, the navigation camera, the codec) or its own camera did (the head moved its
        // eye, or its plane's frustum); the others keep accumulating.
        if (viewSums_.size() != images.size()) viewSums_ = std::vector<ViewSum>(images.size());
        for (size_t v = 0; v < images.size() && v < f.views.size(); ++v) {
            ViewSum& s = viewSums_[v];
            const CameraDesc& camera = f.views[v].camera;
            if (s.stateSeq != f.stateSeq || !s.camera || !(*s.camera == camera)) {
                s.sum.reset();
                s.stateSeq = f.stateSeq;
                s.camera = camera;
                ++viewRestarts_;
            }
            add(s.sum, v);
        }
    }
    ++accumulatedFrames_;
    linearFrames_ += f.linear;
}

EyeImages Compositor::compose(const ComposeFrame& f, std::vector<Image> images, std::span<const std::vector<float>> linear) {
    EyeImages out;
    if (images.empty()) return out;
    if (f.stochastic) accumulate(f, images, linear);
    else if (f.views.empty()) progressiveSeq_ = UINT32_MAX;  // deterministic: every frame of a state is the same image
    if (f.views.empty()) {
        out.left = std::move(images[0]);
        return out;
    }
    for (size_t v = 0; v < images.size() && v < f.views.size() && v < f.eyes.size(); ++v) {
        Image& eye = f.eyes[v] == 1 ? out.right : out.left;
        if (f.views[v].regions.empty()) {
            eye = std::move(images[v]);
            continue;
        }
        if (eye.rgb.empty()) {
            eye.width = images[v].width;
            eye.height = images[v].height;
            eye.rgb.assign(images[v].rgb.size(), 0);
        }
        copyRegions(eye, images[v], f.views[v]);
    }
    return out;
}

}  // namespace rtwall
