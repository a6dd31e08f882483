// ART DTrack's ASCII output: a strict reader and the writer the tracker simulator uses.
#include <rtwall/tracking.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace rtwall {

namespace {

// A problem in the packet; caught by DTrackParser::parse, which drops the packet.
struct Malformed : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// A short, printable quote of untrusted bytes for a message.
std::string quote(std::string_view s) {
    std::string q;
    for (size_t i = 0; i < s.size() && i < 24; ++i) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        if (c >= 0x20 && c < 0x7f && c != '\'') {
            q += char(c);
        } else {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", c);
            q += buf;
        }
    }
    if (s.size() > 24) q += "...";
    return "'" + q + "'";
}

// Reads one line's tokens: numbers and the brackets around the blocks, any spaces between.
class Cursor {
public:
    explicit Cursor(std::string_view s) : s_(s) {}

    bool atEnd() {
        skipSpace();
        return p_ == s_.size();
    }
    void expect(char c, const std::string& after) {
        skipSpace();
        if (p_ >= s_.size() || s_[p_] != c)
            throw Malformed(std::string("expected '") + c + "' " + after + ", found " + (p_ >= s_.size() ? "the line's end" : quote(token())));
        ++p_;
    }
    int64_t integer(const std::string& what, int64_t lo, int64_t hi) {
        const std::string_view t = token();
        int64_t v = 0;
        const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        if (t.empty() || ec != std::errc() || end != t.data() + t.size())
            throw Malformed(what + ": expected an integer, found " + (t.empty() ? "nothing" : quote(t)));
        if (v < lo || v > hi)
            throw Malformed(what + ": " + std::to_string(v) + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        p_ += t.size();
        return v;
    }
    double number(const std::string& what, double lo, double hi) {
        const std::string_view t = token();
        double v = 0;
        const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v))
            throw Malformed(what + ": expected a number, found " + (t.empty() ? "nothing" : quote(t)));
        if (v < lo || v > hi) {
            char buf[160];
            std::snprintf(buf, sizeof buf, ": %g is out of range [%g, %g]", v, lo, hi);
            throw Malformed(what + buf);
        }
        p_ += t.size();
        return v;
    }
    // Whether the next token is a number before `c` closes the block.
    bool numberBefore(char c) {
        skipSpace();
        return p_ < s_.size() && s_[p_] != c;
    }

private:
    void skipSpace() {
        while (p_ < s_.size() && (s_[p_] == ' ' || s_[p_] == '\t')) ++p_;
    }
    // The next token: up to a space or a bracket (a bracket alone is a token of its own).
    std::string_view token() {
        skipSpace();
        size_t e = p_;
        while (e < s_.size() && s_[e] != ' ' && s_[e] != '\t' && s_[e] != '[' && s_[e] != ']') ++e;
        if (e == p_ && e < s_.size()) ++e;
        return s_.substr(p_, e - p_);
    }
    std::string_view s_;
    size_t p_ = 0;
};

constexpr double kMaxMillimetres = 1e7;  // 10 km: anything further is not a room
constexpr double kRotationTolerance = 5e-3;  // DTrack prints 6 decimals

void readPosition(Cursor& c, std::array<double, 3>& p, const std::string& who) {
    static const char* axis[] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i) p[i] = c.number(who + ": position " + axis[i], -kMaxMillimetres, kMaxMillimetres);
}

