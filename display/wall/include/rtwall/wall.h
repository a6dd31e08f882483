// rtwall wall: the display master as a library, the one public header.
//
// A WallSession is what runs on the wall's PC. It loads the scene, starts the master and the
// local render clients, shows the frames on the wall (GLFW windows, or the headless presenter
// where there is no display), and owns the one scene state the clients hold: navigation,
// picking, `--watch` edits and the operating-point controls all change the scene through it,
// and it sends the differential updates. step() advances one frame. `rtwall run` is argument
// parsing and a loop over step().
//
// Where a change goes:
// - a key binding or other input: WallInput::handle (display/wall/src/wall_input.cpp);
// - a control of the operating point and the speed/accuracy sweep: the table in controls.cpp;
// - a camera-path field: camera_path.cpp (read, write and interpolation, one file);
// - a per-frame step: WallSession::step (session.cpp); the run config: run_config.cpp;
// - a change from another thread (the operator console, display/web): WallSession::post, and
//   the operator's state (bookmarks, flights, measurements, session files): operator.cpp.
//
// The GL presenter stays inside the display library; this library joins it to the engine and
// the cluster, which know nothing of each other's windows.
#pragma once

#include <rtwall/cluster.h>
#include <rtwall/display.h>
#include <rtwall/engine.h>
#include <rtwall/tracking.h>
#include <rtwall/tune.h>

#include <array>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rtwall {

// ---- Display nodes (issue 19) ------------------------------------------------------------------

// The master's settings for a wall whose screens name display nodes: the nodes in the wall's
// order, the config text each is sent, and the tile masks from TileRouting. A frame of views
// routes each view's tiles by its eye (viewEyes[v]: -1 mono, 0 left, 1 right); a view without an
// entry goes to every node that shows either eye of its pixels. `reproject`: the nodes re-project
// (issue 27), and each also gets the ring of tiles (one tile wide) around what its screens show.
// `denoiseRing` > 0: the nodes denoise (issue 28), and each also gets the tiles within that
// many pixels of its screens' windows (denoiseWindows).
DisplayNodeSettings displayNodeSettings(const WallConfig& wall, std::string wallText, std::vector<int> viewEyes = {},
                                        bool reproject = false, int denoiseRing = 0);

// The windows a wall's frame is denoised in (ComposeFrame::denoiseWindows, issue 28), per view of
// a width x height frame (one list for a frame without views): the frame rects of the screens
// of the view's eye (views[v]'s eyes[v]: -1 or none the mono/left eye, 1 the right) that meet
// the view's regions (all of them for a view without regions), overlapping rects (projectors
// blended over each other) merged into their bounding box until none overlap; each with the
// nodes that show a screen of it (TileRouting's bits). The single-PC wall filters all of them,
// a display node those that hold one of its screens: the same windows with the same pixels,
// the same bytes.
struct DenoiseWindow {
    TileRect rect;
    uint64_t nodes = 0;
};
std::vector<std::vector<DenoiseWindow>> denoiseWindows(const TileRouting& routing, int width, int height,
                                                       const std::vector<FrameView>& views, const std::vector<int>& eyes);
// The rects of those windows that `node` shows (bit `node`), or all of them (node < 0).
std::vector<std::vector<TileRect>> denoiseWindowRects(const std::vector<std::vector<DenoiseWindow>>& windows, int node = -1);

