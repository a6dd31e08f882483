// rtwall tracking: the viewer's head (and the flystick) from a tracking system.
//
// ART DTrack's ASCII output over UDP is read natively: DTrackParser turns one datagram into a
// DTrackFrame (plain code, no sockets; strict: a malformed packet is dropped with one line
// saying what is wrong). Poses are in the tracker's room coordinates, millimetres.
// HeadTracker (plain code, fed frames and times) takes the head body into wall coordinates
// through the config's room transform, smooths it (one-euro filter, optional), predicts it to
// display time and holds it after a timeout. TrackerReceiver is the only part with a socket: a
// thread receiving the datagrams into a HeadTracker that the frame loop reads without waiting.
#pragma once

#include <rtwall/display.h>

#include <array>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rtwall {

// ---------------------------------------------------------------------------------------------
// ART DTrack ASCII output (one UDP datagram per measurement frame, lines ending in CR LF):
//   fr <frame counter>
//   ts <seconds since 00:00 UTC>
//   6dcal <calibrated bodies>
//   6d <n> [id qu][sx sy sz][b0 b1 ... b8] ...           (DTrack 1 also sent eta theta phi after sz)
//   6df2 <defined> <n> [id qu nbt nct][sx sy sz][b0 ... b8][bt0 ... ct0 ct1 ...] ...
//   3d <n> [id qu][sx sy sz] ...
// Positions are millimetres; b0..b8 is the rotation matrix body-to-room in column order (b0 b1
// b2 is its first column); qu is the quality, 0..1, and -1 for a flystick that is not seen. A
// flystick's buttons come as ceil(nbt / 32) integers of 32 bits each (button i is bit i % 32 of
// integer i / 32); its controllers (joystick axes) as nct numbers in [-1, 1]. Other line types
// (gl, 6dmt, 6di, ts2, ...) are skipped.

struct DTrackBody {
    int id = 0;
    double quality = 0;                                      // 0..1; < 0: not seen in this frame
    std::array<double, 3> position{};                        // millimetres, room coordinates
    std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // body to room, row-major: R[r][c] = rotation[3 r + c]
    bool operator==(const DTrackBody&) const = default;
};

struct DTrackFlystick {
    DTrackBody pose;
    std::vector<bool> buttons;        // nbt of them
    std::vector<double> controllers;  // nct of them, each in [-1, 1]
    bool operator==(const DTrackFlystick&) const = default;
};

struct DTrackMarker {
    int id = 0;
    double quality = 0;
    std::array<double, 3> position{};  // millimetres
    bool operator==(const DTrackMarker&) const = default;
};

struct DTrackFrame {
    std::optional<uint64_t> frame;           // fr
    std::optional<double> timestamp;         // ts: seconds since 00:00 UTC
    std::optional<int> calibratedBodies;     // 6dcal
    std::vector<DTrackBody> bodies;          // 6d: the bodies seen in this frame
    int definedFlysticks = 0;                // 6df2's first number
    std::vector<DTrackFlystick> flysticks;   // 6df2
    std::vector<DTrackMarker> markers;       // 3d
    std::vector<std::string> skipped;        // identifiers of the lines of other types
    const DTrackBody* body(int id) const;    // the 6d body of that id, if it was seen
    const DTrackFlystick* flystick(int id) const;
    bool operator==(const DTrackFrame&) const = default;
};

// Reads DTrack ASCII datagrams. Every problem drops the whole packet (a half-read frame could
// pair one body's new pose with another's old one) and is described by error() in one line:
// "dtrack packet: line 3 ('6d'): body 2: expected ']' after the quality, found '1.2x'".
class DTrackParser {
public:
    // A datagram's bytes (trailing NUL bytes and white space are allowed).
    std::optional<DTrackFrame> parse(std::string_view packet);
    const std::string& error() const { return error_; }  // the last dropped packet's reason
    uint64_t parsed() const { return parsed_; }
    uint64_t dropped() const { return dropped_; }

