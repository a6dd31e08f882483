// rtwall display: the one public header.
//
// A wall config (TOML, configs/wall/) describes the screens of a tiled display wall: where each
// screen's pixels lie in the wall image, hidden bezel pixels, projector overlap with blending
// ramps, per-screen gamma and brightness, stereo eyes, and which monitor/window each one uses.
// Presenting is split in two: the mapping from a wall image to each screen's pixels is plain
// CPU code (mapPixel, presentScreen), used by the headless presenter and the tests; the GLFW /
// OpenGL 3.3 presenter does the same per pixel in a GLSL shader. The display knows nothing of
// the engine or the cluster: it is given finished wall images.
#pragma once

#include <rtwall/camera.h>
#include <rtwall/image.h>
#include <rtwall/input_error.h>
#include <rtwall/vec.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rtwall {

// ---------------------------------------------------------------------------------------------
// Wall configuration

struct PixelRect {
    int x = 0, y = 0, width = 0, height = 0;  // in wall pixels, origin top-left
    bool operator==(const PixelRect&) const = default;
};

enum class Eye { Mono, Left, Right, Both };          // Both: side-by-side or quad-buffered screens
enum class StereoMode { None, Passive, SideBySide, QuadBuffer };

struct ScreenConfig {
    std::string name;
    PixelRect viewport;               // the wall pixels this screen shows
    int outputWidth = 0;              // the screen's own pixels (default: the viewport's size)
    int outputHeight = 0;
    std::array<int, 4> blend{};       // blending ramp width in wall pixels at the left, right, top, bottom edge
    std::array<double, 4> blendGamma{2.2, 2.2, 2.2, 2.2};  // display gamma the ramps compensate, per edge
    double gamma = 1.0;               // colour correction: out = brightness * in^(1/gamma)
    double brightness = 1.0;
    Eye eye = Eye::Mono;
    int monitor = 0;                  // GLFW monitor index (fullscreen)
    std::array<int, 2> window{0, 0};  // window position (windowed)
    bool fullscreen = false;
    std::filesystem::path fragmentShader;  // replaces the shipped present.frag when set
    // Where the screen is in the room (wall coordinates, metres), for walls whose screens are not
    // one rectangle (a CAVE, an angled wall). Without them the whole wall image is [stereo]'s rectangle.
    bool hasCorners = false;
    Float3 lowerLeft{}, lowerRight{}, upperLeft{};
    // The display node (wall PC) that drives this screen; empty: the master drives it. Either
    // every screen of a wall names a node or none does.
    std::string node;
    int line = 0;                     // where the screen was defined (messages only)
    bool operator==(const ScreenConfig& o) const;  // ignores `line`
};

struct StereoConfig {
    StereoMode mode = StereoMode::None;
    double eyeSeparation = 0.065;  // metres
    Float3 viewer{0, 0, 2};        // tracked or nominal head position, wall coordinates (metres)
    Float3 lowerLeft{-1, -0.75f, 0}, lowerRight{1, -0.75f, 0}, upperLeft{-1, 0.75f, 0};  // physical corners
    bool operator==(const StereoConfig& o) const;
};

