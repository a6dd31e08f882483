// rtwall denoising of stochastic frames (issue 28): temporal reuse and an edge-avoiding filter,
// run on the display side after assembly (a filter must see across tile borders, and the tiles
// of one screen come from different clients). No sockets, no OpenGL.
//
// Per view and frame (DenoiseSettings in rtwall/engine.h says which steps run):
// 1. Temporal reuse: each pixel's point (its depth along its ray) is projected into the previous
//    frame's camera (ImageProjection, rtwall/warp.h: the geometry of the display-rate warp) and
//    its history read there bilinearly, each tap kept only where the previous frame saw the same
//    object, a normal within 25 degrees and a depth within 2 % (+ a pixel's footprint). The new
//    frame joins the history with weight 1/n, n the history's length plus one, at most
//    `history` while the camera moves: a moving view averages its last frames, a still view
//    (the same camera and scene state as the frame before) averages every frame since it
//    stopped, exactly as the Accumulator does, so it converges to the same unbiased mean.
//    The first-hit albedo (FeatureView) and the luminance moments (first and second) of the
//    demodulated sample are averaged alike: the noise's variance per frame. While the view
//    moves, fireflies are clamped (kFireflyRatio in denoise.cpp).
// 2. Demodulate: the averaged colour over the averaged albedo is the illumination, which is
//    smooth where textures are not.
// 3. Svgf: `levels` passes of the a-trous wavelet (5x5 B3 spline, step 2^i) over the
//    illumination, each neighbour weighted by edge stops on depth (relative to the local depth
//    gradient), normal (cosine^sigma_normal), object id (equal or nothing) and luminance
//    (relative to the standard deviation of the noise of the pixel's mean: the variance of the
//    frames divided by their number, itself filtered along): a still view's noise falls with its
//    history, so the filter fades as the mean converges.
// 4. Remodulate by the averaged albedo (temporal alone: the averaged colour as it is).
// A pixel whose sample is not finite (NaN, infinity) keeps its history and is no neighbour to
// anyone in that frame; one with neither takes its valid neighbours' filtered value (or black).
// Background pixels (no hit) show the frame as it is while the view moves; a still view averages
// them as any pixel (a silhouette, hit in some frames and missed in others, converges to the
// mean of all its samples). Deterministic: the same frames give the
// same bytes on any number of threads.
#pragma once

#include <rtwall/engine.h>
#include <rtwall/feature_codec.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace rtwall {

// The features a mode reads (FeatureBits): temporal the normal and the id (with depth), svgf
// also the albedo; off none. What a cluster sends with each tile.
inline uint8_t featureBitsFor(DenoiseSettings::Mode mode) {
    return mode == DenoiseSettings::Mode::Svgf       ? uint8_t(kFeatureAll)
           : mode == DenoiseSettings::Mode::Temporal ? uint8_t(kFeatureNormal | kFeatureId)
                                                     : uint8_t(0);
}

// One machine's frame as a cluster delivers it, in place: the colour at half precision (linear
// tiles), the depth through its 16-bit code, the features of `bits` through theirs (the rest
// emptied). The denoiser then filters the very values it would filter on the wall.
void quantiseAsSent(FeatureFrame& frame, uint8_t bits);

// The pixels a filter reaches beyond a pixel (issue 28): what a window of a frame needs around
// the part of it that is shown (a display node's screen) for the shown pixels to be filtered as
// with the whole frame at hand: the a-trous levels' 2 * (2^levels - 1), their 3x3 noise blurs,
// the 7x7 short-history spread and the 3x3 firefly and gradient neighbourhoods, plus a margin
// for history moved in from outside (8). Temporal alone: the neighbourhoods and the margin.
int denoiseRing(const DenoiseSettings& settings);

// One view's frame as the denoiser reads it: width x height pixels, rows top to bottom. A
// window of a larger frame (a screen and its ring, on a wall of several) says where it lies:
// its pixel (x, y) is the camera's pixel (x0 + x, y0 + y) of a frameWidth x frameHeight image
// (0: the input is the whole frame). History and filter see only the window; a history point
// that moved in from outside it is new there.
struct DenoiseInput {
    int width = 0, height = 0;
    std::span<const float> linear;    // 3 a pixel: this frame's own colour (renderTileLinear)
    std::span<const float> depth;     // 1 a pixel: DepthView's (kBackgroundDepth: background)
    std::span<const float> albedo;    // 3 a pixel: FeatureView's (temporal: may be empty, white)
    std::span<const float> normal;    // 3 a pixel
    std::span<const uint32_t> id;     // 1 a pixel
    CameraDesc camera;                // the camera the frame was rendered with
    uint32_t stateSeq = 0;            // the scene's state: any change discards every history
    int x0 = 0, y0 = 0, frameWidth = 0, frameHeight = 0;  // the window's place (frameWidth 0: the whole frame)
};