    static constexpr size_t kMaxPacket = 65507;  // a UDP datagram's payload over IPv4
    static constexpr int kMaxItems = 256;        // bodies, flysticks or markers in one line
    static constexpr int kMaxButtons = 256;      // buttons or controllers of one flystick

private:
    std::string error_;
    uint64_t parsed_ = 0, dropped_ = 0;
};

// Writes a frame as DTrack does (CR LF line ends; positions to 1 µm, rotations and controllers
// to 6 decimals), for the tracker simulator and the tests; parsing it back gives the frame to
// that precision.
std::string writeDTrackPacket(const DTrackFrame& frame);

// ---------------------------------------------------------------------------------------------
// VRPN: the client side of what a tracker needs (docs/tracking.md, VRPN), written from VRPN 07's
// protocol description (Format_Of_Protocol.txt) and sources. A session over TCP: both sides
// send a 24-byte cookie "vrpn: ver. 07.xx  L" (L: the remote log mode, '0'..'3'; NUL padded),
// then messages, each a header of six 32-bit big-endian integers (length = 24 + payload length,
// seconds, microseconds, sender, type, a sequence number) and the payload padded to 8 bytes.
// Negative types are the connection's own: -1 names a sender (payload: int32 length of the name
// with its NUL, the name, NUL), -2 a type (the same), -3 offers a UDP port (sender: the port,
// payload: the address, NUL). Reports name their sender and type by those ids:
//   "vrpn_Tracker Pos_Quat": int32 sensor, int32 (padding), float64 position[3], quaternion[4] (x y z w)
//   "vrpn_Button Change":    int32 button, int32 state (0 up, 1 down)
//   "vrpn_Button States":    int32 count, int32 state each
//   "vrpn_Analog Channel":   float64 count, float64 value each
// (all big-endian). Other types (velocities, pings, ...) are skipped. The same messages, without
// the cookie, come in UDP datagrams when the client offers a UDP port.

// Turns a VRPN byte stream into tracker frames as DTrack would send them: a pose of the head
// sensor (`head_body`) is a 6d body of that id; a pose of the wand sensor (`flystick`), and every
// change of the buttons and analog channels, a flystick of that id with the device's buttons and
// channels as its buttons and controllers. Times are the messages' own (seconds of the day, UTC,
// as DTrack's `ts`). Plain code, no sockets.
class VrpnParser {
public:
    explicit VrpnParser(const TrackingConfig& config);
    // Bytes of the TCP stream as they come (any split). A broken stream (a bad cookie, a message
    // length that cannot be, a name that cannot be) ends the session: failed() turns true and
    // error() says why in one line; nothing more is parsed. A malformed report is dropped, with
    // its reason in error() (dropped() counts them). Each call's frames are appended to `out`.
    void feed(std::string_view bytes, std::vector<DTrackFrame>& out);
    // A UDP datagram of whole messages (no cookie); a malformed one is dropped whole.
    void datagram(std::string_view bytes, std::vector<DTrackFrame>& out);
    bool connected() const { return cookie_; }  // the server's cookie was read
    bool failed() const { return failed_; }
    const std::string& error() const { return error_; }
    uint64_t dropped() const { return dropped_; }
    uint64_t messages() const { return messages_; }
    std::optional<int> udpPortOffered() const { return udpOffer_; }  // the server's -3, if any

    static constexpr size_t kCookieSize = 24;
    static constexpr size_t kHeaderSize = 24;
    static constexpr size_t kMaxPayload = 65536;  // far above any tracker report; more cannot be a VRPN message we read
    static constexpr int kMaxChannels = 256;      // buttons or analog channels of one device (VRPN: 256 and 128)

private:
    TrackingConfig config_;
    std::string buffer_;  // stream bytes not yet parsed
    bool cookie_ = false, failed_ = false;
    std::string error_;
    uint64_t dropped_ = 0, messages_ = 0;
    std::optional<int> udpOffer_;
    std::vector<std::string> senders_, types_;  // by the server's ids
    std::vector<bool> buttons_;
    std::vector<double> channels_;
    std::optional<DTrackBody> wand_;            // the wand's last pose
    // One message; false (and error_) when the stream cannot go on.
    bool message(std::string_view header, std::string_view payload, std::vector<DTrackFrame>& out);
    // Its steps: a sender or type name (false: the stream cannot go on), a tracker pose, and the
    // button and analog reports (false: dropped, with the reason in error_). `where` names the
    // message for the drop's reason.
    bool describe(int32_t type, int32_t id, std::string_view payload);
    void poseReport(const std::string& where, std::string_view payload, double time, std::vector<DTrackFrame>& out);
    bool buttonChange(const std::string& where, std::string_view payload);
    bool buttonStates(const std::string& where, std::string_view payload);
    bool analogReport(const std::string& where, std::string_view payload);
    void drop(const std::string& why);
    bool fail(const std::string& why);
    DTrackFrame wandFrame(double time) const;
};