// [tracking]: the viewer's head from a tracking system (rtwall/tracking.h reads it). The room
// transform takes the tracker's coordinates to wall coordinates (metres): scale first, then the
// rotation about x, then y, then z (degrees), then the translation.
enum class TrackingFilter { None, OneEuro };
enum class TrackingSource { DTrack, Vrpn };
struct TrackingConfig {
    bool enabled = false;                 // a [tracking] table is present
    std::string source = "dtrack://0.0.0.0:5000";  // where the tracker's UDP datagrams arrive, or "vrpn"
    TrackingSource kind = TrackingSource::DTrack;  // from source
    std::string address = "0.0.0.0";      // from source: the local address to listen on (DTrack);
                                          // from server: the VRPN server's host
    int port = 5000;                      // from source (DTrack), or server (VRPN: 3883 unless given)
    // VRPN (source = "vrpn"): server = "DEVICE@HOST[:PORT]". The head is sensor head_body of the
    // device's tracker, the wand sensor `flystick`; its buttons and joystick are the device's
    // vrpn_Button and vrpn_Analog (or those of the devices named by `buttons` and `analog`).
    std::string server;                   // as written
    std::string device;                   // from server
    std::string buttonDevice, analogDevice;  // default: device
    int headBody = 0;                     // the 6d body on the viewer's head (DTrack's id)
    int flystick = -1;                    // the 6df2 flystick's id (-1: none)
    double roomScale = 0.001;             // tracker units to metres (DTrack: millimetres)
    std::array<double, 3> roomRotate{0, 0, 0};     // degrees about x, then y, then z
    std::array<double, 3> roomTranslate{0, 0, 0};  // metres, applied last
    int timeoutMs = 250;                  // no packet for this long: the last pose is held (and said)
    double predictionMs = 0;              // constant-velocity prediction this far ahead (0: off)
    TrackingFilter filter = TrackingFilter::None;
    double minCutoff = 1.0;               // one-euro filter: cutoff (Hz) of a still head
    double beta = 20.0;                   //   cutoff added per m/s of head speed
    double derivativeCutoff = 1.0;        //   cutoff (Hz) of the speed estimate
    // The flystick (wand): its controls, and how it navigates (docs/tracking.md, "Flystick").
    int buttonPick = 0;                   // held: pick the object the wand points at and drag it
    int buttonMode = 1;                   // pressed: fly <-> orbit
    int buttonHome = 2;                   // pressed: back to the start camera
    int joystickX = 0, joystickY = 1;     // controller indices of the joystick's axes
    double flySpeed = 1.0;                // m/s at full deflection (1 m of the room is 1 scene unit)
    double turnSpeed = 45.0;              // degrees per second at full deflection
    double deadZone = 0.1;                // joystick deflections below this count as none
    std::array<double, 3> wandDirection{0, 0, -1};  // where the wand points, in its body's axes
    bool wandRay = true;                  // draw the wand's ray on the wall
    bool operator==(const TrackingConfig&) const = default;
};

// [navigation]: how the physical room (the wall's and the tracker's metres) lies in the scene.
struct NavigationConfig {
    double scale = 1.0;  // scene units per metre: 2 makes the viewer a giant (the world looks half its size)
    bool operator==(const NavigationConfig&) const = default;
};

// [warp] (issue 30, docs/mpcdi.md): the screens a projector calibration covers. Each buffer of
// the MPCDI file is one screen's projector: its pixels are the screen's pixels, and each pixel's
// ray goes from the eye through the surface point the calibration gives it (`direct`), or the
// screen's flat image is resampled through the warp after rendering (`post`, for comparison).
enum class WarpMode { Direct, Post };
struct WarpConfig {
    std::filesystem::path mpcdi;  // the .mpcdi file (relative paths resolved against the config's folder)
    std::vector<std::pair<std::string, std::string>> buffers;  // MPCDI buffer id -> screen name, by id
    WarpMode mode = WarpMode::Direct;
    // Where the file's regions lie in their buffers: y counted from the buffer's top (default;
    // nDisplay's reading) or its bottom (SGCT's, PyMPCDI's); the readers disagree (docs/mpcdi.md).
    bool regionYFromBottom = false;
    // Profile 3d (3D simulation): the calibration's eye point, the apex of its regions' frusta,
    // in room coordinates (default: [stereo] viewer), and the distance of the plane the frusta's
    // rays are fixed on (SGCT's default, 10 m): a tracked or stereo eye looks through those points.
    std::optional<Float3> eyepoint;
    double frustumDistance = 10;
    bool operator==(const WarpConfig&) const = default;
};

struct WallConfig {
    std::filesystem::path file;       // where it was read from (messages, relative shader paths)
    std::string name = "wall";
    int width = 0, height = 0;        // the wall image the renderer produces, bezel pixels included
    bool vsync = true;
    // GLX_NV_swap_group / swap_barrier where the driver has them (off: 0): this PC's windows join
    // swap group `swapGroup`, and with swapBarrier > 0 the group binds to that barrier (a
    // genlocked wall's PCs swap together in hardware, on top of the master's network barrier).
    int swapGroup = 0, swapBarrier = 0;
    // Re-projection (issue 27): every refresh shows the newest rendered frame warped to the head
    // pose read just before the swap. Unset: on for a tracked wall (reprojects()).
    std::optional<bool> reproject;
    bool reprojectDebug = false;  // tint each pixel by where the warp took it from
    double refreshHz = 60;        // presentations a second where no retrace paces them (headless, no vsync)
    bool reprojects() const { return reproject.value_or(tracking.enabled); }
    std::vector<ScreenConfig> screens;
    StereoConfig stereo;
    TrackingConfig tracking;
    NavigationConfig navigation;
    std::optional<WarpConfig> warp;   // projector calibration of some screens ([warp]); none: flat screens
    int writeEvery = 1;               // headless: every Nth frame as per-screen PNGs (0: never)
    std::string video;                // headless: also encode the wall to this file through ffmpeg
    bool operator==(const WallConfig& o) const;  // ignores `file` and screen lines
    // The display nodes its screens name, in the order of their first screen; empty when the
    // master drives every screen itself.
    std::vector<std::string> nodes() const;
};

