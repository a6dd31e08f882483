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
};
// One line for the status overlay: "tracker: head at (x, y, z) m, 12 ms old" or "tracker: no
// head for 1.3 s, holding the last pose".
std::string describeTracker(const TrackerState& state);

// The head body's poses over time: room transform, filter, prediction, timeout. Plain code:
// times are seconds on any monotonic clock, given by the caller.
class HeadTracker {
public:
    explicit HeadTracker(const TrackingConfig& config);
    // A frame that arrived at `time`. False when it does not hold the head body (or not seen).
    bool add(const DTrackFrame& frame, double time);
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
    int port() const;  // the bound port
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
uint64_t playHeadPath(const HeadPath& path, int port, double rate, double seconds, const std::atomic<bool>* stop = nullptr);

}  // namespace rtwall