// [b0 .. b8] (column order) into the row-major matrix; a seen body's matrix must be a rotation.
void readRotation(Cursor& c, DTrackBody& b, const std::string& who) {
    c.expect('[', "before " + who + "'s rotation");
    for (int i = 0; i < 9; ++i) {
        const int col = i / 3, row = i % 3;
        b.rotation[3 * row + col] = c.number(who + ": rotation b" + std::to_string(i), -1.0 - kRotationTolerance, 1.0 + kRotationTolerance);
    }
    c.expect(']', "after " + who + "'s rotation");
    if (b.quality < 0) return;  // not seen: DTrack sends zeros
    const auto& r = b.rotation;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const double d = r[i] * r[j] + r[3 + i] * r[3 + j] + r[6 + i] * r[6 + j];
            if (std::fabs(d - (i == j ? 1.0 : 0.0)) > kRotationTolerance)
                throw Malformed(who + ": the rotation b0..b8 is not orthonormal (columns " + std::to_string(i) + " and " +
                                std::to_string(j) + ")");
        }
    const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) + r[2] * (r[3] * r[7] - r[4] * r[6]);
    if (det < 0) throw Malformed(who + ": the rotation b0..b8 is a reflection (determinant " + std::to_string(det) + ")");
}

template <class T> void checkUniqueId(const std::vector<T>& items, int id, const std::string& who) {
    for (size_t i = 0; i + 1 < items.size(); ++i) {
        int other;
        if constexpr (requires { items[i].pose; }) other = items[i].pose.id;
        else other = items[i].id;
        if (other == id) throw Malformed(who + ": id " + std::to_string(id) + " appears twice");
    }
}

// The n items of a line ("body 2 of 3" in every message), each read by `read(who)`; the line
// must end after the last.
template <class Read> void readItems(Cursor& c, int n, const char* noun, const char* plural, Read read) {
    for (int i = 0; i < n; ++i) {
        const std::string who = std::string(noun) + " " + std::to_string(i + 1) + " of " + std::to_string(n);
        if (c.atEnd()) throw Malformed(who + ": missing (the line ends after " + std::to_string(i) + ")");
        read(who);
    }
    if (!c.atEnd()) throw Malformed("more than the " + std::to_string(n) + " " + plural + " it announces");
}

// "[id quality]" of a body or marker, and its position's opening bracket.
template <class Item> void readIdAndQuality(Cursor& c, Item& item, const std::string& who) {
    c.expect('[', "before " + who);
    item.id = int(c.integer(who + ": id", 0, 1'000'000));
    item.quality = c.number(who + ": quality", -1, 1);
    c.expect(']', "after " + who + "'s quality");
    c.expect('[', "before " + who + "'s position");
}

void parse6d(Cursor& c, DTrackFrame& f) {
    const int n = int(c.integer("the number of bodies", 0, DTrackParser::kMaxItems));
    readItems(c, n, "body", "bodies", [&](const std::string& who) {
        DTrackBody b;
        readIdAndQuality(c, b, who);
        readPosition(c, b.position, who);
        // DTrack 1 adds the Euler angles; the matrix after them says the same.
        if (c.numberBefore(']'))
            for (const char* a : {"eta", "theta", "phi"}) c.number(who + ": angle " + a, -360, 360);
        c.expect(']', "after " + who + "'s position");
        readRotation(c, b, who);
        f.bodies.push_back(b);
        checkUniqueId(f.bodies, b.id, who);
    });
}

void parse6df2(Cursor& c, DTrackFrame& f) {
    f.definedFlysticks = int(c.integer("the number of defined flysticks", 0, DTrackParser::kMaxItems));
    const int n = int(c.integer("the number of flysticks", 0, f.definedFlysticks));
    readItems(c, n, "flystick", "flysticks", [&](const std::string& who) {
        DTrackFlystick s;
        c.expect('[', "before " + who);
        s.pose.id = int(c.integer(who + ": id", 0, f.definedFlysticks - 1));
        s.pose.quality = c.number(who + ": quality", -1, 1);
        const int buttons = int(c.integer(who + ": number of buttons", 0, DTrackParser::kMaxButtons));
        const int controllers = int(c.integer(who + ": number of controllers", 0, DTrackParser::kMaxButtons));
        c.expect(']', "after " + who + "'s numbers of buttons and controllers");
        c.expect('[', "before " + who + "'s position");
        readPosition(c, s.pose.position, who);
        c.expect(']', "after " + who + "'s position");
        readRotation(c, s.pose, who);
        c.expect('[', "before " + who + "'s buttons and controllers");
        s.buttons.resize(size_t(buttons));
        for (int w = 0; w * 32 < buttons; ++w) {
            const auto bits = uint32_t(c.integer(who + ": button word " + std::to_string(w), 0, 0xffffffffLL));
            const int inWord = std::min(32, buttons - 32 * w);
            if (inWord < 32 && (bits >> inWord) != 0)
                throw Malformed(who + ": button word " + std::to_string(w) + " (" + std::to_string(bits) + ") sets buttons beyond the " +
                                std::to_string(buttons) + " it has");
            for (int b = 0; b < inWord; ++b) s.buttons[size_t(32 * w + b)] = (bits >> b) & 1u;
        }
        for (int k = 0; k < controllers; ++k) s.controllers.push_back(c.number(who + ": controller " + std::to_string(k), -1, 1));
        c.expect(']', "after " + who + "'s " + std::to_string(buttons) + " buttons and " + std::to_string(controllers) + " controllers");
        f.flysticks.push_back(std::move(s));
        checkUniqueId(f.flysticks, f.flysticks.back().pose.id, who);
    });
}