// `rtwall display`: one display node of a wall (runDisplayNode), presenting its screens of the
// wall config the master sends (nodeWall) in GLFW windows, or as images in `out` when headless
// or where no window can be opened. A frame the wall released without this node shows nothing
// new; nodes left out of a frame are named in an overlay on the first screen.
struct DisplayNodeOptions {
    std::string connect;                      // the master, tcp://HOST:PORT
    std::string name;                         // the node's name in the wall config
    std::string bind = "tcp://127.0.0.1:0";   // where the render clients send its tiles
    std::string advertise;                    // the host the clients reach it at (DisplayNodeRun::advertise)
    std::filesystem::path keyFile;            // CURVE, as `rtwall client --key`
    std::filesystem::path serverKeyFile;      // the master's public key
    bool headless = false;
    std::filesystem::path out = "out/node";   // headless screens go here (a folder per node name is not made)
    int frames = 0;                           // > 0: exit after presenting this many frames
    int exitAfterIdleMs = 0;                  // > 0: exit when no master answers for this long
    std::filesystem::path capture;            // tests: in windows, each presented frame's screens as read back from GL (frame_NNNNNN_SCREEN.png)
};
int runWallNode(const DisplayNodeOptions& options, const std::atomic<bool>* stop = nullptr);

// Measuring on the wall (key M, docs/design-review.md, "Measuring"): two picked surface points in the scene
// FILE's coordinates (a rebased scene's `origin` added back, in double precision) and their
// distance in scene units (scenes declare no unit).
struct Measurement {
    std::array<double, 3> a{};               // the first point
    std::optional<std::array<double, 3>> b;  // the second, once picked
    double distance = 0;                     // |b - a| once b is set
    bool operator==(const Measurement&) const = default;
};

// ---- The operator's session (issue 31, docs/web-console.md) --------------------------------------

// A named view: the operator console's bookmarks (the keys' Ctrl+digit slots are the navigator's).
struct Bookmark {
    std::string name;
    CameraDesc camera;  // relative to the scene's origin, as every camera of a SceneDesc
    bool operator==(const Bookmark&) const = default;
};
// What a session file brings back (TOML, docs/web-console.md, "Session files"): the viewer's
// camera, the bookmarks, the section planes, the part view (on top of what the scene was loaded
// with), the instances moved away from where the scene put them, and the measurements. Written
// in the scene file's coordinates (the rebased origin added back, in double), so a file survives
// a change of origin.
struct SessionState {
    CameraDesc camera;
    std::vector<Bookmark> bookmarks;
    SectionPlanes sections{};
    PartView parts;
    std::vector<std::pair<uint32_t, Transform>> moved;  // instance, its transform (increasing instances)
    std::vector<Measurement> measurements;              // complete ones (b set)
    bool operator==(const SessionState&) const = default;
};
std::string writeSessionState(const SessionState& state, const SceneDesc& scene);
// Every problem (TOML, unknown keys, an instance or slot out of range, a non-finite number, a
// zero normal, a pattern that names no part of `scene`) is an InputError "NAME:LINE: what".
SessionState parseSessionState(std::string_view text, const std::string& name, const SceneDesc& scene);
SessionState readSessionState(const std::filesystem::path& file, const SceneDesc& scene);

// `rtwall run --web` and the run config's [web] (issue 31): the operator console, an HTTP server
// inside the master (rtwall/web.h, display/web/). Loopback unless told otherwise; a bind to
// another address needs TLS or `insecure`.
struct WebSettings {
    bool enabled = false;
    std::string address = "127.0.0.1";
    int port = 8480;                           // 0: any free port (said at start)
    std::string token;                         // empty: a random one, said at start
    std::filesystem::path certificate, key;    // PEM files: HTTPS
    bool insecure = false;                     // a non-loopback bind without TLS (said loudly)
    double thumbnailsPerSecond = 4;            // the live thumbnail's rate, at most
    int thumbnailWidth = 480;                  // its width in pixels (each eye of a stereo wall)
    bool operator==(const WebSettings&) const = default;
};

// ---- Run configs (configs/README.md, "Run configs") ---------------------------------------------

