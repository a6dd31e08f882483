// rtwall frame: the one path from tiles to the images a wall shows (issue 26).
//
// Tiles -> FrameAssembler (one image per view of a frame) -> Compositor (each view accumulated
// when the frame is stochastic, the views composed into the eyes). The master, the display node,
// the single-PC wall and `rtwall render` all go this way; none of them composes pixels itself.
// No sockets and no OpenGL: the library sits below cluster and display.
#pragma once

#include <rtwall/denoise.h>
#include <rtwall/engine.h>
#include <rtwall/feature_codec.h>
#include <rtwall/reproject.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace rtwall {

// ---- Views of a frame ------------------------------------------------------------------------
// Both eyes of a stereo wall, and each plane of screens of a non-coplanar wall (a CAVE), render
// in one frame: one scheduler pass over the tiles of every view, each view with its own
// off-axis camera, assembled into one image per view (Master::setViews, renderViews).

// A rectangle of the wall image (x, y, width, height in pixels of a reference image).
struct ViewRegion {
    int x = 0, y = 0, width = 0, height = 0;
    bool operator==(const ViewRegion&) const = default;
};

// One image of a multi-view frame: its camera and the parts of the image it shows (a CAVE plane
// shows only its screens), in pixels of a refWidth x refHeight image (the wall's), scaled to
// the frame's resolution as the wall scales a smaller frame (scaledRegion). No regions: the
// whole image.
// A calibrated projector's part of a view (issue 30): its pixels (`rect`, in the view's
// reference pixels) look where warp grid `grid` says; the grids are the wall's, sent to each
// render client once (ClusterSettings::warpGrids), so a frame only names them. `room` places
// the room's surface points in the world for this frame (the navigation).
struct WarpRef {
    uint32_t grid = 0;
    ViewRegion rect;
    RoomToWorld room;
    bool operator==(const WarpRef&) const = default;
};

struct FrameView {
    CameraDesc camera;
    std::vector<ViewRegion> regions;
    int refWidth = 0, refHeight = 0;  // also the reference of `warps` (then never 0)
    std::vector<WarpRef> warps{};
    bool operator==(const FrameView&) const = default;
};

// A view's warps in a width x height image of it: each reference's rectangle scaled as
// scaledRegion scales a region, its screen offsets scaled by image pixels per reference pixel.
// A reference to a grid not in `grids` makes it throw std::out_of_range (a client can then not
// render the view).
std::vector<ScreenWarp> frameWarps(const FrameView& view, std::span<const std::shared_ptr<const PixelWarp>> grids,
                                   int width, int height);

// The rasteriser's way, for comparison with tracing each projector pixel's ray (issue 30's
// post-warp): the pixels of `warp`'s rectangle of a width x height image of the view,
// resampled from `flat`, the view rendered flat with `camera` (no warps) at any resolution.
// Each pixel centre's ray through the warp meets the flat image plane; the 8-bit image is
// sampled there bilinearly between pixel centres, clamped at its edges, as a GL texture sampler
// does. A pixel on no screen (NaN) or looking off the flat image is black. `out` gets the
// width x height size (black where new); only the rectangle's pixels are written.
void postWarp(const Image& flat, const CameraDesc& camera, const ScreenWarp& warp, int width, int height, Image& out);

// A tile of a multi-view frame: the view it belongs to and its pixels in that view's image.
struct ViewTile {
    uint32_t view = 0;
    TileRect rect;
};

// A region's pixels in a width x height frame: x0 rounded down, x1 up (a frame smaller than
// the wall still covers every pixel of the region), clipped to the frame.
TileRect scaledRegion(const ViewRegion& region, int refWidth, int refHeight, int width, int height);

// The tiling of a multi-view frame, which master and clients compute alike (a tile's number in
// the protocol indexes it): view by view, the tiles of makeTiles(width, height, tileSize) that
// meet one of the view's regions (all of them without regions), in makeTiles order. A client
// that renders a tile of view v renders it as it would in a frame of v's camera alone.
std::vector<ViewTile> viewTiles(const std::vector<FrameView>& views, int width, int height, int tileSize);

// ---- Assembly --------------------------------------------------------------------------------