// The bytes a VRPN peer sends (the tests' recorded sessions, the fuzz corpus, a test server).
std::string vrpnCookie(char logMode = '0');
std::string vrpnMessage(int32_t sender, int32_t type, double unixSeconds, std::string_view payload);
std::string vrpnName(int32_t id, int32_t kind, std::string_view name);  // kind -1: a sender, -2: a type
std::string vrpnPosQuat(int32_t sensor, const std::array<double, 3>& position, const std::array<double, 4>& xyzw);
std::string vrpnButtonChange(int32_t button, int32_t state);
std::string vrpnButtonStates(const std::vector<bool>& states);
std::string vrpnAnalog(const std::vector<double>& channels);

// ---------------------------------------------------------------------------------------------
// The head in wall coordinates

// Tracker room coordinates to wall coordinates (metres): wall = rotation * (scale * room) + translate.
struct RoomTransform {
    std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
    double scale = 0.001;
    std::array<double, 3> translate{};
    std::array<double, 3> point(const std::array<double, 3>& room) const;
    std::array<double, 3> direction(const std::array<double, 3>& room) const;  // rotation only
};
RoomTransform roomTransform(const TrackingConfig& config);

// The pose of a DTrack body (millimetres, room axes) in wall coordinates.
HeadPose headPoseOf(const DTrackBody& body, const RoomTransform& room);

// One-euro filter (Casiez, Roussel and Vogel, CHI 2012) of one value: a low-pass filter whose
// cutoff rises with the speed, so a still head does not jitter and a moving one does not lag.
class OneEuroFilter {
public:
    OneEuroFilter(double minCutoff, double beta, double derivativeCutoff);
    double operator()(double value, double time);  // time in seconds, increasing
    void reset() { primed_ = false; }

private:
    double minCutoff_, beta_, derivativeCutoff_;
    bool primed_ = false;
    double value_ = 0, derivative_ = 0, time_ = 0;
};

// One-euro filter of an orientation: the same adaptive cutoff, driven by the angular speed, and
// the smoothing step a slerp from the filtered quaternion towards the new one (q and -q are the
// same turn: the new one is taken on the filtered one's side).
class OneEuroRotationFilter {
public:
    OneEuroRotationFilter(double minCutoff, double beta, double derivativeCutoff);
    // A quaternion (w, x, y, z), unit; returns the filtered one (unit).
    std::array<double, 4> operator()(const std::array<double, 4>& q, double time);
    void reset() { primed_ = false; }

private:
    double minCutoff_, beta_, derivativeCutoff_;
    bool primed_ = false;
    std::array<double, 4> value_{1, 0, 0, 0};
    double speed_ = 0, time_ = 0;  // filtered angular speed, radians per second
};
// A rotation matrix (row-major, orthonormal) as a unit quaternion (w, x, y, z) and back.
std::array<double, 4> quaternionOf(const std::array<double, 9>& rotation);
std::array<double, 9> rotationOf(const std::array<double, 4>& quaternion);
// Spherical interpolation from a to b (unit quaternions, the shorter way round).
std::array<double, 4> slerp(const std::array<double, 4>& a, const std::array<double, 4>& b, double t);