struct RunConfig {
    std::string scene = "builtin:knots";  // scene file (.toml), mesh file or builtin:NAME
    std::optional<SceneDesc> loaded;      // a scene loaded in code: used instead of loading `scene`
    std::string camera;                   // a camera of the scene by name (empty: its first)
    ClusterSettings cluster;
    int frames = 60;                      // 0: until stopped (in a window: until it is closed)
    bool framesGiven = false;             // a count was asked for: a window closes after it too
    int writeEvery = 30;                  // every Nth frame as PNG (0: never)
    std::filesystem::path out = "out/frames";
    double orbit = 1.0;                   // degrees per frame around the look-at point (no window)
    std::filesystem::path cameraPath;     // keyframes to follow (replaces the orbit)
    int width = 0, height = 0;            // override the scene's image size (0: the scene's)
    std::filesystem::path wall;           // a wall config; empty: one window of the image's size
    std::optional<WallConfig> loadedWall; // a wall given in code (the embedded default's): used instead of loading `wall`
    // Given on the command line only.
    bool headless = false;                // never open windows
    std::optional<bool> reproject;        // --reproject on|off: overrides the wall config's `reproject`
    std::optional<DenoiseSettings::Mode> denoise;  // --denoise / [run] denoise: over the scene's [denoise] mode
    bool watch = false;                   // reload the scene file when it changes on disk
    double targetFps = 0;                 // > 0: hold this frame rate with the operating point
    std::filesystem::path front;          // the measured front for targetFps (empty: calibrate)
    std::filesystem::path trace;          // with targetFps: one CSV line per frame
    PartView parts;                       // --hide, --isolate, --highlight: on top of the scene file's [parts]
    std::filesystem::path session;        // --session / [run] session: a session file restored before the first frame
    WebSettings web;                      // --web / [web]: the operator console (started by the caller: rtwall/web.h)
    // A wall whose screens name display nodes (issue 19): one `rtwall display` process per node
    // on this PC, of clientExecutable (LocalDisplayNodes; the whole wall on one machine), or with
    // clientThreads a headless runWallNode thread per node writing to out/NAME. Off ([cluster]
    // local_display_nodes = false, --no-local-nodes): the nodes are started on their own PCs
    // and the master waits for them.
    bool localDisplayNodes = true;
    // Local render clients: `rtwall client` processes of this executable, or (tests) threads of
    // this process running runClient.
    std::filesystem::path clientExecutable = "/proc/self/exe";
    bool clientThreads = false;
    std::shared_ptr<const ClientFaults> clientFaults;  // tests: what client threads do wrong (rtwall/cluster_testing.h)
    // Where the session's progress lines go (stdout by default).
    std::function<void(const std::string&)> log;

    bool hasWall() const { return loadedWall || !wall.empty(); }
};

// Reads a run config; every problem is an InputError naming the file, line and key.
RunConfig readRunConfig(const std::filesystem::path& file);
// The embedded default of `rtwall run` without a config: the built-in knot field on the reference
// wall (configs/wall/projectors-2x2.toml, built into the binary: 2x2 projectors, 1600x1200), two
// local clients, 60 frames orbiting, every 30th written (and each projector's image of it where
// the wall is headless), the operating point holding kDefaultTargetFps.
RunConfig defaultRunConfig();
// A session that its caller drives by WallSession::step() (tests, the latency bench): headless,
// `localClients` clients on threads of this process, no orbit, no frame count, no PNGs, no
// progress lines; `out` for what it writes all the same. The scene and the wall are the caller's.
RunConfig steppedRunConfig(const std::filesystem::path& out, int localClients = 2);
// The frame rate the embedded default holds (`--target-fps`): interactive on a 2-core PC.
inline constexpr double kDefaultTargetFps = 10.0;

// ---- Controls: what the operating point and the speed/accuracy sweep change ----------------------

// The settings a control acts on.
struct Knobs {
    RenderSettings settings;
    CodecSettings codec;
    float volumeStep = 0;  // > 0: every volume material's ray-march step, in voxels
    // The display side's denoising (issue 28) where a point names it. The cluster must send the
    // features of the most demanding mode of the front (the session asks for them at its start).
    std::optional<DenoiseSettings::Mode> denoise;
};

