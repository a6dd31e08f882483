// VRPN's wire format, client side: the cookie, message framing, sender and type names, and the
// tracker, button and analog reports (tracking.h has the layout). Plain code; the socket is in
// tracker_receiver.cpp. Every number is read byte by byte, big-endian: no struct is copied.
#include <rtwall/tracking.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>

namespace rtwall {

namespace {

constexpr int32_t kSenderDescription = -1, kTypeDescription = -2, kUdpDescription = -3,  // -4: a log description (skipped)
                  kDisconnect = -5;
constexpr size_t kMaxNames = 4096;  // senders or types one server may name

uint32_t u32(const char* p) {
    return uint32_t(uint8_t(p[0])) << 24 | uint32_t(uint8_t(p[1])) << 16 | uint32_t(uint8_t(p[2])) << 8 | uint32_t(uint8_t(p[3]));
}
int32_t i32(const char* p) { return int32_t(u32(p)); }
double f64(const char* p) { return std::bit_cast<double>(uint64_t(u32(p)) << 32 | u32(p + 4)); }

void putU32(std::string& out, uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(char(uint8_t(v >> shift)));
}
void putF64(std::string& out, double v) {
    const uint64_t b = std::bit_cast<uint64_t>(v);
    putU32(out, uint32_t(b >> 32));
    putU32(out, uint32_t(b));
}

size_t padded(size_t n) { return (n + 7) / 8 * 8; }

std::string printable(std::string_view s) {
    std::string out;
    for (char c : s.substr(0, 40)) out += std::isprint(uint8_t(c)) ? c : '?';
    return out;
}

}  // namespace

std::string vrpnCookie(char logMode) {
    std::string c = "vrpn: ver. 07.35  ";
    c += logMode;
    c.resize(VrpnParser::kCookieSize, '\0');
    return c;
}

std::string vrpnMessage(int32_t sender, int32_t type, double unixSeconds, std::string_view payload) {
    std::string out;
    const double whole = std::floor(unixSeconds);
    putU32(out, uint32_t(VrpnParser::kHeaderSize + payload.size()));
    putU32(out, uint32_t(int64_t(whole)));
    putU32(out, uint32_t(std::min(999999.0, std::round((unixSeconds - whole) * 1e6))));
    putU32(out, uint32_t(sender));
    putU32(out, uint32_t(type));
    putU32(out, 0);  // the sequence number: for sniffers only
    out.append(payload);
    out.resize(VrpnParser::kHeaderSize + padded(payload.size()), '\0');
    return out;
}

std::string vrpnName(int32_t id, int32_t kind, std::string_view name) {
    std::string payload;
    putU32(payload, uint32_t(name.size() + 1));
    payload.append(name);
    payload.push_back('\0');
    return vrpnMessage(id, kind, 0, payload);
}

std::string vrpnPosQuat(int32_t sensor, const std::array<double, 3>& position, const std::array<double, 4>& xyzw) {
    std::string p;
    putU32(p, uint32_t(sensor));
    putU32(p, uint32_t(sensor));  // VRPN repeats it to align the doubles
    for (double v : position) putF64(p, v);
    for (double v : xyzw) putF64(p, v);
    return p;
}

std::string vrpnButtonChange(int32_t button, int32_t state) {
    std::string p;
    putU32(p, uint32_t(button));
    putU32(p, uint32_t(state));
    return p;
}

std::string vrpnButtonStates(const std::vector<bool>& states) {
    std::string p;
    putU32(p, uint32_t(states.size()));
    for (bool b : states) putU32(p, b ? 1 : 0);
    return p;
}

std::string vrpnAnalog(const std::vector<double>& channels) {
    std::string p;
    putF64(p, double(channels.size()));
    for (double v : channels) putF64(p, v);
    return p;
}

VrpnParser::VrpnParser(const TrackingConfig& config) : config_(config) {}

void VrpnParser::drop(const std::string& why) {
    ++dropped_;
    error_ = "vrpn message: " + why;
}

bool VrpnParser::fail(const std::string& why) {
    failed_ = true;
    error_ = "vrpn session: " + why;
    buffer_.clear();
    return false;
}

DTrackFrame VrpnParser::wandFrame(double time) const {
    DTrackFrame f;
    f.timestamp = time;
    DTrackFlystick s;
    if (wand_) s.pose = *wand_;
    else s.pose.quality = -1;  // buttons before the first pose
    s.pose.id = config_.flystick;
    s.buttons = buttons_;
    s.controllers = channels_;
    f.definedFlysticks = config_.flystick + 1;
    f.flysticks.push_back(std::move(s));
    return f;
}

void VrpnParser::feed(std::string_view bytes, std::vector<DTrackFrame>& out) {
    if (failed_) return;
    buffer_.append(bytes);
    size_t at = 0;
    if (!cookie_) {
        if (buffer_.size() < kCookieSize) return;
        // The major version must be 07 (VRPN compares through the last '.'); the minor may differ.
        const std::string_view c(buffer_.data(), kCookieSize);
        if (c.substr(0, 14) != "vrpn: ver. 07." || !std::isdigit(uint8_t(c[14])) || !std::isdigit(uint8_t(c[15])) || c[18] < '0' ||
            c[18] > '3') {
            fail("the server's cookie '" + printable(c.substr(0, 19)) + "' is not VRPN version 07.xx");
            return;
        }
        cookie_ = true;
        at = kCookieSize;
    }
    while (buffer_.size() - at >= kHeaderSize) {
        const char* h = buffer_.data() + at;
        const uint32_t length = u32(h);
        if (length < kHeaderSize || length - kHeaderSize > kMaxPayload) {
            fail("a message of " + std::to_string(length) + " bytes (header included), not within [24, " +
                 std::to_string(kHeaderSize + kMaxPayload) + "]");
            return;
        }
        const size_t payload = length - kHeaderSize, whole = kHeaderSize + padded(payload);
        if (buffer_.size() - at < whole) break;
        if (!message(std::string_view(h, kHeaderSize), std::string_view(h + kHeaderSize, payload), out)) return;
        at += whole;
    }
    buffer_.erase(0, at);
}

void VrpnParser::datagram(std::string_view bytes, std::vector<DTrackFrame>& out) {
    if (failed_) return;
    // Checked whole first: a datagram is dropped whole, never half applied.
    size_t at = 0;
    while (at < bytes.size()) {
        if (bytes.size() - at < kHeaderSize) return drop("a UDP datagram ends inside a message header");
        const uint32_t length = u32(bytes.data() + at);
        if (length < kHeaderSize || length - kHeaderSize > kMaxPayload || bytes.size() - at < kHeaderSize + padded(length - kHeaderSize))
            return drop("a UDP datagram with a message of " + std::to_string(length) + " bytes that it does not hold");
        at += kHeaderSize + padded(length - kHeaderSize);
    }
    for (at = 0; at < bytes.size();) {
        const uint32_t length = u32(bytes.data() + at);
        const int32_t type = i32(bytes.data() + at + 16);
        if (type >= kDisconnect && type < 0) return drop("a connection message (type " + std::to_string(type) + ") in a UDP datagram");
        if (!message(bytes.substr(at, kHeaderSize), bytes.substr(at + kHeaderSize, length - kHeaderSize), out)) return;
        at += kHeaderSize + padded(length - kHeaderSize);
    }
}

bool VrpnParser::message(std::string_view header, std::string_view p, std::vector<DTrackFrame>& out) {
    ++messages_;
    const uint32_t seconds = u32(header.data() + 4), micro = u32(header.data() + 8);
    const int32_t sender = i32(header.data() + 12), type = i32(header.data() + 16);
    if (type == kSenderDescription || type == kTypeDescription) return describe(type, sender, p);
    if (type == kUdpDescription) {
        if (sender > 0 && sender <= 65535) udpOffer_ = sender;
        return true;
    }
    if (type < 0) return true;  // log descriptions and the rest of the connection's own
    auto named = [](const std::vector<std::string>& names, int32_t id) -> const std::string* {
        return id >= 0 && size_t(id) < names.size() && !names[size_t(id)].empty() ? &names[size_t(id)] : nullptr;
    };
    const std::string* typeName = named(types_, type);
    const std::string* senderName = named(senders_, sender);
    if (!typeName || !senderName) {
        drop("type " + std::to_string(type) + " from sender " + std::to_string(sender) + ": " + (typeName ? "the sender" : "the type") +
             " was never named");
        return true;
    }
    if (micro >= 1'000'000) {
        drop(printable(*typeName) + " from '" + printable(*senderName) + "': " + std::to_string(micro) + " microseconds");
        return true;
    }
    const double time = double(seconds % 86400) + micro * 1e-6;  // seconds of the day, as DTrack's ts
    const std::string where = printable(*typeName) + " from '" + printable(*senderName) + "': ";
    if (*typeName == "vrpn_Tracker Pos_Quat") {
        if (*senderName == config_.device) poseReport(where, p, time, out);
    } else if (*typeName == "vrpn_Button Change" || *typeName == "vrpn_Button States") {
        if (*senderName != config_.buttonDevice) return true;
        const bool read = *typeName == "vrpn_Button Change" ? buttonChange(where, p) : buttonStates(where, p);
        if (read && config_.flystick >= 0) out.push_back(wandFrame(time));
    } else if (*typeName == "vrpn_Analog Channel") {
        if (*senderName == config_.analogDevice && analogReport(where, p) && config_.flystick >= 0) out.push_back(wandFrame(time));
    }
    return true;  // velocities, pings, text and the rest: not what a tracker needs
}

bool VrpnParser::describe(int32_t type, int32_t id, std::string_view p) {
    const char* what = type == kSenderDescription ? "sender" : "type";
    if (id < 0 || size_t(id) >= kMaxNames)
        return fail(std::string("a ") + what + " id " + std::to_string(id) + " out of [0, " + std::to_string(kMaxNames) + ")");
    if (p.size() < 5 || u32(p.data()) != p.size() - 4 || p.back() != '\0' || p.size() - 5 > 99 ||
        std::memchr(p.data() + 4, '\0', p.size() - 5) != nullptr)
        return fail(std::string("the name of ") + what + " " + std::to_string(id) + " is not a length and a NUL-terminated name of at most 99 characters");
    std::vector<std::string>& names = type == kSenderDescription ? senders_ : types_;
    if (names.size() <= size_t(id)) names.resize(size_t(id) + 1);
    names[size_t(id)] = std::string(p.substr(4, p.size() - 5));
    return true;
}

void VrpnParser::poseReport(const std::string& where, std::string_view p, double time, std::vector<DTrackFrame>& out) {
    if (p.size() != 64) return drop(where + std::to_string(p.size()) + " bytes, not 64");
    const int32_t sensor = i32(p.data());
    std::array<double, 3> pos{};
    std::array<double, 4> q{};  // x y z w
    for (size_t i = 0; i < 3; ++i) pos[i] = f64(p.data() + 8 + 8 * i);
    for (size_t i = 0; i < 4; ++i) q[i] = f64(p.data() + 32 + 8 * i);
    double n = 0;
    for (double c : q) n += c * c;
    n = std::sqrt(n);
    if (!std::isfinite(pos[0] + pos[1] + pos[2]) || std::fabs(pos[0]) > 1e6 || std::fabs(pos[1]) > 1e6 || std::fabs(pos[2]) > 1e6)
        return drop(where + "sensor " + std::to_string(sensor) + ": a position that is not a finite number within 1e6");
    if (!(std::fabs(n - 1) < 1e-3))
        return drop(where + "sensor " + std::to_string(sensor) + ": a quaternion of length " + std::to_string(n) + ", not 1");
    DTrackBody b;
    b.id = sensor;
    b.quality = 1;
    b.position = pos;
    b.rotation = rotationOf({q[3] / n, q[0] / n, q[1] / n, q[2] / n});
    if (sensor == config_.headBody) {
        DTrackFrame f;
        f.timestamp = time;
        f.bodies.push_back(b);
        out.push_back(std::move(f));
    }
    if (sensor == config_.flystick) {
        wand_ = b;
        out.push_back(wandFrame(time));
    }
}

bool VrpnParser::buttonChange(const std::string& where, std::string_view p) {
    if (p.size() != 8) {
        drop(where + std::to_string(p.size()) + " bytes, not 8");
        return false;
    }
    const int32_t button = i32(p.data()), state = i32(p.data() + 4);
    if (button < 0 || button >= kMaxChannels || (state != 0 && state != 1)) {
        drop(where + "button " + std::to_string(button) + " to state " + std::to_string(state) + " (buttons 0.." +
             std::to_string(kMaxChannels - 1) + ", states 0 or 1)");
        return false;
    }
    if (buttons_.size() <= size_t(button)) buttons_.resize(size_t(button) + 1);
    buttons_[size_t(button)] = state == 1;
    return true;
}

bool VrpnParser::buttonStates(const std::string& where, std::string_view p) {
    const int32_t count = p.size() >= 4 ? i32(p.data()) : -1;
    if (count < 0 || count > kMaxChannels || p.size() != 4 + 4 * size_t(count)) {
        drop(where + std::to_string(p.size()) + " bytes for " + std::to_string(count) + " buttons");
        return false;
    }
    std::vector<bool> states(static_cast<size_t>(count));
    for (int32_t i = 0; i < count; ++i) {
        const int32_t s = i32(p.data() + 4 + 4 * i);
        if (s != 0 && s != 1) {
            drop(where + "button " + std::to_string(i) + " in state " + std::to_string(s) + ", not 0 or 1");
            return false;
        }
        states[size_t(i)] = s == 1;
    }
    buttons_ = std::move(states);
    return true;
}

bool VrpnParser::analogReport(const std::string& where, std::string_view p) {
    const double count = p.size() >= 8 ? f64(p.data()) : -1;
    if (!(count >= 0 && count <= kMaxChannels && count == std::floor(count)) || p.size() != 8 + 8 * size_t(count)) {
        drop(where + std::to_string(p.size()) + " bytes for " + (count == count ? std::to_string(count) : std::string("NaN")) + " channels");
        return false;
    }
    std::vector<double> channels(static_cast<size_t>(count));
    for (size_t i = 0; i < channels.size(); ++i) {
        channels[i] = f64(p.data() + 8 + 8 * i);
        if (!std::isfinite(channels[i])) {
            drop(where + "channel " + std::to_string(i) + " is not a finite number");
            return false;
        }
        channels[i] = std::clamp(channels[i], -1.0, 1.0);  // a joystick's axes; other analogs are not read as one
    }
    channels_ = std::move(channels);
    return true;
}

}  // namespace rtwall