constexpr size_t kMaxDisplayNodes = 64;  // node sets are 64-bit masks on the tile path
// Letters, digits, '-' and '_', 1 to 32 of them (a node name travels in messages and file names).
bool validNodeName(const std::string& name);

// Reads and validates a wall config (format: configs/README.md, "Wall configs"). Every problem
// is an InputError of one line "<file>:<line>: <context>key '<key>': <what>".
WallConfig loadWallConfig(const std::filesystem::path& file);
WallConfig parseWallConfig(const std::string& text, const std::filesystem::path& nameForMessages);
// Writes a config that loads back to an equal WallConfig (screens always as an explicit list).
std::string writeWallConfig(const WallConfig& wall);
// One window showing the whole image: the default wall of `rtwall run`.
WallConfig singleScreenWall(int width, int height);
// The screens of one display node, in the wall's order, as a wall config of their own: the same
// wall image and stereo, only those screens (what `rtwall display --node NAME` presents).
// Throws std::invalid_argument for a node the wall does not name.
WallConfig nodeWall(const WallConfig& wall, const std::string& node);

// ---------------------------------------------------------------------------------------------
// Tile-to-node routing

// Which display nodes need a tile of a frame: those with a screen that shows one of its pixels.
// Screens sample the wall image at their viewport's pixels (bezel pixels are rendered, shown by
// none); a frame smaller than the wall is upscaled bilinearly, so a screen needs the frame pixels
// its viewport's samples read with a weight above zero. A tile under a bezel or a blending
// overlap may go to two nodes, or four at a corner, one wholly under a bezel to none. Passive
// stereo screens need their eye's image, side-by-side and quad-buffered ones both.
// Plain arithmetic, no sockets: the render client asks it where to send each tile.
class TileRouting {
public:
    // Nodes are wall.nodes(), or one node (the master, named "") for a wall without any.
    TileRouting(const WallConfig& wall, int frameWidth, int frameHeight);
    const std::vector<std::string>& nodes() const { return nodes_; }
    // Bit i: nodes()[i] needs the tile [x0, x1) x [y0, y1) of eye `eye` (0 left/mono, 1 right).
    uint64_t route(int x0, int y0, int x1, int y1, int eye) const;
    // The masks of every tile of the frame cut into tileSize squares, row-major (the engine's
    // makeTiles order, edge tiles cut at the frame's border): the table a frame's tiles travel by.
    std::vector<uint64_t> routeTiles(int tileSize, int eye) const;
    // The frame pixels node i's screens read, per eye (empty rects where it shows no such eye).
    const std::vector<std::array<PixelRect, 2>>& needs(size_t node) const { return needs_.at(node); }
    // Which node owns each frame pixel of eye `eye` among the nodes `nodes` (bits): the lowest
    // numbered whose screens read it, 0xFF where none does (under a bezel). One byte a pixel,
    // row-major: the pixels each node sums for the operator console's picture (issue 31), so
    // that no pixel is counted twice.
    std::vector<uint8_t> owners(int eye, uint64_t nodes) const;

private:
    std::vector<std::string> nodes_;
    int frameWidth_ = 0, frameHeight_ = 0;
    std::vector<std::vector<std::array<PixelRect, 2>>> needs_;  // [node][screen of the node][eye]
};

// ---------------------------------------------------------------------------------------------
// Shaders