// What an assembler holds of a frame besides the 8-bit image of each view. Further channels per
// view (depth, features for a denoiser) join `linear` here: one buffer per view, written through
// the claim of the tile they came with.
struct FrameHolding {
    bool linear = false;  // tiles come as linear RGB too: each view has a linear buffer (3 floats a pixel)
    // Tiles come with depth (issue 27): each view has a depth buffer (a float a pixel, distance
    // along the primary ray, kBackgroundDepth for background), NaN wherever no tile of this frame
    // wrote (outside a view's regions, tiles not routed here): a hole to the warp.
    bool depth = false;
    // Tiles come with the denoiser's features (issue 28; FeatureBits, rtwall/feature_codec.h):
    // each view has the buffers of those bits (FeatureImages), what no tile wrote zero.
    uint8_t features = 0;
    // Routing: `routes[t]` is the node mask of tile t and this assembler is bit `node`; it holds
    // the frame when the tiles routed to it are in (a display node). Null: every tile.
    const std::vector<uint64_t>* routes = nullptr;
    unsigned node = 0;
};

// A view's features (FeatureView's, width x height pixels): albedo and normal 3 floats a pixel,
// id one; the buffers of features a frame does not carry are empty.
struct FeatureImages {
    std::vector<float> albedo, normal;
    std::vector<uint32_t> id;
};

// Gathers a frame's tiles into one image per view, each tile decoded straight into its place at
// most once. Tiles of any other frame, tiles not routed here and repeats are refused. A plain
// class without sockets; claim/commit/release are safe from several decode threads at once
// (atomics per tile: a decode thread never waits for another).
class FrameAssembler {
public:
    // A frame of one image whose tiles are makeTiles(width, height, tileSize), all held here.
    void beginFrame(uint32_t frame, int width, int height, int tileSize);
    // A frame of `views` images of width x height whose tiles are `tiles` (viewTiles). Throws
    // std::invalid_argument when a tile's view is not below `views`, the routes do not match
    // the tiles or the node is not below 64.
    void beginFrame(uint32_t frame, int width, int height, const std::vector<ViewTile>& tiles, uint32_t views,
                    const FrameHolding& options = {});

    enum class Claim { Granted, Stale, Duplicate, NotRouted, Invalid };
    // Reserves tile `tile` of `frame` for writing. Granted: write its pixels into `view` (rect
    // gives the size; of a linear frame also into linearAt(viewOf(tile), rect.x0, rect.y0), of a
    // frame with depth its depth into depthAt), then commit() it, or release() it when decoding
    // failed.
    Claim claim(uint32_t frame, uint32_t tile, TileRect& rect, TileView& view);
    void commit(uint32_t tile);
    void release(uint32_t tile);

    bool complete() const { return done_.load() == expected_; }
    size_t expected() const { return expected_; }  // tiles held here (routed here)
    size_t missing() const { return expected_ - done_.load(); }
    uint32_t frame() const { return frame_; }
    const std::vector<TileRect>& tiles() const { return tiles_; }
    uint32_t viewOf(uint32_t tile) const { return view_.empty() ? 0 : view_[tile]; }
    size_t views() const { return images_.size(); }
    Image& image(size_t view = 0) { return images_[view]; }
    const Image& image(size_t view = 0) const { return images_[view]; }
    // The master takes the images of a complete frame away (std::exchange); the next beginFrame
    // sizes them again.
    std::vector<Image>& images() { return images_; }
    const std::vector<Image>& images() const { return images_; }
    bool linear() const { return linear_; }
    // The master swaps a complete linear frame's buffers with the caller's (renderViews).
    std::vector<std::vector<float>>& linearImages() { return linearImages_; }
    const std::vector<std::vector<float>>& linearImages() const { return linearImages_; }
    float* linearAt(size_t view, int x, int y) {
        return linearImages_[view].data() + (size_t(y) * size_t(images_[view].width) + size_t(x)) * 3;
    }
    bool depth() const { return depth_; }
    // One per view of a frame with depth (width * height floats, row-major); the master swaps a
    // complete frame's buffers with the caller's as the linear ones.
    std::vector<std::vector<float>>& depthImages() { return depthImages_; }
    const std::vector<std::vector<float>>& depthImages() const { return depthImages_; }
    float* depthAt(size_t view, int x, int y) {
        return depthImages_[view].data() + size_t(y) * size_t(images_[view].width) + size_t(x);
    }
    uint8_t features() const { return features_; }
    // One per view of a frame with features; swapped away like the depth.
    std::vector<FeatureImages>& featureImages() { return featureImages_; }
    const std::vector<FeatureImages>& featureImages() const { return featureImages_; }
    // Where a tile at (x, y) of `view` decodes its features: the view's buffers there (null for
    // features the frame does not carry), rows of the view's width.
    FeatureView featuresAt(size_t view, int x, int y) {
        FeatureImages& f = featureImages_[view];
        const size_t w = size_t(images_[view].width), i = size_t(y) * w + size_t(x);
        return {f.albedo.empty() ? nullptr : f.albedo.data() + 3 * i, f.normal.empty() ? nullptr : f.normal.data() + 3 * i,
                f.id.empty() ? nullptr : f.id.data() + i, w};
    }

private:
    uint32_t frame_ = 0;
    std::vector<Image> images_ = std::vector<Image>(1);  // one per view
    std::vector<std::vector<float>> linearImages_;       // one per view of a linear frame
    std::vector<std::vector<float>> depthImages_;        // one per view of a frame with depth
    std::vector<FeatureImages> featureImages_;           // one per view of a frame with features
    bool linear_ = false;
    bool depth_ = false;
    uint8_t features_ = 0;
    std::vector<TileRect> tiles_;
    std::vector<uint32_t> view_;  // each tile's view (empty: all of view 0)
    // 0 missing, 1 being written, 2 done, 3 not routed here
    std::unique_ptr<std::atomic<uint8_t>[]> state_;
    size_t stateSize_ = 0;
    size_t expected_ = 0;
    std::atomic<size_t> done_{0};