// One change of a flystick button, as the tracker reported it. The buttons are read once a
// frame, the tracker sends 60 or more datagrams a second: a click shorter than a frame is seen
// only as the two changes it made.
struct ButtonEvent {
    uint64_t seq = 0;      // 1, 2, ... over the tracker's life: a reader keeps the last one it acted on
    int button = 0;
    bool pressed = false;  // down; false: up
    bool operator==(const ButtonEvent&) const = default;
};

// The flystick (wand) in wall coordinates, as the last frame gave it (filtered, not predicted:
// a pointer that runs ahead of the hand is worse than one 10 ms late).
struct WandState {
    bool seen = false;                  // a pose has arrived
    bool stale = false;                 // none for timeout_ms (buttons and joystick count as released)
    bool visible = false;               // the last frame saw it (a flystick not seen keeps its last pose)
    Float3 position{};                  // wall coordinates, metres
    std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // body to wall, row-major
    Float3 direction{0, 0, -1};         // where it points (wand_direction turned into the wall), unit
    std::vector<bool> buttons;
    std::vector<double> controllers;    // joystick axes, [-1, 1]
    bool button(int i) const { return !stale && i >= 0 && size_t(i) < buttons.size() && buttons[size_t(i)]; }
    double controller(int i) const { return !stale && i >= 0 && size_t(i) < controllers.size() ? controllers[size_t(i)] : 0.0; }
    // Every press and release, in order, the last kMaxButtonEvents of them (oldest first).
    std::vector<ButtonEvent> events;
    // Those after `after` (the seq of the last one the reader acted on), oldest first; `lost`
    // (optional) is set to how many after it are no longer kept.
    std::vector<ButtonEvent> eventsAfter(uint64_t after, uint64_t* lost = nullptr) const;
    uint64_t lastEvent() const { return events.empty() ? 0 : events.back().seq; }
    static constexpr size_t kMaxButtonEvents = 64;  // 32 clicks: far more than a hand makes in one frame
};

// What the frame loop knows of the head.
struct TrackerState {
    bool seen = false;       // a pose of the head body has arrived
    bool stale = false;      // none for timeout_ms: `head` is the last one, held (not predicted)
    double age = 0;          // seconds since the last pose
    HeadPose head;           // wall coordinates, filtered and predicted to the display time
    Float3 velocity{};       // metres per second, the prediction's estimate
    uint64_t packets = 0;    // datagrams read
    uint64_t dropped = 0;    // malformed ones
    std::string lastError;   // why the last one was dropped
    // From the tracker's own timestamps (DTrack `ts`, VRPN's message times), where the wall's
    // clock and the tracker's agree (NTP or PTP: a transit time in [0, 1) s): the last frame's
    // time from measurement to arrival. The age and the prediction count from the measurement.
    std::optional<double> latency;
    WandState wand;          // the flystick of [tracking] `flystick` (seen = false without one)
};
// One line for the status overlay: "tracker: head at (x, y, z) m, 12 ms old" or "tracker: no
// head for 1.3 s, holding the last pose".
std::string describeTracker(const TrackerState& state);

// The head body's poses over time: room transform, filter, prediction, timeout. Plain code:
// times are seconds on any monotonic clock, given by the caller.
class HeadTracker {
public:
    explicit HeadTracker(const TrackingConfig& config);
    // A frame that arrived at `time` (the monotonic clock; `arrivalUtc`: the same moment in
    // seconds since 00:00 UTC, for the frame's own timestamp). Poses are filtered and their
    // velocity is fitted at the times they were measured: from the timestamp where the frame has
    // one (mapped onto the monotonic clock by the fastest transit seen, so network jitter does
    // not shake the velocity; by the measured transit where the clocks agree), else on arrival.
    // False when it does not hold the head body (or not seen); the wand is taken either way.
    bool add(const DTrackFrame& frame, double time, std::optional<double> arrivalUtc = std::nullopt);
    // The head for an image shown at `time` + the prediction (prediction_ms): the last pose moved
    // at the estimated velocity; held as it was when no pose came for timeout_ms.
    TrackerState at(double time) const;
    void setPredictionSeconds(double seconds) { prediction_ = seconds; }
    void countDropped(const std::string& why);
    static constexpr double kVelocityWindow = 0.05;  // seconds of poses the velocity is fitted to

private:
    TrackingConfig config_;
    RoomTransform room_;
    double prediction_ = 0;
    std::array<OneEuroFilter, 3> filters_;
    OneEuroRotationFilter headRotation_, wandRotation_;
    std::array<OneEuroFilter, 3> wandFilters_;
    WandState wand_;
    double wandTime_ = 0;
    void recordButtonChanges(const std::vector<bool>& buttons);  // against wand_.buttons, into wand_.events
    // Tracker timestamps onto the monotonic clock: offset = min(arrival - timestamp) since the
    // tracker's clock last went back (a restart, midnight UTC).
    std::optional<double> clockOffset_;
    double lastStamp_ = 0;
    std::optional<double> latency_;
    double sampleTime(const DTrackFrame& frame, double time, std::optional<double> arrivalUtc);
    struct Sample {
        double time;
        std::array<double, 3> position;
    };
    std::vector<Sample> recent_;  // within kVelocityWindow of the last, oldest first
    HeadPose last_;
    bool seen_ = false;
    double lastTime_ = 0;
    uint64_t packets_ = 0, dropped_ = 0;
    std::string lastError_;
    std::array<double, 3> velocity() const;
};