struct ShaderSource {
    std::string name;  // file name, for messages
    std::string text;
};
// The shipped shaders (display/shaders/), embedded at build time.
ShaderSource presentVertexShader();
ShaderSource presentFragmentShader();
// The GL re-projection's passes (issue 27, display/shaders/warp_*): a name ending in .vert is a
// vertex shader, .frag a fragment shader.
std::vector<ShaderSource> warpShaders();
// Compiles GLSL 330 core with glslang (no GPU needed). Returns the problems, one line each:
// "<name>:<line>: <message>", empty when it compiles.
std::vector<std::string> checkShader(const ShaderSource& source, bool fragment);
// Everything `rtwall check` does: the config (throws InputError), every shader it uses and the
// projector calibration of its [warp] (checkWarp).
std::vector<std::string> checkWall(const std::filesystem::path& file);
// The shaders and the calibration of a wall already loaded (or given in code).
std::vector<std::string> checkWall(const WallConfig& wall);
struct EyeWindow;
// [warp] against its MPCDI file (docs/mpcdi.md), one line per problem, "<config>: [warp]: ...":
// the file reads; every buffer is mapped and every mapped buffer is in it; each buffer has its
// screen's pixels and its regions tile it; every surface point (a3, sl), screen coordinate
// (2d) or frustum ray from the eye point (3d, where it meets the frame's plane) lies inside the
// screen's frame (its corners, or its part of [stereo]'s rectangle) within 2 % of its size, and
// a surface point no farther from its plane than its diagonal (a wrong geometric unit shows
// there). Empty without [warp].
std::vector<std::string> checkWarp(const WallConfig& wall);
// A screen's frame in wall coordinates (metres): its corners, or its viewport's part of
// [stereo]'s rectangle.
EyeWindow screenFrame(const WallConfig& wall, size_t screen);
// The warps of a wall's calibrated screens (issue 30), for the views' cameras (the warps a
// Camera is made with): per warped screen one ScreenWarp per region of its buffer, over its part
// of the screen's viewport (wall pixels; regionTop places it). A 2D profile becomes offsets in
// wall pixels to where the flat view looks (snapped to 1/1024 pixel, so an identity warp is
// exactly none and a whole-pixel shift exactly that), a3 and sl surface points in metres, and
// 3d the points one frustum distance along each pixel's frustum direction from the eye point;
// `room` is left to each frame's view. The file must have passed checkWarp.
struct WallWarp {
    size_t screen = 0;
    std::vector<ScreenWarp> regions;
};
struct MpcdiFile;
struct MpcdiRegion;
std::vector<WallWarp> wallWarps(const WallConfig& wall, const MpcdiFile& file);
// A region's top row in its buffer, a fraction of the buffer's height from its top: its y, or
// with region_y = "bottom" the y of its bottom counted from the buffer's bottom.
double regionTop(const WarpConfig& warp, const MpcdiRegion& region);

// ---------------------------------------------------------------------------------------------
// Mapping a wall image to the screens (the CPU reference of present.frag)

// One rendered view to be re-projected into an eye's image (issue 27): its newest image, depth
// and camera, optionally the one before it, and the pose to show it for. The pointers are the
// caller's and must live through present().
struct ViewWarp {
    int eye = 0;                      // 0: the left (mono) eye, 1: the right
    std::vector<TileRect> regions;    // its pixels in the eye image, empty: the whole image
    const Image* image = nullptr;
    const std::vector<float>* depth = nullptr;
    CameraDesc camera;                // newest
    const Image* olderImage = nullptr;
    const std::vector<float>* olderDepth = nullptr;
    CameraDesc olderCamera;
    CameraDesc target;
};

// A rectangle of one eye's image painted in one colour over what a frame shows (the wand's ray,
// wandRayPaints), by every presenter once the eye's image is made: uploaded, or warped on the
// GPU, where the eye images never pass through the CPU.
struct EyePaint {
    int eye = 0;    // 0 left/mono, 1 right
    TileRect rect;  // in the eye image's pixels
    std::array<uint8_t, 3> colour{};
};
// Paints `paints` of eye `eye` into `image`, clipped to it.
void applyPaints(const std::vector<EyePaint>& paints, int eye, Image& image);

// A finished frame as the renderer delivers it.
// Its images are the wall's size, or smaller: a frame rendered at a fraction of the wall's
// resolution is shown upscaled (bilinear, pixel centres aligned, edges clamped).
struct WallFrame {
    uint32_t number = 0;
    Image left;                         // the mono image, or the left eye
    Image right;                        // the right eye (stereo walls only; the left's size)
    std::vector<uint32_t> tileOwners;   // client id per tile of the frame (row-major), for the false-colour view
    int tileSize = 0;                   // in the frame's pixels
    // Not empty: the GL presenter makes the eyes' images on the GPU from these (each view warped
    // to its target as Reprojector::warp does, written into its regions of its eye, the rest of
    // an eye black, as the Compositor composes) instead of uploading left and right; all views
    // are of one size, the frame's. warpDebug: the warp's debug view (warpDebugColours' tints).
    std::vector<ViewWarp> warps;
    bool warpDebug = false;
    std::vector<EyePaint> paints;  // painted over the eyes' images by the presenter (the wand's ray over a GPU warp)
};
// Throws std::invalid_argument, naming `who` and the sizes, for a frame larger than the wall, an
// empty one, or eyes of different sizes.
void checkFrameSize(const WallConfig& wall, const WallFrame& frame, const char* who);

