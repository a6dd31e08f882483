// Compositor (rtwall/frame.h): the one place where views become the eyes' images.
#include <rtwall/frame.h>

#include <algorithm>
#include <stdexcept>
#include <string>

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

// View `view`'s image into its eye's: the whole eye when it has no regions, else the pixels of
// its regions over black (an eye of several views gets each one's).
void placeView(Image& eye, const Image& from, const FrameView& view) {
    if (view.regions.empty()) {
        eye = from;  // copy-assigned: the eye's buffer is reused at the same size
        return;
    }
    if (eye.rgb.empty()) {
        eye.width = from.width;
        eye.height = from.height;
        eye.rgb.assign(from.rgb.size(), 0);
    }
    copyRegions(eye, from, view);
}

}  // namespace

// Whether view v of frame f is denoised: a mode, a linear frame, and the view's depth and the
// features its mode reads, all of the view's size.
bool Compositor::denoises(const ComposeFrame& f, size_t v, const Image& image, std::span<const std::vector<float>> linear) {
    if (f.denoise.mode == DenoiseSettings::Mode::Off || !f.linear || v >= linear.size() || v >= f.depth.size() ||
        v >= f.features.size())
        return false;
    const size_t n = size_t(image.width) * size_t(image.height);
    const FeatureImages& ft = f.features[v];
    const bool albedo = f.denoise.mode != DenoiseSettings::Mode::Svgf || ft.albedo.size() == 3 * n;
    return n > 0 && linear[v].size() == 3 * n && f.depth[v].size() == n && ft.normal.size() == 3 * n && ft.id.size() == n &&
           albedo && (ft.albedo.empty() || ft.albedo.size() == 3 * n);
}

void Compositor::denoise(ViewDenoiser& windows, const ComposeFrame& f, size_t v, const CameraDesc& camera, Image& image,
                         std::span<const std::vector<float>> linear) {
    const FeatureImages& ft = f.features[v];
    const int w = image.width, h = image.height;
    const TileRect whole{0, 0, w, h};
    // The windows of this frame: shown rects clipped to the view, inputs grown by the ring. Other
    // windows than the last frame's start afresh.
    std::span<const TileRect> rects(&whole, 1);
    if (v < f.denoiseWindows.size() && !f.denoiseWindows[v].empty()) rects = f.denoiseWindows[v];
    const int ring = std::max(0, f.denoiseRing);
    auto clip = [&](TileRect r, int grow) {
        return TileRect{std::max(0, r.x0 - grow), std::max(0, r.y0 - grow), std::min(w, r.x1 + grow), std::min(h, r.y1 + grow)};
    };
    bool same = windows.size() == rects.size();
    for (size_t k = 0; same && k < rects.size(); ++k) same = windows[k].shown == clip(rects[k], 0);
    if (!same) {
        windows = ViewDenoiser(rects.size());
        for (size_t k = 0; k < rects.size(); ++k) {
            windows[k].shown = clip(rects[k], 0);
            windows[k].input = clip(rects[k], ring);
        }
    }
    for (DenoiseWindow& win : windows) {
        const TileRect& r = win.input;
        if (r.width() <= 0 || r.height() <= 0 || win.shown.width() <= 0 || win.shown.height() <= 0) continue;
        if (r == whole) {  // the whole view: its buffers as they are
            const DenoiseInput in{w, h, linear[v], f.depth[v], ft.albedo, ft.normal, ft.id, camera, f.sceneSeq};
            const std::span<const float> out = win.denoiser.denoise(in, f.denoise);
            for (int y = win.shown.y0; y < win.shown.y1; ++y) {
                const size_t i = size_t(y) * size_t(w) + size_t(win.shown.x0);
                linearToSrgb8(out.data() + 3 * i, 3 * size_t(win.shown.width()), image.rgb.data() + 3 * i);
            }
            continue;
        }
        // A window: its pixels cut out (rows of the view's buffers), placed in the view.
        const size_t rw = size_t(r.width()), n = rw * size_t(r.height());
        auto cut = [&](const auto& from, auto& to, size_t channels) {
            to.resize(from.empty() ? 0 : n * channels);
            if (from.empty()) return;
            for (int y = r.y0; y < r.y1; ++y) {
                const size_t src = (size_t(y) * size_t(w) + size_t(r.x0)) * channels;
                std::copy(from.begin() + long(src), from.begin() + long(src + rw * channels),
                          to.begin() + long(size_t(y - r.y0) * rw * channels));
            }
        };
        cut(linear[v], win.linear, 3);
        cut(f.depth[v], win.depth, 1);
        cut(ft.albedo, win.albedo, 3);
        cut(ft.normal, win.normal, 3);
        cut(ft.id, win.id, 1);
        DenoiseInput in{r.width(), r.height(), win.linear, win.depth, win.albedo, win.normal, win.id, camera, f.sceneSeq};
        in.x0 = r.x0, in.y0 = r.y0, in.frameWidth = w, in.frameHeight = h;
        const std::span<const float> out = win.denoiser.denoise(in, f.denoise);
        for (int y = win.shown.y0; y < win.shown.y1; ++y) {
            const size_t from = (size_t(y - r.y0) * rw + size_t(win.shown.x0 - r.x0)) * 3;
            const size_t to = (size_t(y) * size_t(w) + size_t(win.shown.x0)) * 3;
            linearToSrgb8(out.data() + from, 3 * size_t(win.shown.width()), image.rgb.data() + to);
        }
    }
    ++denoisedFrames_;
}

