// rtwall tracking: the viewer's head (and the flystick) from a tracking system.
//
// ART DTrack's ASCII output over UDP is read natively: DTrackParser turns one datagram into a
// DTrackFrame (plain code, no sockets; strict: a malformed packet is dropped with one line
// saying what is wrong). Poses are in the tracker's room coordinates, millimetres.
#pragma once

#include <array>
#include <cstdint>
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

}  // namespace rtwall