void parse3d(Cursor& c, DTrackFrame& f) {
    const int n = int(c.integer("the number of markers", 0, DTrackParser::kMaxItems));
    readItems(c, n, "marker", "markers", [&](const std::string& who) {
        DTrackMarker m;
        readIdAndQuality(c, m, who);
        readPosition(c, m.position, who);
        c.expect(']', "after " + who + "'s position");
        f.markers.push_back(m);
        checkUniqueId(f.markers, m.id, who);
    });
}

bool isIdentifier(std::string_view s) {
    if (s.empty() || s.size() > 16) return false;
    return std::all_of(s.begin(), s.end(), [](char ch) { return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9'); });
}

DTrackFrame parsePacket(std::string_view packet) {
    if (packet.size() > DTrackParser::kMaxPacket)
        throw Malformed(std::to_string(packet.size()) + " bytes, more than a UDP datagram holds");
    while (!packet.empty() && (packet.back() == '\0' || packet.back() == '\n' || packet.back() == '\r' || packet.back() == ' '))
        packet.remove_suffix(1);
    if (packet.empty()) throw Malformed("empty");
    DTrackFrame f;
    std::vector<std::string> seen;
    int lineNo = 0;
    size_t start = 0;
    while (start <= packet.size()) {
        size_t end = packet.find('\n', start);
        if (end == std::string_view::npos) end = packet.size();
        std::string_view line = packet.substr(start, end - start);
        start = end + 1;
        ++lineNo;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        for (char ch : line)
            if ((static_cast<unsigned char>(ch) < 0x20 && ch != '\t') || static_cast<unsigned char>(ch) >= 0x7f)
                throw Malformed("line " + std::to_string(lineNo) + ": a byte that is not printable ASCII in " + quote(line));
        const size_t sp = line.find_first_of(" \t");
        const std::string_view id = line.substr(0, sp);
        const std::string_view rest = sp == std::string_view::npos ? std::string_view{} : line.substr(sp);
        if (line.empty()) throw Malformed("line " + std::to_string(lineNo) + ": empty");
        if (!isIdentifier(id)) throw Malformed("line " + std::to_string(lineNo) + ": not a DTrack line: " + quote(line));
        const std::string name(id);
        const std::string where = "line " + std::to_string(lineNo) + " ('" + name + "'): ";
        if (std::find(seen.begin(), seen.end(), name) != seen.end()) throw Malformed(where + "a second '" + name + "' line in one frame");
        seen.push_back(name);
        Cursor c(rest);
        try {
            if (name == "fr") {
                f.frame = uint64_t(c.integer("the frame counter", 0, INT64_MAX));
            } else if (name == "ts") {
                f.timestamp = c.number("the timestamp", 0, 86401);  // seconds of the day (a leap second included)
            } else if (name == "6dcal") {
                f.calibratedBodies = int(c.integer("the number of calibrated bodies", 0, DTrackParser::kMaxItems));
            } else if (name == "6d") {
                parse6d(c, f);
            } else if (name == "6df2") {
                parse6df2(c, f);
            } else if (name == "3d") {
                parse3d(c, f);
            } else {
                // Other outputs DTrack can be set to send (gloves, measurement tools, ...): not used here.
                f.skipped.push_back(name);
                continue;
            }
            if (!c.atEnd()) throw Malformed("unexpected " + quote(rest) + " after the value");
        } catch (const Malformed& e) {
            throw Malformed(where + e.what());
        }
    }
    return f;
}

void appendf(std::string& out, const char* fmt, auto... args) {
    char buf[128];
    const int n = std::snprintf(buf, sizeof buf, fmt, args...);
    out.append(buf, size_t(std::clamp(n, 0, int(sizeof buf) - 1)));
}

void writePose(std::string& out, const DTrackBody& b) {
    appendf(out, "[%.3f %.3f %.3f][", b.position[0], b.position[1], b.position[2]);
    for (int i = 0; i < 9; ++i) appendf(out, i ? " %.6f" : "%.6f", b.rotation[3 * (i % 3) + i / 3]);
    out += "]";
}

}  // namespace

const DTrackBody* DTrackFrame::body(int id) const {
    for (const DTrackBody& b : bodies)
        if (b.id == id) return &b;
    return nullptr;
}

const DTrackFlystick* DTrackFrame::flystick(int id) const {
    for (const DTrackFlystick& s : flysticks)
        if (s.pose.id == id) return &s;
    return nullptr;
}

std::optional<DTrackFrame> DTrackParser::parse(std::string_view packet) {
    try {
        DTrackFrame f = parsePacket(packet);
        ++parsed_;
        return f;
    } catch (const Malformed& e) {
        error_ = std::string("dtrack packet: ") + e.what();
    } catch (const std::bad_alloc&) {
        error_ = "dtrack packet: out of memory";
    }
    ++dropped_;
    return std::nullopt;
}

std::string writeDTrackPacket(const DTrackFrame& f) {
    std::string out;
    if (f.frame) appendf(out, "fr %llu\r\n", (unsigned long long)*f.frame);
    if (f.timestamp) appendf(out, "ts %.6f\r\n", *f.timestamp);
    if (f.calibratedBodies) appendf(out, "6dcal %d\r\n", *f.calibratedBodies);
    if (!f.bodies.empty()) {
        appendf(out, "6d %zu", f.bodies.size());
        for (const DTrackBody& b : f.bodies) {
            appendf(out, " [%d %.3f]", b.id, b.quality);
            writePose(out, b);
        }
        out += "\r\n";
    }
    if (f.definedFlysticks > 0 || !f.flysticks.empty()) {
        appendf(out, "6df2 %d %zu", f.definedFlysticks, f.flysticks.size());
        for (const DTrackFlystick& s : f.flysticks) {
            appendf(out, " [%d %.3f %zu %zu]", s.pose.id, s.pose.quality, s.buttons.size(), s.controllers.size());
            writePose(out, s.pose);
            out += "[";
            bool first = true;
            for (size_t w = 0; w * 32 < s.buttons.size(); ++w) {
                uint32_t bits = 0;
                for (size_t b = 0; b < 32 && 32 * w + b < s.buttons.size(); ++b) bits |= uint32_t(s.buttons[32 * w + b]) << b;
                appendf(out, first ? "%u" : " %u", bits);
                first = false;
            }
            for (double v : s.controllers) {
                appendf(out, first ? "%.6f" : " %.6f", v);
                first = false;
            }
            out += "]";
        }
        out += "\r\n";
    }
    if (!f.markers.empty()) {
        appendf(out, "3d %zu", f.markers.size());
        for (const DTrackMarker& m : f.markers)
            appendf(out, " [%d %.3f][%.3f %.3f %.3f]", m.id, m.quality, m.position[0], m.position[1], m.position[2]);
        out += "\r\n";
    }
    return out;
}

}  // namespace rtwall