    void resize(size_t views, int width, int height, const FrameHolding& holding);
};

// ---- Composition -----------------------------------------------------------------------------

// What the compositor needs to know of a frame besides its images.
struct ComposeFrame {
    // The frame's views (empty: a frame of one image without views, the mono image) and each
    // view's eye: -1 the mono image, 0 the left eye's, 1 the right eye's. A view with regions
    // gives its eye those pixels, one without is the eye's whole image.
    std::vector<FrameView> views;
    std::vector<int> eyes;
    // A stochastic frame refines: frames of one state are summed (per view: of one state and one
    // camera); any change of stateSeq restarts the sums.
    bool stochastic = false;
    uint32_t stateSeq = 0;
    bool linear = false;  // the frame came as linear tiles: sum its linear buffers, not its 8-bit images
    // Per view, the depth its tiles came with (width x height, distance along the primary ray):
    // given, the frame's views become the re-projection's newest source (reproject()).
    std::span<const std::vector<float>> depth{};
    // Denoising (issue 28): a stochastic linear frame whose views came with depth and `features`
    // is denoised view by view (rtwall/denoise.h) instead of accumulated, when denoise.mode is
    // not Off: history re-projected across camera moves, filtered (svgf). Without depth or
    // features (or Off) the frame accumulates as ever.
    DenoiseSettings denoise{};
    std::span<const FeatureImages> features{};
    uint32_t sceneSeq = 0;  // the scene state without camera moves: a change discards the denoiser's history
    std::optional<CameraDesc> camera;  // a frame without views: its camera (the denoiser needs one)
    // Per view, the windows it is denoised in: each rect is filtered with the view's pixels
    // within `denoiseRing` (denoiseRing(), rtwall/denoise.h) of it and none beyond, keeps a
    // history of its own, and gives the view's image its own pixels (the rest stay as they came).
    // A wall of several screens is filtered screen by screen so that a display node, which holds
    // its screens and that ring around them, filters them to the single-PC wall's bytes. No
    // windows for a view (or none given): the whole view is one.
    std::span<const std::vector<TileRect>> denoiseWindows{};
    int denoiseRing = 0;
    // The views with depth become the re-projection's newest source (false: depth for the
    // denoiser only).
    bool keepForWarp = true;
    // Per view, the part of it this compositor holds and shows (a display node: the bounding
    // box of its routed tiles; empty where it holds none): reproject() warps only that
    // (WarpOptions::region). A view beyond the span: all of it.
    std::span<const TileRect> held{};
};

struct EyeImages {
    Image left;   // the mono image, or the left eye's
    Image right;  // the right eye's: empty unless a view is of eye 1
};