void Compositor::accumulate(const ComposeFrame& f, std::vector<Image>& images, std::span<const std::vector<float>> linear) {
    auto add = [&](Accumulator& sum, size_t v) {
        if (f.linear && v < linear.size()) sum.addLinear(linear[v].data(), images[v].width, images[v].height);
        else sum.add(images[v]);
        images[v] = sum.resolve();
    };
    if (f.views.empty() && f.camera && denoises(f, 0, images[0], linear)) {
        denoise(progressiveDenoiser_, f, 0, *f.camera, images[0], linear);
        progressiveDenoising_ = true;
        progressiveSeq_ = UINT32_MAX;  // accumulating again starts afresh
        ++accumulatedFrames_;
        ++linearFrames_;
        return;
    }
    if (progressiveDenoising_) {
        progressiveDenoiser_.clear();
        progressiveDenoising_ = false;
    }
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
            if (denoises(f, v, images[v], linear)) {
                // Denoised: the history goes on across camera moves (re-projected); the
                // denoiser itself restarts on a new state.
                denoise(s.denoiser, f, v, camera, images[v], linear);
                s.denoising = true;
                s.camera.reset();  // accumulating again starts afresh
                continue;
            }
            if (s.denoising) {
                s.denoiser.clear();
                s.denoising = false;
            }
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
    keepWarpSource(f, images);
    if (f.views.empty()) {
        out.left = std::move(images[0]);
        return out;
    }
    for (size_t v = 0; v < images.size() && v < f.views.size() && v < f.eyes.size(); ++v) {
        Image& eye = f.eyes[v] == 1 ? out.right : out.left;
        if (f.views[v].regions.empty()) eye = std::move(images[v]);
        else placeView(eye, images[v], f.views[v]);
    }
    return out;
}

// The composed views (after accumulation) with their depth and cameras become the newest warp
// source; the newest before them, the older one, when it had as many views.
void Compositor::keepWarpSource(const ComposeFrame& f, const std::vector<Image>& images) {
    const size_t n = std::min({images.size(), f.views.size(), f.eyes.size(), f.depth.size()});
    if (!f.keepForWarp || n == 0 || f.depth.size() != images.size()) return;
    std::swap(warpNewest_, warpOlder_);
    if (warpOlder_.size() != n) warpOlder_.clear();  // another set of views: no older source for them
    warpNewest_.resize(n);
    for (size_t v = 0; v < n; ++v) {
        WarpSlot& s = warpNewest_[v];
        s.image = images[v];  // copy-assigned into the slot's buffers
        s.depth.assign(f.depth[v].begin(), f.depth[v].end());
        s.camera = f.views[v].camera;
        s.held = v < f.held.size() ? std::optional<TileRect>(f.held[v]) : std::nullopt;
    }
    warpViews_.assign(f.views.begin(), f.views.begin() + long(n));
    warpEyes_.assign(f.eyes.begin(), f.eyes.begin() + long(n));
    if (warpers_.size() < n) warpers_.resize(n);
}

const EyeImages& Compositor::reproject(std::span<const CameraDesc> targets, const WarpOptions& options, bool debug) {
    const size_t n = warpNewest_.size();
    if (n == 0) throw std::invalid_argument("reproject: no frame with depth was composed");
    if (targets.size() != n)
        throw std::invalid_argument("reproject: " + std::to_string(targets.size()) + " target cameras for " + std::to_string(n) + " views");
    warpedEyes_.left.rgb.clear();  // the capacity stays: placeView refills it
    warpedEyes_.right.rgb.clear();
    for (size_t v = 0; v < n; ++v) {
        const WarpSlot& s = warpNewest_[v];
        const bool older = warpOlder_.size() == n;
        const WarpSource newest{s.image, s.depth, s.camera};
        const WarpSource before = older ? WarpSource{warpOlder_[v].image, warpOlder_[v].depth, warpOlder_[v].camera} : newest;
        WarpOptions o = options;
        if (!o.region) o.region = s.held;
        const WarpedView& w = warpers_[v].warp(newest, targets[v], older ? &before : nullptr, o);
        const Image* shown = &w.image;
        if (debug) {
            warpDebugColours(w, debugView_);
            shown = &debugView_;
        }
        placeView(warpEyes_[v] == 1 ? warpedEyes_.right : warpedEyes_.left, *shown, warpViews_[v]);
    }
    return warpedEyes_;
}

}  // namespace rtwall