struct Control {
    const char* name;    // its key in a front's [point.controls]
    const char* option;  // its flag on `rtwall bench tiles` and `rtwall reference`
    const char* help;
    double min, max;     // the values it accepts
    std::vector<double> sweep;  // what tools/speed_accuracy.py sweeps unless a scene says otherwise
    const char* label;   // a value's name in charts: "{}" stands for the value
    void (*apply)(Knobs& knobs, const RenderSettings& base, double value);
    std::vector<std::string> names;  // a whole-number control's values by name (value i: names[i]); else empty
};
// Every control, in one table (controls.cpp). tools/speed_accuracy.py reads it from
// `rtwall controls --json`.
const std::vector<Control>& controls();
// The control of that name, or an InputError naming the operating point and the known names.
const Control& control(const std::string& name, const std::string& point);
std::string controlsJson();

// The settings of an operating point over the base ones (throws InputError for an unknown
// control or a value outside its range).
Knobs knobsOf(const OperatingPoint& point, const RenderSettings& base, const CodecSettings& baseCodec);
// A front written by tools/speed_accuracy.py: [[point]] name, frame_s, error, [point.controls].
std::vector<OperatingPoint> readFront(const std::filesystem::path& file);

// ---- Camera paths (configs/README.md, "Camera paths") --------------------------------------------

// A keyframe: the camera at a frame number; between keys cameras are interpolated linearly,
// after the last the last is held.
struct CameraKey {
    int frame = 0;
    CameraDesc camera;
};
// Positions in the file are world coordinates (double); the keys come relative to the scene's
// rebased `origin`, so a path survives a change of origin, and written paths are the same.
std::vector<CameraKey> readCameraPath(const std::filesystem::path& file, const std::array<double, 3>& origin);
std::string writeCameraPath(const std::vector<CameraKey>& keys, const std::array<double, 3>& origin);
CameraDesc cameraAt(const std::vector<CameraKey>& keys, int frame);
// a's camera moved t of the way to b's (0: a, 1: b): pose and field of view linearly, an up that
// would vanish halfway (opposite ups) the nearer end's. Camera paths and the operator's flights.
CameraDesc mixCameras(const CameraDesc& a, const CameraDesc& b, float t);

// ---- The session ----------------------------------------------------------------------------------

struct RunSummary {
    size_t frames = 0;
    double medianFps = 0;
    double megabytesPerFrame = 0;
    int accumulatedFrames = 0;  // frames of a stochastic scene averaged while the view was still
    int linearFrames = 0;       // of which as linear tiles
    bool onNodes = false;       // display nodes composed the frames (the master holds no pixels)
    // With a target frame rate:
    size_t framesOnTarget = 0;
    uint64_t operatingPointChanges = 0;
    std::string operatingPoint;
    MasterCounters counters;
};
// The lines `rtwall run` prints at the end.
std::string describeSummary(const RunSummary& summary, double targetFps);


// The tracked wand (flystick) as the session's tools see it (docs/tracking.md, "Flystick"): the last
// step's pose in the room and in the world, its buttons and joystick, and what it holds.
struct WandPose {
    Float3 wallPosition, wallDirection;   // wall coordinates (metres); the direction is unit
    std::array<double, 9> wallRotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // body to wall, row-major
    Float3 origin, direction;             // world (scene) coordinates, the navigation applied
    std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};      // body to world, row-major
    std::vector<bool> buttons;
    std::vector<double> controllers;
    float length = 0;                     // of the ray drawn, scene units: to what it points at, else kWandRayLength
    std::optional<uint32_t> dragging;     // the instance it holds
};
constexpr float kWandRayLength = 10.0f;  // metres of the room (times the navigation scale in scene units), when the ray hits nothing

// One picture the wall showed. Without re-projection a step shows its frame once; with it the
// wall shows the newest frame at every refresh while the next one renders, each time warped to
// the head pose read just before (late latching).
struct Presentation {
    std::chrono::steady_clock::time_point at;     // when the presenter had it (headless: took it; GL: swapped)
    std::chrono::steady_clock::time_point posed;  // when its head pose was read
    uint32_t frame = 0;               // the rendered frame it shows
    uint64_t trackerPackets = 0;      // the tracker datagrams counted when its head pose was read
    HeadPose head;                    // that pose (the frusta it shows)
    bool warped = false;              // re-projected (else the frame as rendered)
};