// Receives DTrack datagrams on the config's UDP address and port on a thread of its own and
// keeps the latest head in a HeadTracker; state() never waits for the network. Throws
// InputError naming the source when the port cannot be opened. Port 0 (tests) picks a free one.
class TrackerReceiver {
public:
    explicit TrackerReceiver(const TrackingConfig& config);
    ~TrackerReceiver();
    TrackerReceiver(const TrackerReceiver&) = delete;
    TrackerReceiver& operator=(const TrackerReceiver&) = delete;
    int port() const;  // the bound UDP port (DTrack), or the VRPN server's port
    // The head for an image shown now (plus the prediction).
    TrackerState state() const;
    TrackerState state(std::chrono::steady_clock::time_point now) const;
    static double seconds(std::chrono::steady_clock::time_point t);  // the clock HeadTracker is fed with
    // What the receive thread has to say since the last call (a dropped datagram's reason, one
    // line per 100 at most; the thread stopping), for the owner's thread to log: the owner's
    // log need not be thread-safe. At most 16 lines wait; more are counted in one last line.
    std::vector<std::string> takeMessages();

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------------------------------------
// Head paths and the tracker simulator

// A head path (configs/README.md, "Head paths"): keyframes of the head body in the tracker's
// room (millimetres, degrees), linearly interpolated and held after the last; scripted by hand
// or converted from a recording (a key per recorded frame).
struct HeadKey {
    double time = 0;                 // seconds from the start, increasing
    std::array<double, 3> position{};  // millimetres, tracker room coordinates
    std::array<double, 3> rotate{};    // degrees: the body turned about the room's x, then y, then z
};
struct HeadPath {
    int body = 0;                    // the 6d body id it is sent as
    std::vector<HeadKey> keys;
    double duration() const { return keys.empty() ? 0.0 : keys.back().time; }
};
// Throws InputError "<file>:<line>: <context>key '<key>': <what>" for any mistake.
HeadPath readHeadPath(const std::filesystem::path& file);
// The DTrack frame of the path at `time` (seconds; held after the end): fr = frame, ts = time.
DTrackFrame headPathFrame(const HeadPath& path, double time, uint64_t frame);

// Sends DTrack datagrams to a port on 127.0.0.1, and nowhere else (the simulator and the tests).
class DTrackSender {
public:
    explicit DTrackSender(int port);
    ~DTrackSender();
    void send(const DTrackFrame& frame);
    void send(std::string_view datagram);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Plays a path to 127.0.0.1:port at `rate` frames a second for `seconds` (looping the path when
// it is shorter), on the calling thread; returns early when `stop` is set. Returns frames sent.
// Each frame's `ts` is the time of day (UTC) it is sent at, as a DTrack with a synchronised clock.
uint64_t playHeadPath(const HeadPath& path, int port, double rate, double seconds, const std::atomic<bool>* stop = nullptr);

}  // namespace rtwall