// A per-screen stage (issue 26): a step between the frame's eye images and what a screen shows,
// run on each screen after its pixels are mapped (crop, scale, stereo packing, blend ramps,
// colour correction), stage after stage. Each is written for both presenters, which must give
// the same pixels: apply() for presentScreen (the headless presenter, display nodes without a
// window, the tests), drawGl() for the GL presenter. The status overlay is one (OverlayStage);
// re-projection, denoising and projector warp come as others.
class ScreenStage {
public:
    virtual ~ScreenStage() = default;
    // Screen `screen`'s pixels (outputWidth x outputHeight), in place. `eye`: which eye's buffer
    // of a quad-buffered screen they are (0 left, 1 right); 0 on every other screen, whose
    // pixels show the eyes its packing says (one eye, or both side by side).
    virtual void apply(const WallConfig& wall, size_t screen, int eye, Image& pixels) const = 0;
    // The same in OpenGL 3.3 core: called with screen `screen`'s context current, its viewport
    // set and its back buffer (both of a quad-buffered screen) as the draw framebuffer, after
    // the present shader drew it. Leaves GL_FRAMEBUFFER bound to 0.
    virtual void drawGl(const WallConfig& wall, size_t screen) = 0;
    // Frees what drawGl made: the GL presenter calls it with the first screen's context current
    // before it closes its windows.
    virtual void releaseGl() {}
};

// The status overlay: copied 1:1 (no blending, no correction) to the first screen, kOverlayMargin
// pixels from its top-left, clipped to the screen.
class OverlayStage final : public ScreenStage {
public:
    explicit OverlayStage(const Image* overlay = nullptr) : overlay_(overlay) {}
    void set(const Image* overlay) { overlay_ = overlay; }
    void apply(const WallConfig& wall, size_t screen, int eye, Image& pixels) const override;
    void drawGl(const WallConfig& wall, size_t screen) override;
    void releaseGl() override;

private:
    const Image* overlay_;
    unsigned texture_ = 0, framebuffer_ = 0;  // GL names, in the first screen's context
    int textureWidth_ = 0, textureHeight_ = 0;
};

// A calibrated wall's blend (issue 30, docs/mpcdi.md): each MPCDI region's alpha (intensity)
// and beta (black level) maps on its screen's pixels, applied in linear light before the
// display encoding: out = beta + (1 - beta) * alpha * in, with in and out sRGB (decoded and
// encoded again) and each map's embedded gamma undone. A pixel whose alpha is 1 and beta 0 is
// left as it is, so unit blends change no bit. Screens and regions without maps are untouched.
// Its GL objects live in the presenter's shared context and its windows' (one vertex array
// each); they go with the contexts.
class ProjectorBlendStage final : public ScreenStage {
public:
    // The file must have passed checkWarp for `wall`.
    ProjectorBlendStage(const WallConfig& wall, const MpcdiFile& file);
    ~ProjectorBlendStage() override;
    bool blends(size_t screen) const;  // whether any pixel of the screen changes
    void apply(const WallConfig& wall, size_t screen, int eye, Image& pixels) const override;
    void drawGl(const WallConfig& wall, size_t screen) override;
    void releaseGl() override;

private:
    struct Maps {
        int width = 0, height = 0;
        std::vector<float> alpha, beta;  // 3 a pixel, top row first; empty: nothing blended
    };
    std::vector<Maps> screens_;
    std::array<float, 256> toLinear_{};  // sRGB 8-bit to linear, made once
    struct Gl;
    std::unique_ptr<Gl> gl_;
};