class WallSession {
public:
    // Loads the scene and the wall, starts the master and the local clients, waits for them and,
    // with a target frame rate, takes or measures the front. Throws InputError for any problem
    // of the configs. `stop` (optional) ends the run between frames and interrupts a frame that
    // cannot finish (Master::setStopFlag): a signal handler may set it.
    explicit WallSession(RunConfig config, const std::atomic<bool>* stop = nullptr);
    ~WallSession();
    WallSession(const WallSession&) = delete;
    WallSession& operator=(const WallSession&) = delete;

    // One frame: input, edits, the scripted camera, the render, accumulation, the wall, the
    // controller, files and the progress line. A tile a client failed is one line in the log with
    // the `rtwall render` command that replays it (also when the frame then fails). False once the run is over (its frames done, the
    // wall closed, or stopped), before anything is rendered.
    bool step();

    // The one scene state: what every client holds, and what picking casts rays into.
    const SceneDesc& scene() const;
    CameraDesc camera() const;  // the viewer's camera (each eye of a stereo wall is derived from it)
    void setCamera(const CameraDesc& camera);
    void setInstanceTransform(uint32_t instance, const Transform& transform);
    void setMaterial(uint32_t material, const Material& value);
    void setLight(uint32_t light, const Light& value);
    void setRenderSettings(const RenderSettings& settings);
    // Section plane slot `index` (< kMaxSections), in the scene's coordinates (relative to
    // scene().origin, as lights are): a differential update to every client, O(1), no BVH is
    // rebuilt. It becomes the active plane (the one the section keys move; -1: none). The wall's
    // keys (docs/design-review.md, "Section planes") and a wand come here alike. Throws for a bad slot or a
    // plane that is not finite or has a zero normal, before anything changed.
    void setSection(uint32_t index, const SectionPlane& plane);
    int activeSection() const;
    void setCodec(const CodecSettings& codec);
    // A reloaded scene file: what changed goes out as differential updates; `refused` lists
    // what updates cannot express (and what the camera path or controller owns).
    SceneEdit applyEdit(const SceneDesc& edited);
    // The instance under wall pixel (x, y) for the viewer's camera.
    std::optional<PickResult> pick(double wallX, double wallY);
    // Measure mode (key M toggles it, Esc leaves it): while it is on, a pick sets point A, the
    // next point B (the distance goes to the log and the status line), the next a new A. The
    // wall's Ctrl+click and a wand's button (issue 18) come here alike. measurePick is false
    // (and sets nothing, and the log says so) where the ray hits nothing or the mode is off.
    void setMeasuring(bool on);
    bool measuring() const;
    bool measurePick(double wallX, double wallY);
    // The measurement under way: nothing before A is picked (and after the mode is left).
    std::optional<Measurement> measurement() const;
    void showTileOwners(bool on);  // the false-colour view of who rendered each tile (key T)
    // Parts by name (docs/design-review.md, "Parts"; keys X hide, I isolate, G highlight, U show all, on the part
    // a Ctrl+click picked): `view` on top of what the scene was loaded with (its [parts] and
    // RunConfig::parts). Only the instances whose visibility changes travel. Throws InputError
    // for a pattern that matches nothing, before anything changed. showAllParts also shows what
    // the scene file hid.
    void setPartView(const PartView& view);
    const PartView& partView() const;
    void showAllParts();
    // Input as if from the wall's windows, applied at the next step() (keys, mouse, picking:
    // display.h's InputState): scripted control and tests; it works headless too.
    void inject(const InputState& input);
    // Scene units per metre of the room: the wall's [navigation] scale, as the keys [ and ] left it.
    double navigationScale() const;