// The filter's instruction set, a CPU path of this process (not a scene setting): its tap loop
// 4 lanes wide (SSE2, every x86-64), 8 (AVX2) or 16 (AVX-512); auto the widest this CPU has.
// Every one gives the same bytes (tested), so forcing one only changes the speed.
enum class DenoiseIsa { Auto, Sse2, Avx2, Avx512 };
DenoiseIsa denoiseIsaFromName(const std::string& name);  // auto, sse2, avx2, avx512; else InputError
const char* denoiseIsaName(DenoiseIsa isa);
bool denoiseIsaSupported(DenoiseIsa isa);
DenoiseIsa resolvedDenoiseIsa(DenoiseIsa isa);  // auto: the widest supported
// For every Denoiser of this process from its next frame; InputError for one this CPU lacks.
void setDenoiseIsa(DenoiseIsa isa);
DenoiseIsa denoiseIsa();

// What the last frame did.
struct DenoiseStats {
    bool still = false;     // same camera and state as the frame before: plain accumulation
    bool restarted = false; // no history was usable (first frame, camera cut, new state, new size)
    size_t reused = 0;      // pixels that kept history
    size_t rejected = 0;    // surface pixels whose history was refused (disocclusion, another object)
    size_t invalid = 0;     // samples that were not finite
    size_t clamped = 0;     // fireflies scaled down
    int maxHistory = 0;     // the longest history of any pixel
    DenoiseIsa isa = DenoiseIsa::Sse2;  // the tap loop's instruction set
    // Where the frame's time went, wall seconds of its phases: temporal reuse, the filter's
    // inputs (unit normals, keys, demodulation), the variance, the a-trous levels together,
    // remodulation (with the threads' join).
    struct Seconds {
        double temporal = 0, prepare = 0, variance = 0, atrous = 0, finish = 0;
        double total() const { return temporal + prepare + variance + atrous + finish; }
    } seconds;
};

// The filter's threads (denoise.cpp): started by a Denoiser's first frame, and again when their
// number changes, then woken for each frame; a frame allocates nothing. A copy starts its own.
class DenoiseWorkers;
class DenoiseWorkerPool {
public:
    DenoiseWorkerPool();
    DenoiseWorkerPool(const DenoiseWorkerPool&);
    DenoiseWorkerPool& operator=(const DenoiseWorkerPool&);
    DenoiseWorkerPool(DenoiseWorkerPool&&) noexcept;
    DenoiseWorkerPool& operator=(DenoiseWorkerPool&&) noexcept;
    ~DenoiseWorkerPool();
    std::unique_ptr<DenoiseWorkers> workers;
};

class Denoiser {
public:
    // One frame of the view: returns its denoised linear colour (3 floats a pixel), kept until
    // the next call. Throws std::invalid_argument when a span's size does not match the size.
    // `threads`: 0 one per hardware thread; the bytes are the same for any number. Nothing is
    // allocated after the first frame of a size and thread count (tested): the threads stay.
    std::span<const float> denoise(const DenoiseInput& in, const DenoiseSettings& settings, int threads = 0);
    // Forgets the history: the next frame starts anew (a new size or scene state does so by
    // itself). A camera cut (another named camera, a jump) is the caller's to say; a move is
    // re-projected.
    void reset() { hasPrevious_ = false; }
    const DenoiseStats& stats() const { return stats_; }

private:
    int width_ = 0, height_ = 0;
    int x0_ = 0, y0_ = 0, frameWidth_ = 0, frameHeight_ = 0;  // the last frame's window (a new place restarts)
    bool hasPrevious_ = false;
    CameraDesc previousCamera_;
    uint32_t previousState_ = 0;
    // History (this frame's written over the previous frame's, then swapped).
    std::vector<float> colour_, colourPrev_;      // 3 a pixel: temporally averaged colour
    std::vector<float> albedo_, albedoPrev_;      // 3 a pixel: temporally averaged albedo
    std::vector<float> moments_, momentsPrev_;    // 2 a pixel: mean luminance and mean squared luminance
    std::vector<float> length_, lengthPrev_;      // frames in the history (0: none)
    std::vector<float> depthPrev_, normalPrev_;   // the previous frame's features
    std::vector<uint32_t> idPrev_;
    // Filter buffers.
    std::vector<float> variance_, varianceB_;     // of the mean's luminance
    std::vector<float> filtered_, filteredB_;     // the filter's illumination: planes of red, green, blue
    std::vector<float> unit_;                     // this frame's unit normals: planes of x, y, z
    std::vector<uint32_t> key_, centre_;          // the filter's ids: as a neighbour (none: no value), as a centre
    std::vector<float> rowScratch_;               // per thread: 9 rows of sums and scales
    std::vector<double> reprojected_;             // per thread: a row's places in the previous frame (x, y)
    std::vector<float> gradient_;                 // depth change per pixel step
    std::vector<float> zf_;                       // the filter's depth: finite everywhere (0: no surface)
    std::vector<float> gx_, gy_;                  // signed depth change per pixel step along x and y
    std::vector<uint8_t> valid_;                  // 1: a value (this frame's or history)
    std::vector<uint8_t> known_;                  // valid, or given a value by the filter
    std::vector<float> out_;
    std::vector<DenoiseStats> partStats_;
    DenoiseStats stats_;
    DenoiseWorkerPool pool_;

    void resize(int w, int h);
};

}  // namespace rtwall