// A calibrated wall's post-warp (issue 30, `[warp] mode = "post"`, the rasteriser's way, for
// comparison with tracing each projector pixel's ray): each warped screen's flat image (its
// viewport of a flat render, as mapped to its pixels) resampled through the warp. A pixel's
// target: for a 2D warp the flat wall position its offset names, for 3D where the ray from the
// eye through its surface point meets the screen's frame (screenFrame); the screen's pixels
// are sampled there bilinearly between pixel centres, clamped at the edges (GL_LINEAR); a pixel
// on no screen or looking off the screen is black. Every stereo packing: each eye's image on a
// screen (its half of a side-by-side screen, its buffer of a quad-buffered one, a passive
// screen's one eye) is warped alone, from that eye. The eyes move (tracking): setEyes before
// each presentation, with the eyes the shown frame was rendered for.
class PostWarpStage final : public ScreenStage {
public:
    PostWarpStage(const WallConfig& wall, const MpcdiFile& file);  // the file must have passed checkWarp
    ~PostWarpStage() override;
    void setEyes(const Float3& left, const Float3& right);          // wall coordinates, metres (at first: the config's viewer)
    void apply(const WallConfig& wall, size_t screen, int eye, Image& pixels) const override;
    void drawGl(const WallConfig& wall, size_t screen) override;
    void releaseGl() override;

private:
    // One eye's image on a screen: columns x0 .. x0 + width of its pixels.
    struct Pane {
        int x0 = 0, width = 0;
        int eye = 0;                   // 0 left (mono), 1 right
        std::vector<Float3> samples;   // per pane pixel, top row first: surface point, or target (x, y) in pane pixels
        // targets() for targetsEye (2D: for any eye), and apply's copy of the flat pixels: kept
        // from frame to frame (one screen is applied by one thread at a time).
        mutable std::vector<float> targets;
        mutable Float3 targetsEye{};
        mutable Image flat;
    };
    struct Screen {
        int width = 0, height = 0;
        bool surface = false;          // 3D points (else 2D: targets fixed)
        bool quad = false;             // each pane is a buffer of its own (quad buffer)
        Float3 lowerLeft, right, up;   // the screen's frame (screenFrame; 3D targets)
        std::vector<Pane> panes;       // empty: not warped
    };
    // Per pane pixel where it samples the pane's flat image, x and y in its pixels (NaN:
    // black); computed again only when the pane's eye has moved (3D points).
    const std::vector<float>& targets(const Screen& s, const Pane& p) const;
    void applyPane(const Screen& s, const Pane& p, Image& pixels) const;
    std::vector<Screen> screens_;
    Float3 eyes_[2]{};
    struct Gl;
    std::unique_ptr<Gl> gl_;
};

struct PresentOptions {
    bool falseColour = false;  // tint every tile with the colour of the client that rendered it
    const Image* overlay = nullptr;  // the status overlay (OverlayStage): drawn after `stages`, on top
    int quadBufferEye = 0;     // quad-buffered screens: which eye presentScreen returns (0 left, 1 right)
    std::vector<ScreenStage*> stages{};  // run on every screen in order (the caller keeps them)
};

struct ScreenSample {
    int wallX = 0, wallY = 0;  // the wall pixel shown
    int eye = 0;               // 0 left/mono, 1 right
    float weight = 1.0f;       // blending multiplier on the encoded value
};

// Which wall pixel an output pixel of a screen shows, and its blending weight.
ScreenSample mapPixel(const ScreenConfig& screen, StereoMode mode, int outX, int outY);
// Linear-light blending ramp (0 at the screen's outer edge, 1 inside) times all edges; the
// encoded weight is this to the power 1/blendGamma per edge.
float blendRamp(int widthPx, float distancePx);
uint8_t correctColour(uint8_t value, float weight, const ScreenConfig& screen);
std::array<uint8_t, 3> ownerColour(uint32_t client);  // fixed palette; grey for nobody
// Text as an image (the status overlay): a built-in 3x5 pixel font scaled by `scale`, light on
// dark, '\n' starts a new line; letters are shown upper-case, characters without a glyph as blanks.
Image textImage(const std::string& text, int scale = 2);
constexpr int kOverlayMargin = 8;
// The image a screen (projector) gets, exactly what the GL presenter draws (within rounding).
Image presentScreen(const WallConfig& wall, size_t screen, const WallFrame& frame, const PresentOptions& options = {});

// ---------------------------------------------------------------------------------------------
// Presenters

struct PresentStats {
    uint64_t frames = 0;
    double uploadSeconds = 0, drawSeconds = 0, swapSeconds = 0;  // totals
    uint64_t late = 0;  // frames shown more than 1.5 refresh intervals after the previous (vsync only)
};

// Writes per-screen PNGs (as the projectors would get them) and optionally a video (ffmpeg).
class HeadlessPresenter {
public:
    HeadlessPresenter(WallConfig wall, std::filesystem::path outDir);
    ~HeadlessPresenter();
    void present(const WallFrame& frame, const PresentOptions& options = {});
    const std::vector<std::filesystem::path>& written() const { return written_; }

private:
    WallConfig wall_;
    std::filesystem::path out_;
    std::vector<std::filesystem::path> written_;
    FILE* video_ = nullptr;
    uint64_t count_ = 0;
};

enum class UploadMethod { TexSubImage, Pbo };
const char* uploadMethodName(UploadMethod m);