    // The tracked head (a wall with [tracking]): what the last step used, and the UDP port the
    // tracker's datagrams go to (0 without tracking).
    std::optional<TrackerState> tracker() const;
    int trackerPort() const;
    const HeadPose& lastHead() const;  // the head the last step's frusta were made for
    // The wand as the last step left it: nothing without a flystick, before its first pose, and
    // after timeout_ms without one. The pose for the session's tools (picking, dragging,
    // measuring; a section plane).
    std::optional<WandPose> wand() const;
    // The tracker datagrams counted (TrackerState::packets) when the head pose of the last
    // shown frame was taken: with async on, the frame shown was specified a step earlier.
    uint64_t shownTrackerPackets() const;
    const HeadPose& shownHead() const;  // and that head (lastHead() with async off)
    // Whether this wall re-projects (the wall config's `reproject`, RunConfig::reproject).
    bool reprojecting() const;
    // The presentations since the last call, oldest first (at most the last 4096 are kept). On
    // display nodes a re-projecting master's presentation is the pose it sent the nodes.
    std::vector<Presentation> takePresentations();
    // On display nodes, re-projecting: the refreshes the nodes answered since the last call, with
    // the time from the pose's latching to each node's answer (at most the last 4096 are kept).
    std::vector<NodeRefreshDelay> takeNodeRefreshes();
    // View accumulations restarted so far (a stochastic scene on a wall with views: a view
    // restarts when the state or its own camera changed).
    size_t viewRestarts() const;

    // ---- The operator console's side (issue 31) ----
    // Thread-safe: `command` runs on the session's thread at the next step(), after the windows'
    // and inject()'s input (the keys', the mouse's and the wand's changes), in the order posted:
    // one scene state, changed only there, and every change a differential update.
    void post(std::function<void(WallSession&)> command);
    // Called on the session's thread at the end of every step(), after the frame was shown (where
    // the console takes its snapshot and thumbnail); it must not block.
    void addStepObserver(std::function<void(const WallSession&)> observer);
    const std::vector<Bookmark>& bookmarks() const;
    void saveBookmark(const std::string& name);  // the viewer's camera now; replaces one of that name
    bool goToBookmark(const std::string& name, double seconds = 0.8);  // false: no such bookmark
    bool deleteBookmark(const std::string& name);
    // The viewer's camera goes to `camera` over `seconds` (smoothstep in time; 0: at once). A
    // scripted orbit stops (the operator took over); a camera path refuses (false).
    bool flyTo(const CameraDesc& camera, double seconds);
    bool flying() const;
    // The measurements kept (measure mode's complete ones, and measureBetween's), oldest first.
    const std::vector<Measurement>& measurements() const;
    // A measurement between what wall pixels a and b show: kept and returned; nothing (and
    // nothing kept) where either ray hits nothing.
    std::optional<Measurement> measureBetween(double ax, double ay, double bx, double by);
    bool deleteMeasurement(size_t index);
    // The operator's state, and the same brought back: camera (at once), bookmarks, sections,
    // part view, moved instances (the others back where the scene put them), measurements.
    SessionState sessionState() const;
    void restoreSession(const SessionState& state);
    const WallConfig& wallConfig() const;
    double frameSeconds() const;  // the last step's, 0 before it
    size_t steps() const;         // frames stepped
    std::string operatingPointName() const;  // with a target frame rate: the point held now; else empty

    // A wall on display nodes (summary().onNodes; the master holds no pixels): a picture of
    // what the nodes present now, each eye `width` pixels across, box-filtered
    // (Master::nodePicture). Any thread, while the session lives; waits at most `timeout`.
    // nullopt: no display node is present (or too many pictures are being taken at once).
    std::optional<NodePicture> nodePicture(int width, std::chrono::milliseconds timeout) const;

    // What the last step showed and measured.
    const WallFrame& lastFrame() const;
    const FrameReport& lastReport() const;
    RunSummary summary() const;
    std::string endpoint() const;
    bool windowed() const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace rtwall