// Turns a frame's view images into the images of the eyes, frame after frame: each view of a
// stochastic frame is added to its running mean in linear light (Accumulator), which restarts
// when the state or the view's camera changes (or the number of views); a frame without views
// has one running mean, which restarts when the state changes. Then the views are composed into
// the eyes. The single-PC wall and the display nodes make the same bytes of the same frames.
class Compositor {
public:
    // `images`: one per view (one for a frame without views); `linear`: the matching linear
    // buffers of a linear frame (used when frame.linear).
    EyeImages compose(const ComposeFrame& frame, std::vector<Image> images,
                      std::span<const std::vector<float>> linear = {});
    // Re-projection (issue 27): the views of the last frame composed with depth (as composed:
    // accumulated when stochastic), each warped from the camera it was rendered with to
    // `targets[v]` (a view's camera for the pose read just before the swap), holes filled from
    // the frame composed with depth before it, then composed into the eyes as compose() does.
    // Targets equal to the rendered cameras give compose()'s bytes. `debug` tints each pixel by
    // where it came from (warpDebugColours). The images stay the compositor's: nothing is
    // allocated after the first frame of a size. Throws std::invalid_argument when no frame with
    // depth was composed or the targets are not one per view.
    const EyeImages& reproject(std::span<const CameraDesc> targets, const WarpOptions& options = {}, bool debug = false);
    size_t reprojectViews() const { return warpNewest_.size(); }  // views of the newest warp source (0: none)
    // The sources themselves, for a presenter that warps on the GPU (WallFrame::warps): view v's
    // newest image, depth and camera; the frame before's (null: none); its view and eye.
    struct WarpSlot {
        Image image;
        std::vector<float> depth;
        CameraDesc camera;
        std::optional<TileRect> held;  // ComposeFrame::held (none: all of the view)
    };
    const WarpSlot& newestSource(size_t view) const { return warpNewest_.at(view); }
    const WarpSlot* olderSource(size_t view) const { return warpOlder_.size() == warpNewest_.size() ? &warpOlder_.at(view) : nullptr; }
    const FrameView& sourceView(size_t view) const { return warpViews_.at(view); }
    int sourceEye(size_t view) const { return warpEyes_.at(view); }
    const WarpedView& warped(size_t view) const { return warpers_.at(view).result(); }  // of the last reproject()
    size_t viewRestarts() const { return viewRestarts_; }       // a view's running mean restarted
    size_t progressiveRestarts() const { return progressiveRestarts_; }  // the mono running mean restarted
    int denoisedFrames() const { return denoisedFrames_; }        // stochastic frames denoised instead
    int accumulatedFrames() const { return accumulatedFrames_; }  // stochastic frames summed
    int linearFrames() const { return linearFrames_; }            // of them, as linear tiles

private:
    // A view's denoising, window by window (ComposeFrame::denoiseWindows): each window's
    // history (frames of any camera, re-projected) and its pixels cut out of the view's.
    struct DenoiseWindow {
        TileRect shown, input;  // input: shown and its ring, inside the view
        Denoiser denoiser;
        std::vector<float> linear, depth, albedo, normal;
        std::vector<uint32_t> id;
    };
    using ViewDenoiser = std::vector<DenoiseWindow>;
    struct ViewSum {
        Accumulator sum;
        uint32_t stateSeq = UINT32_MAX;
        std::optional<CameraDesc> camera;
        ViewDenoiser denoiser;
        bool denoising = false;
    };
    Accumulator progressive_;  // frames without views
    ViewDenoiser progressiveDenoiser_;
    bool progressiveDenoising_ = false;
    uint32_t progressiveSeq_ = UINT32_MAX;
    std::vector<ViewSum> viewSums_;
    size_t viewRestarts_ = 0, progressiveRestarts_ = 0;
    int accumulatedFrames_ = 0, linearFrames_ = 0, denoisedFrames_ = 0;

    std::vector<WarpSlot> warpNewest_, warpOlder_;  // the re-projection's sources; older: the frame before
    std::vector<FrameView> warpViews_;
    std::vector<int> warpEyes_;
    std::vector<Reprojector> warpers_;
    EyeImages warpedEyes_;
    Image debugView_;

    void accumulate(const ComposeFrame& frame, std::vector<Image>& images, std::span<const std::vector<float>> linear);
    static bool denoises(const ComposeFrame& frame, size_t view, const Image& image, std::span<const std::vector<float>> linear);
    void denoise(ViewDenoiser& denoiser, const ComposeFrame& frame, size_t view, const CameraDesc& camera, Image& image,
                 std::span<const std::vector<float>> linear);
    void keepWarpSource(const ComposeFrame& frame, const std::vector<Image>& images);
};

}  // namespace rtwall