// Keyboard and mouse state collected by the GL presenter between two polls.
struct InputState {
    std::array<bool, 512> keyDown{};  // GLFW key codes
    std::vector<int> keysPressed;     // pressed since the last poll (GLFW key codes)
    std::vector<int> modsPressed;     // modifiers of each press (GLFW_MOD_* bits)
    double mouseDx = 0, mouseDy = 0;  // cursor motion with a button held, screen pixels
    double scroll = 0;
    bool leftDown = false, rightDown = false;
    bool leftPressed = false;         // the left button went down since the last poll
    int clickMods = 0;
    double wallX = 0, wallY = 0;      // cursor position in wall pixels (last moved window)
    bool closeRequested = false;
};

// GLFW windows (one per screen, shared contexts), OpenGL 3.3 core, the wall streamed into a
// texture and drawn per screen with present.frag (or the screen's own shader).
class GlPresenter {
public:
    struct Options {
        // glTexSubImage2D measured faster than PBO streaming (docs/benchmarks.md, bench display): with Mesa's
        // llvmpipe a PBO is one more CPU copy, not a DMA transfer. Measure again on a real GPU.
        UploadMethod upload = UploadMethod::TexSubImage;
        bool visible = true;
        int vsyncOverride = -1;  // -1: the config's vsync; 0/1 force it (benchmarks)
    };
    // Null, with the reason in *whyNot, where no window can be opened (no DISPLAY, no GL 3.3).
    static std::unique_ptr<GlPresenter> open(const WallConfig& wall, const Options& options, std::string* whyNot);
    ~GlPresenter();
    GlPresenter(const GlPresenter&) = delete;
    GlPresenter& operator=(const GlPresenter&) = delete;

    // Uploads the frame, draws every screen and swaps them all together. With `capture`, each
    // screen's pixels are read back before the swap (tests).
    void present(const WallFrame& frame, const PresentOptions& options = {}, std::vector<Image>* capture = nullptr);
    InputState poll();
    void setStatus(const std::string& text);  // shown in the first window's title
    const PresentStats& stats() const;
    std::string renderer() const;  // GL_RENDERER
    // WallConfig::swapGroup: the line that said whether the windows joined GLX_NV_swap_group (also
    // on stderr when the presenter opened); empty when the wall asks for no group.
    const std::string& swapGroup() const;

    struct Impl;

private:
    explicit GlPresenter(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------------------------------------
// Navigation

struct ViewPose {
    Float3 position{0, 0, 5};
    Float3 lookAt{0, 0, 0};
    Float3 up{0, 1, 0};
    float fovY = 45.0f;
};

// Off-axis stereo (generalised perspective, Kooima): what one eye sees of the physical wall is the
// wall rectangle as a projection window seen from that eye. Plain floats, no engine types: the
// tools glue turns this into an engine CameraDesc (position = eye, window = lowerLeft/right/up).
struct EyeWindow {
    Float3 eye;                   // the eye's position
    Float3 lowerLeft, right, up;  // the wall: lower-left corner, edge to lower-right, edge to upper-left
};
// Where the viewer's head is and how it is turned, in wall coordinates (metres): tracked
// (rtwall/tracking.h), or the static viewer of the config. The eyes lie on the head's x axis
// (`right`, from the left eye to the right one).
struct HeadPose {
    Float3 position{0, 0, 2};
    Float3 right{1, 0, 0};
    Float3 up{0, 1, 0};
};
// The head a static config assumes: at `viewer`, level, facing the wall: its x axis along the
// wall's lower edge (lowerRight - lowerLeft, normalised), its y axis along the left edge.
HeadPose staticHead(const StereoConfig& stereo);
// eye 0: the left eye, half the separation along -right from the head; 1: the right eye; any
// other: the head's centre (mono walls).
Float3 eyePosition(const HeadPose& head, double eyeSeparation, int eye);
// In wall coordinates (metres): [stereo]'s rectangle seen from an eye of the static head...
EyeWindow wallEyeWindow(const StereoConfig& stereo, int eye);
// ... or of any head (tracked).
EyeWindow wallEyeWindow(const StereoConfig& stereo, const HeadPose& head, int eye);
// What one render of the whole wall image shows to one eye: a projection window spanning the
// image, and the screens it is right for. A wall is one view (one plane: [stereo]'s rectangle,
// or screen corners that line up); a CAVE is one view per plane of screens, each window
// extended from a screen's physical corners over the whole image so that the screen's viewport
// lands on the screen. Screens of the other eye are left out.
struct WallView {
    EyeWindow window;
    std::vector<size_t> screens;  // indices into WallConfig::screens
};
std::vector<WallView> wallViews(const WallConfig& wall, const HeadPose& head, int eye);
// Whether the wall needs off-axis views even without stereo (tracked, or screens with corners).
bool wallHasViews(const WallConfig& wall);
// Maps a wall-coordinate EyeWindow into the world through the navigation pose: the wall frame's
// x, y, z axes become the camera's right, up and back (= -forward) axes, 1 metre becomes `scale`
// world units (NavigationConfig::scale), and the viewer's physical head position `viewer`
// becomes the camera position. So the pose steers the whole physical room through the scene;
// pose.fovY is unused. Scale 1 gives the very floats the unscaled map gives.
EyeWindow eyeWindowInWorld(const EyeWindow& wall, const Float3& viewer, const ViewPose& pose, double scale = 1.0);
// That map on its own (a turn, the scale and a move): where a tracked wand in the room is in the world.
// It is core's RoomToWorld (rtwall/camera.h), which a calibrated screen's rays use too: origin is
// the camera position (where `viewer` lands), x, y, z the wall's axes in the world (the camera's
// right, up and back, unit), scale world units per metre.
using WallToWorld = RoomToWorld;
WallToWorld wallToWorld(const Float3& viewer, const ViewPose& pose, double scale = 1.0);
// The navigation pose that shows the room at `newScale` world units per metre with the wall
// point `fixed` (the head, between the eyes) where it was in the world at `scale`: the room
// grows or shrinks about it, so the viewer stays put in the scene and the world about them
// looks smaller or larger. The pose only moves (it does not turn).
ViewPose rescaledPose(const ViewPose& pose, const Float3& viewer, double scale, double newScale, const Float3& fixed);

// The wand's ray on the wall, drawn into one eye's image of the whole wall (a frame smaller than
// the wall is drawn at its scale): the segment from `from` to `to` (wall coordinates, metres) as
// that eye sees it, i.e. projected from the eye onto each view's plane of screens and clipped to
// the screens of that view; the part behind the eye is cut off. Per eye, so it has the right
// parallax in stereo; it is drawn over the scene (not hidden by it: it ends where it hits).
void drawWandRay(const WallConfig& wall, const HeadPose& head, int eye, const Float3& from, const Float3& to, Image& image,
                 std::array<uint8_t, 3> colour = {255, 230, 40});
// The same ray as the rectangles it paints into an eye image of width x height (appended to
// `out`, runs of the line merged): for a presenter that makes the eye images itself.
void wandRayPaints(const WallConfig& wall, const HeadPose& head, int eye, const Float3& from, const Float3& to, int width,
                   int height, std::vector<EyePaint>& out, std::array<uint8_t, 3> colour = {255, 230, 40});

// Fly (WASD + mouse look) and orbit (drag around the look-at point, scroll to zoom), camera
// bookmarks and camera-path recording. Plain state: fed InputState, tested without a window.
class Navigator {
public:
    enum class Mode { Fly, Orbit };
    explicit Navigator(const ViewPose& start, float sceneScale = 1.0f);
    // Applies one poll's input over dt seconds; true when the pose changed.
    bool update(const InputState& input, double dt);
    const ViewPose& pose() const { return pose_; }
    void setPose(const ViewPose& p) { pose_ = p; }
    Mode mode() const { return mode_; }
    void setMode(Mode m) { mode_ = m; }
    // The flystick's joystick over dt seconds (docs/tracking.md, "Flystick"). Fly: y moves along the wand's
    // pointing direction, x turns about the up axis through the camera. Orbit: x turns the camera
    // about the vertical axis through `centre`, y moves it towards the centre (never past it).
    // True when the pose changed.
    struct Wand {
        double x = 0, y = 0;          // joystick deflection in [-1, 1], dead zone already applied
        Float3 direction{0, 0, -1};   // where the wand points, world (unit)
        Float3 centre{0, 0, 0};       // orbit: the scene's centre
        double speed = 1.0;           // world units per second at full deflection
        double turnDegrees = 45.0;    // per second at full deflection
    };
    bool updateWand(const Wand& wand, double dt);
    // Bookmarks 1..9: Ctrl+digit stores, digit recalls.
    bool hasBookmark(int slot) const;
    // Recording (key R): one pose per update while on; the wall writes them as a camera path
    // (rtwall/wall.h, writeCameraPath).
    bool recording() const { return recording_; }
    const std::vector<ViewPose>& recorded() const { return path_; }

private:
    ViewPose pose_;
    Mode mode_ = Mode::Orbit;
    float speed_;
    std::array<ViewPose, 10> bookmarks_{};
    std::array<bool, 10> hasBookmark_{};
    bool recording_ = false;
    std::vector<ViewPose> path_;
};

}  // namespace rtwall
