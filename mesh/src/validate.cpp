#include "validate.h"

#include "rtwall/mesh.h"

#include <algorithm>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string_view>
#include <vector>

namespace rtwall::detail {
namespace {

// ---------------------------------------------------------------------------------------------
// Errors

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw InputError(name + ": " + what); }

[[noreturn]] void failLine(const std::string& name, size_t line, const std::string& what) {
    throw InputError(name + ":line " + std::to_string(line) + ": " + what);
}

[[noreturn]] void failOffset(const std::string& name, size_t offset, const std::string& what) {
    throw InputError(name + ":offset " + std::to_string(offset) + ": " + what);
}

// Quotes a token for an error message. Tokens come from untrusted files, so they are shortened
// and control bytes are escaped: the message stays one printable line.
std::string quote(std::string_view token) {
    constexpr size_t kMax = 32;
    std::string out = "'";
    for (size_t i = 0; i < token.size() && i < kMax; ++i) {
        const auto c = static_cast<unsigned char>(token[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            static const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    if (token.size() > kMax) out += "...";
    return out + "'";
}

std::string plural(uint64_t n, std::string_view noun) {
    std::string word(noun);
    if (n != 1) word = noun == "vertex" ? "vertices" : word + "s";
    return std::to_string(n) + " " + word;
}

// ---------------------------------------------------------------------------------------------
// Text scanning

// The characters std::istream's operator>> skips.
constexpr bool isSpace(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

char lower(char c) { return (c >= 'A' && c <= 'Z') ? char(c - 'A' + 'a') : c; }

bool equalsNoCase(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return lower(x) == lower(y); });
}

void splitTokens(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSpace(line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !isSpace(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
}

// Walks the lines of a buffer; `begin`/`end` exclude the '\n'.
class Lines {
public:
    explicit Lines(std::string& data, size_t start = 0) : data_(data), pos_(start) {}
    bool next() {
        if (pos_ >= data_.size()) return false;
        begin_ = pos_;
        const size_t nl = data_.find('\n', pos_);
        end_ = nl == std::string::npos ? data_.size() : nl;
        pos_ = end_ + 1;
        ++number_;
        return true;
    }
    std::string_view view() const { return std::string_view(data_).substr(begin_, end_ - begin_); }
    size_t number() const { return number_; }
    size_t begin() const { return begin_; }
    size_t end() const { return end_; }
    size_t rest() const { return pos_ >= data_.size() ? 0 : data_.size() - pos_; }
    // Overwrites [from, end of line) with blanks; every reader skips them like any whitespace.
    void blankFrom(size_t from) { std::fill(data_.begin() + long(from), data_.begin() + long(end_), ' '); }
    // The OBJ reader trims only " \t\r\n" and then skips any line that starts with other
    // whitespace, where the other readers would read on; make all whitespace plain blanks.
    void plainBlanks() {
        std::replace_if(data_.begin() + long(begin_), data_.begin() + long(end_), [](char c) { return c == '\v' || c == '\f'; }, ' ');
    }
    void blankComment() {
        // Searched within the line only: searching the rest of the buffer made a file without
        // any '#' quadratic (a 63 MB OBJ ran for minutes in this pre-pass).
        const size_t hash = view().find('#');
        if (hash != std::string_view::npos) blankFrom(begin_ + hash);
    }

private:
    std::string& data_;
    size_t pos_;
    size_t begin_ = 0, end_ = 0, number_ = 0;
};

// Walks whitespace-separated tokens across lines (ASCII PLY ignores line structure).
class Tokens {
public:
    Tokens(std::string_view data, size_t start, size_t line) : data_(data), pos_(start), line_(line) {}
    bool next(std::string_view& token) {
        while (pos_ < data_.size() && isSpace(data_[pos_])) {
            if (data_[pos_] == '\n') ++line_;
            ++pos_;
        }
        if (pos_ >= data_.size()) return false;
        const size_t start = pos_;
        while (pos_ < data_.size() && !isSpace(data_[pos_])) ++pos_;
        token = data_.substr(start, pos_ - start);
        return true;
    }
    size_t line() const { return line_; }

private:
    std::string_view data_;
    size_t pos_;
    size_t line_;
};

void rejectNul(const std::string& data, const std::string& name, size_t from = 0) {
    const size_t nul = data.find('\0', from);
    if (nul != std::string::npos) failOffset(name, nul, "binary data (a NUL byte) in a text file");
}

// ---------------------------------------------------------------------------------------------
// Numbers, parsed the way std::istream would accept them (the readers use operator>>), but
// requiring the whole token: istream would stop at the first bad character and leave the rest
// for the next read, which misaligns every value after it.

enum class Num { Ok, Bad, NonFinite, TooLarge };

Num parseFloat(std::string_view t, float& out) {
    if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
    const char* first = t.data();
    const char* last = t.data() + t.size();
    auto [ptr, ec] = std::from_chars(first, last, out, std::chars_format::general);
    if (ec == std::errc::result_out_of_range) {
        // Either overflow (istream fails) or underflow to a denormal or zero (istream accepts).
        double d = 0;
        auto [dptr, dec] = std::from_chars(first, last, d, std::chars_format::general);
        if (dptr != last) return Num::Bad;
        if (dec == std::errc() && std::isfinite(d) && std::fabs(d) <= double(FLT_MAX)) {
            out = float(d);
            return Num::Ok;
        }
        return Num::TooLarge;
    }
    if (ec != std::errc() || ptr != last) return Num::Bad;
    // from_chars accepts "nan" and "inf", which istream does not, and which are no coordinates.
    if (!std::isfinite(out)) return Num::NonFinite;
    return Num::Ok;
}

bool parseInteger(std::string_view t, int64_t& out) {
    if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
    auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
    return ec == std::errc() && ptr == t.data() + t.size();
}

std::string describeBadFloat(Num status, std::string_view token) {
    switch (status) {
    case Num::NonFinite: return "NaN or infinite value " + quote(token);
    case Num::TooLarge: return "value " + quote(token) + " is too large for a float";
    default: return quote(token) + " is not a number";
    }
}

// ---------------------------------------------------------------------------------------------
// Binary reading

uint64_t readUnsigned(const char* p, int bytes, bool bigEndian) {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) {
        const auto b = static_cast<unsigned char>(p[bigEndian ? i : bytes - 1 - i]);
        v = (v << 8) | b;
    }
    return v;
}

int64_t readSigned(const char* p, int bytes, bool bigEndian) {
    const uint64_t u = readUnsigned(p, bytes, bigEndian);
    const int shift = 64 - 8 * bytes;
    return static_cast<int64_t>(u << shift) >> shift;
}

float readFloat32(const char* p, bool bigEndian) {
    const auto u = static_cast<uint32_t>(readUnsigned(p, 4, bigEndian));
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

double readFloat64(const char* p, bool bigEndian) {
    const uint64_t u = readUnsigned(p, 8, bigEndian);
    double d;
    std::memcpy(&d, &u, 8);
    return d;
}

// a * b + c, saturating instead of wrapping: header counts are untrusted.
uint64_t mulAdd(uint64_t a, uint64_t b, uint64_t c) {
    constexpr uint64_t kMax = std::numeric_limits<uint64_t>::max();
    if (b != 0 && a > (kMax - c) / b) return kMax;
    return a * b + c;
}

// ---------------------------------------------------------------------------------------------
// OBJ

// Statements of the OBJ format and its common extensions. OpenMesh ignores all but v, vt, vn,
// f, mtllib and usemtl; an unknown keyword means the file is not OBJ at all.
bool isObjKeyword(std::string_view k) {
    static const std::string_view known[] = {
        "v",     "vt",    "vn",    "vp",   "vc",      "f",         "fo",       "l",        "p",
        "g",     "o",     "s",     "mg",   "mtllib",  "usemtl",    "usemap",   "maplib",   "cstype",
        "deg",   "bmat",  "step",  "curv", "curv2",   "surf",      "parm",     "trim",     "hole",
        "scrv",  "sp",    "end",   "con",  "bevel",   "c_interp",  "d_interp", "lod",      "shadow_obj",
        "trace_obj", "ctech", "stech", "call", "csh", "res",
    };
    return std::find(std::begin(known), std::end(known), k) != std::end(known);
}

Prepass validateObj(std::string& data, const std::string& name) {
    rejectNul(data, name);
    Prepass out;
    uint64_t counts[3] = {0, 0, 0};  // v, vt, vn seen so far
    // OpenMesh reads all vertex data before any face, so a positive index may point forward;
    // the largest one of each kind is checked at the end, against the line that used it.
    int64_t maxIndex[3] = {0, 0, 0};
    size_t maxIndexLine[3] = {0, 0, 0};
    static const char* kinds[3] = {"vertex", "texture coordinate", "normal"};

    std::vector<std::string_view> tokens;
    std::vector<int64_t> corners, sorted;
    size_t facesPassedOn = 0;
    Lines lines(data);
    while (lines.next()) {
        lines.plainBlanks();
        lines.blankComment();
        splitTokens(lines.view(), tokens);
        if (tokens.empty()) continue;
        const std::string_view key = tokens[0];
        const size_t line = lines.number();

        if (key == "v" || key == "vn" || key == "vt") {
            const size_t need = key == "vt" ? 2 : 3;
            if (tokens.size() < 1 + need)
                failLine(name, line, std::string(key == "v" ? "vertex" : key == "vn" ? "normal" : "texture coordinate") +
                                         " needs " + std::to_string(need) + " numbers");
            for (size_t i = 1; i <= need; ++i) {
                float value;
                const Num status = parseFloat(tokens[i], value);
                if (status == Num::Ok) continue;
                if (key == "v")
                    failLine(name, line, "vertex " + std::to_string(counts[0]) + ": " + describeBadFloat(status, tokens[i]));
                failLine(name, line, std::string(key == "vn" ? "normal " : "texture coordinate ") +
                                         std::to_string(counts[key == "vn" ? 2 : 1]) + ": " + describeBadFloat(status, tokens[i]));
            }
            ++counts[key == "v" ? 0 : key == "vt" ? 1 : 2];
        } else if (key == "f") {
            if (tokens.size() < 4) failLine(name, line, "face has fewer than 3 corners");
            corners.clear();
            for (size_t c = 1; c < tokens.size(); ++c) {
                const std::string_view corner = tokens[c];
                // v, v/vt, v//vn or v/vt/vn. OpenMesh asserts on an empty vertex part and reuses
                // a stale value for an unparsable one, so the syntax is checked strictly.
                std::string_view parts[3];
                size_t nParts = 0;
                size_t start = 0;
                while (true) {
                    const size_t slash = corner.find('/', start);
                    if (nParts == 3) failLine(name, line, "bad face corner " + quote(corner));
                    parts[nParts++] = corner.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
                    if (slash == std::string_view::npos) break;
                    start = slash + 1;
                }
                for (size_t k = 0; k < nParts; ++k) {
                    if (parts[k].empty()) {
                        if (k == 1 && nParts == 3) continue;  // v//vn
                        failLine(name, line, "bad face corner " + quote(corner));
                    }
                    int64_t value;
                    if (!parseInteger(parts[k], value) || value < std::numeric_limits<int32_t>::min() ||
                        value > std::numeric_limits<int32_t>::max())
                        failLine(name, line, "bad face corner " + quote(corner));
                    if (value == 0)
                        failLine(name, line, std::string(kinds[k]) + " index 0 is out of range (OBJ indices start at 1)");
                    int64_t resolved = value;
                    if (value < 0) {
                        resolved = int64_t(counts[k]) + value + 1;
                        if (resolved < 1)
                            failLine(name, line, std::string(kinds[k]) + " index " + std::to_string(value) +
                                                     " is out of range (" + plural(counts[k], kinds[k]) + " so far)");
                    } else if (value > maxIndex[k]) {
                        maxIndex[k] = value;
                        maxIndexLine[k] = line;
                    }
                    if (k == 0) corners.push_back(resolved);
                }
            }
            // OpenMesh removes repeated corners and drops what falls below a triangle; where it
            // passes on what is left, the importer puts the repeats back.
            sorted.assign(corners.begin(), corners.end());
            std::sort(sorted.begin(), sorted.end());
            const size_t distinct = size_t(std::unique(sorted.begin(), sorted.end()) - sorted.begin());
            if (distinct < 3) {
                ++out.droppedDegenerate;
            } else {
                if (distinct < corners.size()) {
                    RepeatedCornerFace& face = out.repeatedCorners.emplace_back();
                    face.face = facesPassedOn;
                    for (const int64_t c : corners) face.corners.push_back(uint32_t(c - 1));
                }
                out.triangles += corners.size() - 2;
                ++facesPassedOn;
            }
        } else if (key == "mtllib") {
            // The reader would open the material file relative to the working directory, and
            // rtwall has no use for OBJ materials.
            lines.blankFrom(lines.begin());
        } else if (!isObjKeyword(key)) {
            failLine(name, line, "unknown OBJ statement " + quote(key));
        }
    }
    for (int k = 0; k < 3; ++k) {
        if (maxIndex[k] > int64_t(counts[k]))
            failLine(name, maxIndexLine[k], std::string(kinds[k]) + " index " + std::to_string(maxIndex[k]) +
                                                " is out of range (the file has " + plural(counts[k], kinds[k]) + ")");
    }
    out.vertices = counts[0];
    return out;
}

// ---------------------------------------------------------------------------------------------
// OFF (ASCII only)

Prepass validateOff(std::string& data, const std::string& name) {
    rejectNul(data, name);
    Prepass out;
    std::vector<std::string_view> tokens;
    Lines lines(data);

    // Header keyword: [ST][C][N]OFF, alone on the first line, as OpenMesh reads it.
    if (!lines.next()) fail(name, "file is empty");
    lines.blankComment();
    splitTokens(lines.view(), tokens);
    // The reader matches the keyword at the very start of the file.
    std::string_view key = tokens.empty() || tokens[0].data() != data.data() ? std::string_view() : tokens[0];
    bool colors = false, normals = false;
    {
        std::string_view k = key;
        if (k.substr(0, 2) == "ST") k.remove_prefix(2);
        if (k.substr(0, 1) == "C") colors = true, k.remove_prefix(1);
        if (k.substr(0, 1) == "N") normals = true, k.remove_prefix(1);
        if (k == "4OFF" || k == "nOFF" || k == "4nOFF") failLine(name, 1, "OFF with other than 3 dimensions is not supported");
        if (k != "OFF") failLine(name, 1, "not an OFF file (first line is not an OFF keyword)");
    }
    if (tokens.size() > 1) {
        if (tokens[1] == "BINARY") failLine(name, 1, "binary OFF is not supported");
        failLine(name, 1, "unexpected " + quote(tokens[1]) + " after " + quote(key) + " (counts belong on the next line)");
    }

    // Counts: vertices, faces, edges (ignored), alone on their line.
    uint64_t nV = 0, nF = 0;
    while (true) {
        if (!lines.next()) fail(name, "truncated: no vertex and face counts after the OFF header");
        lines.blankComment();
        splitTokens(lines.view(), tokens);
        if (tokens.empty()) continue;
        int64_t v[3];
        if (tokens.size() != 3 || !parseInteger(tokens[0], v[0]) || !parseInteger(tokens[1], v[1]) || !parseInteger(tokens[2], v[2]) ||
            v[0] < 0 || v[1] < 0 || v[2] < 0)
            failLine(name, lines.number(), "expected three counts (vertices faces edges)");
        if (v[0] > std::numeric_limits<int32_t>::max() || v[1] > std::numeric_limits<uint32_t>::max())
            failLine(name, lines.number(), "vertex or face count too large");
        nV = uint64_t(v[0]);
        nF = uint64_t(v[1]);
        break;
    }
    // Every vertex and face needs a line of at least two bytes.
    if (nV + nF > lines.rest() / 2 + 1)
        failLine(name, lines.number(),
                 "truncated: header declares " + plural(nV, "vertex") + " and " + plural(nF, "face") + " but only " +
                     plural(lines.rest(), "byte") + " follow");

    const size_t coords = normals ? 6 : 3;
    for (uint64_t v = 0; v < nV;) {
        if (!lines.next()) fail(name, "truncated: file ends after " + std::to_string(v) + " of " + plural(nV, "vertex"));
        lines.blankComment();
        splitTokens(lines.view(), tokens);
        if (tokens.empty()) continue;
        if (tokens.size() < coords)
            failLine(name, lines.number(), "vertex " + std::to_string(v) + " needs " + std::to_string(coords) + " numbers");
        for (size_t i = 0; i < coords; ++i) {
            float value;
            const Num status = parseFloat(tokens[i], value);
            if (status != Num::Ok)
                failLine(name, lines.number(), std::string(i < 3 ? "vertex " : "normal of vertex ") + std::to_string(v) + ": " +
                                                   describeBadFloat(status, tokens[i]));
        }
        ++v;
    }
    for (uint64_t f = 0; f < nF;) {
        if (!lines.next()) fail(name, "truncated: file ends after " + std::to_string(f) + " of " + plural(nF, "face"));
        lines.blankComment();
        splitTokens(lines.view(), tokens);
        if (tokens.empty()) continue;
        const size_t line = lines.number();
        const std::string face = "face " + std::to_string(f);
        int64_t n;
        if (!parseInteger(tokens[0], n) || n < 0) failLine(name, line, face + ": bad corner count " + quote(tokens[0]));
        if (n < 3) failLine(name, line, face + " has fewer than 3 corners");
        if (uint64_t(n) + 1 > tokens.size())
            failLine(name, line, face + " declares " + std::to_string(n) + " corners but lists " + std::to_string(tokens.size() - 1));
        // Without a colour keyword the reader takes extra values for the next face's corners.
        if (uint64_t(n) + 1 < tokens.size() && !colors)
            failLine(name, line, face + ": unexpected " + quote(tokens[size_t(n) + 1]) + " after its corners");
        for (size_t c = 1; c <= size_t(n); ++c) {
            int64_t index;
            if (!parseInteger(tokens[c], index)) failLine(name, line, face + ": bad vertex index " + quote(tokens[c]));
            if (index < 0 || uint64_t(index) >= nV)
                failLine(name, line, face + ": vertex index " + std::to_string(index) + " is out of range (the file has " +
                                         plural(nV, "vertex") + ")");
        }
        out.triangles += size_t(n) - 2;
        ++f;
    }
    out.vertices = nV;
    return out;
}

// ---------------------------------------------------------------------------------------------
// STL

bool sameStlPoint(const float* a, const float* b) {
    // OpenMesh merges STL vertices that agree to within FLT_MIN in every coordinate.
    return std::fabs(a[0] - b[0]) <= FLT_MIN && std::fabs(a[1] - b[1]) <= FLT_MIN && std::fabs(a[2] - b[2]) <= FLT_MIN;
}

bool degenerateStl(const float (&p)[3][3]) {
    return sameStlPoint(p[0], p[1]) || sameStlPoint(p[0], p[2]) || sameStlPoint(p[1], p[2]);
}

bool looksLikeAsciiStl(const std::string& data) {
    size_t i = 0;
    while (i < data.size() && isSpace(data[i])) ++i;
    if (!equalsNoCase(std::string_view(data).substr(i, 5), "solid")) return false;
    // Binary STL headers often begin with "solid" too; text has no control bytes.
    return std::none_of(data.begin(), data.end(), [](char c) {
        const auto u = static_cast<unsigned char>(c);
        return u < 0x20 && !isSpace(c);
    });
}

Prepass validateBinaryStl(const std::string& data, const std::string& name, uint64_t count) {
    Prepass out;
    out.binaryStl = true;
    for (uint64_t t = 0; t < count; ++t) {
        const size_t base = size_t(84 + 50 * t);
        float p[3][3];
        for (int v = 0; v < 3; ++v) {
            for (int k = 0; k < 3; ++k) {
                const size_t offset = base + 12 + size_t(12 * v + 4 * k);
                p[v][k] = readFloat32(data.data() + offset, false);
                if (!std::isfinite(p[v][k]))
                    failOffset(name, offset, "triangle " + std::to_string(t) + " has a NaN or infinite vertex coordinate");
            }
        }
        if (degenerateStl(p)) ++out.droppedDegenerate;
    }
    out.triangles = size_t(count) - out.droppedDegenerate;
    out.vertices = 3 * size_t(count);
    return out;
}

Prepass validateAsciiStl(std::string& data, const std::string& name) {
    Prepass out;
    enum class State { Start, Outside, Facet, Loop, EndLoop, EndFacet } state = State::Start;
    int vertex = 0;
    float p[3][3] = {};
    std::vector<std::string_view> tokens;
    Lines lines(data);
    while (lines.next()) {
        splitTokens(lines.view(), tokens);
        const size_t line = lines.number();
        // The reader takes the three lines after "outer loop" as vertices, whatever they hold.
        if (state == State::Loop) {
            if (tokens.empty() || !equalsNoCase(tokens[0], "vertex")) failLine(name, line, "expected 'vertex'");
            if (tokens.size() < 4) failLine(name, line, "vertex needs 3 numbers");
            for (int k = 0; k < 3; ++k) {
                const Num status = parseFloat(tokens[size_t(k) + 1], p[vertex][k]);
                if (status != Num::Ok)
                    failLine(name, line, "triangle " + std::to_string(out.triangles) + ": " + describeBadFloat(status, tokens[size_t(k) + 1]));
            }
            if (++vertex == 3) state = State::EndLoop;
            continue;
        }
        if (tokens.empty()) continue;
        const std::string_view key = tokens[0];
        auto expect = [&](const char* what) { failLine(name, line, "expected " + std::string(what) + ", found " + quote(key)); };
        switch (state) {
        case State::Start:
            if (!equalsNoCase(key, "solid")) expect("'solid'");
            state = State::Outside;
            break;
        case State::Outside:
            if (equalsNoCase(key, "facet"))
                state = State::Facet;
            else if (!equalsNoCase(key, "endsolid") && !equalsNoCase(key, "solid"))
                expect("'facet' or 'endsolid'");
            break;
        case State::Facet:
            if (!equalsNoCase(key, "outer") || tokens.size() < 2 || !equalsNoCase(tokens[1], "loop")) expect("'outer loop'");
            // The reader spots this line by the substring "outer" (or "OUTER"), so it is
            // rewritten to exactly that and is the only line left holding the word.
            lines.blankFrom(lines.begin());
            std::memcpy(data.data() + lines.begin(), "outer loop", std::min<size_t>(10, lines.end() - lines.begin()));
            state = State::Loop;
            vertex = 0;
            continue;
        case State::EndLoop:
            if (!equalsNoCase(key, "endloop")) expect("'endloop'");
            state = State::EndFacet;
            break;
        case State::EndFacet:
            if (!equalsNoCase(key, "endfacet")) expect("'endfacet'");
            if (degenerateStl(p))
                ++out.droppedDegenerate;
            else
                ++out.triangles;
            state = State::Outside;
            break;
        case State::Loop: break;
        }
        // Facet normals, solid names and closing keywords mean nothing to the reader, but a
        // solid named "outer..." would be mistaken for a loop.
        lines.blankFrom(lines.begin());
    }
    if (state != State::Outside) fail(name, "truncated: file ends inside a facet");
    out.vertices = 3 * (out.triangles + out.droppedDegenerate);
    return out;
}

Prepass validateStl(std::string& data, const std::string& name) {
    // Binary when the size matches the triangle count, as OpenMesh decides for files; that rule
    // wins over a header that happens to start with "solid".
    if (data.size() >= 84) {
        const uint64_t count = readUnsigned(data.data() + 80, 4, false);
        const uint64_t expected = 84 + 50 * count;
        if (expected == data.size()) return validateBinaryStl(data, name, count);
        if (!looksLikeAsciiStl(data)) {
            if (data.size() < expected)
                failOffset(name, 80, "truncated binary STL: header declares " + plural(count, "triangle") + " (" +
                                         std::to_string(expected) + " bytes) but the file has " + std::to_string(data.size()));
            failOffset(name, 80, "binary STL size mismatch: header declares " + plural(count, "triangle") + " (" +
                                     std::to_string(expected) + " bytes) but the file has " + std::to_string(data.size()));
        }
    } else if (!looksLikeAsciiStl(data)) {
        fail(name, "truncated binary STL or not an STL file: " + plural(data.size(), "byte") + ", less than the 84-byte header");
    }
    return validateAsciiStl(data, name);
}

// ---------------------------------------------------------------------------------------------
// PLY

struct PlyType {
    std::string_view name;
    int size;
    bool isFloat;
    bool isSigned;
};

// Exactly the type names OpenMesh's PLY reader knows.
constexpr PlyType kPlyTypes[] = {
    {"char", 1, false, true},   {"uchar", 1, false, false}, {"int8", 1, false, true},    {"uint8", 1, false, false},
    {"short", 2, false, true},  {"ushort", 2, false, false}, {"int16", 2, false, true},  {"uint16", 2, false, false},
    {"int", 4, false, true},    {"uint", 4, false, false},  {"int32", 4, false, true},   {"uint32", 4, false, false},
    {"float", 4, true, true},   {"float32", 4, true, true}, {"double", 8, true, true},   {"float64", 8, true, true},
};

const PlyType* findPlyType(std::string_view n) {
    for (const auto& t : kPlyTypes)
        if (t.name == n) return &t;
    return nullptr;
}

enum class PlyRole {
    Skip,         // read into a scratch string (ASCII) or skipped by size (binary)
    Coordinate,   // x, y, z
    VertexFloat,  // normals and texture coordinates: read as float
    Color,        // read as float for float/float32, as integer otherwise
    Integer,      // face texnumber: read as unsigned
    Indices,      // the face's vertex_indices list
    DropList,     // any other face list (MeshLab's texcoord): the reader would lose its place
                  // on it, so it is removed from header and data
};

struct PlyProperty {
    std::string name;
    const PlyType* type = nullptr;
    const PlyType* countType = nullptr;  // set for lists
    PlyRole role = PlyRole::Skip;
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    size_t line = 0;
    std::vector<PlyProperty> props;
};

struct PlyHeader {
    enum class Encoding { Ascii, BinaryLe, BinaryBe } encoding = Encoding::Ascii;
    std::string formatText, versionText;
    std::vector<PlyElement> elements;
    size_t dataOffset = 0;  // first byte after the end_header line
    size_t dataLine = 0;    // line number of the end_header line
    int vertexElement = -1, faceElement = -1;
    std::vector<std::string> warnings;  // header lines skipped
};

// Levenshtein distance, for header keywords (a few letters each).
size_t editDistance(std::string_view a, std::string_view b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        size_t diagonal = row[0];
        row[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            const size_t above = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1)});
            diagonal = above;
        }
    }
    return row[b.size()];
}

// A header line that is no keyword could still be meant as one that lays out the data: a
// misspelt keyword, or the shape of a property line ("<word> <type> <name>", "<word> list ...")
// or an element line ("<word> <name> <count>"). Skipping such a line would misread every value
// after it, so it stays an error; any other line cannot change the layout.
bool mayChangePlyLayout(const std::vector<std::string_view>& tokens) {
    const std::string_view key = tokens[0].substr(0, 16);
    for (const std::string_view keyword : {"format", "element", "property", "end_header"})
        if (editDistance(key, keyword) <= 2) return true;
    if (tokens.size() >= 2 && (tokens[1] == "list" || findPlyType(tokens[1]))) return true;
    int64_t count = 0;
    return tokens.size() == 3 && parseInteger(tokens[2], count);
}

bool isColorName(std::string_view n) {
    return n == "red" || n == "green" || n == "blue" || n == "alpha" || n == "diffuse_red" || n == "diffuse_green" ||
           n == "diffuse_blue";
}

PlyHeader parsePlyHeader(std::string& data, const std::string& name) {
    PlyHeader h;
    std::vector<std::string_view> tokens;
    Lines lines(data);
    if (!lines.next()) fail(name, "file is empty");
    splitTokens(lines.view(), tokens);
    if (tokens.size() != 1 || (tokens[0] != "ply" && tokens[0] != "PLY")) failLine(name, 1, "not a PLY file (the first line is not 'ply')");

    bool ended = false;
    while (!ended && lines.next()) {
        const size_t line = lines.number();
        const std::string_view text = lines.view();
        if (text.find('\0') != std::string_view::npos) failLine(name, line, "binary data inside the PLY header");
        splitTokens(text, tokens);
        if (tokens.empty()) continue;
        const std::string_view key = tokens[0];
        if (key == "comment" || key == "obj_info") continue;
        if (key == "end_header") {
            if (tokens.size() != 1) failLine(name, line, "unexpected text after end_header");
            if (lines.end() == data.size()) failLine(name, line, "truncated: no data after the PLY header");
            h.dataOffset = std::min(lines.end() + 1, data.size());
            h.dataLine = line;
            ended = true;
        } else if (key == "format") {
            if (!h.formatText.empty()) failLine(name, line, "second format line");
            if (!h.elements.empty()) failLine(name, line, "format line after the first element");
            if (tokens.size() != 3) failLine(name, line, "expected 'format <encoding> <version>'");
            if (tokens[1] == "ascii")
                h.encoding = PlyHeader::Encoding::Ascii;
            else if (tokens[1] == "binary_little_endian")
                h.encoding = PlyHeader::Encoding::BinaryLe;
            else if (tokens[1] == "binary_big_endian")
                h.encoding = PlyHeader::Encoding::BinaryBe;
            else
                failLine(name, line, "unknown PLY format " + quote(tokens[1]));
            float version;
            if (parseFloat(tokens[2], version) != Num::Ok) failLine(name, line, "bad PLY version " + quote(tokens[2]));
            h.formatText = tokens[1];
            h.versionText = tokens[2];
        } else if (key == "element") {
            if (h.formatText.empty()) failLine(name, line, "element before the format line");
            int64_t count;
            if (tokens.size() != 3) failLine(name, line, "expected 'element <name> <count>'");
            if (!parseInteger(tokens[2], count) || count < 0 || count > int64_t(std::numeric_limits<uint32_t>::max()))
                failLine(name, line, "bad element count " + quote(tokens[2]));
            PlyElement e;
            e.name = tokens[1];
            e.count = uint64_t(count);
            e.line = line;
            if (e.name == "vertex") {
                if (h.vertexElement >= 0) failLine(name, line, "second vertex element");
                h.vertexElement = int(h.elements.size());
            } else if (e.name == "face") {
                if (h.faceElement >= 0) failLine(name, line, "second face element");
                if (h.vertexElement < 0) failLine(name, line, "face element before the vertex element");
                h.faceElement = int(h.elements.size());
            }
            h.elements.push_back(std::move(e));
        } else if (key == "property") {
            if (h.elements.empty()) failLine(name, line, "property before any element");
            PlyElement& e = h.elements.back();
            PlyProperty p;
            if (tokens.size() >= 2 && tokens[1] == "list") {
                if (tokens.size() != 5) failLine(name, line, "expected 'property list <count type> <entry type> <name>'");
                // The reader accepts only these count types and gives up on anything else.
                const std::string_view ct = tokens[2];
                if (!findPlyType(ct)) failLine(name, line, "unknown list count type " + quote(ct));
                if (findPlyType(ct)->isFloat) failLine(name, line, "list count type " + quote(ct) + " is not an integer type");
                if (ct != "uchar" && ct != "uint8" && ct != "uint16" && ct != "int")
                    failLine(name, line, "unsupported list count type " + quote(ct) + " (use uchar, uint8, uint16 or int)");
                p.countType = findPlyType(ct);
                p.type = findPlyType(tokens[3]);
                if (!p.type) failLine(name, line, "unknown list entry type " + quote(tokens[3]));
                p.name = tokens[4];
            } else {
                if (tokens.size() != 3) failLine(name, line, "expected 'property <type> <name>'");
                p.type = findPlyType(tokens[1]);
                if (!p.type) failLine(name, line, "unknown property type " + quote(tokens[1]));
                p.name = tokens[2];
                // OpenMesh knows texture coordinates as u/v or s/t only; texture_u/texture_v
                // (and texture_s/texture_t) are renamed in place, padded with blanks in front so
                // that every byte after the header keeps its offset.
                if (e.name == "vertex" && (p.name == "texture_u" || p.name == "texture_v" || p.name == "texture_s" ||
                                           p.name == "texture_t")) {
                    const char last = p.name.back();
                    char* at = data.data() + (tokens[2].data() - data.data());
                    std::fill(at, at + tokens[2].size() - 1, ' ');
                    at[tokens[2].size() - 1] = last;
                    p.name = std::string(1, last);
                }
            }
            // The reader finds the type by looking at both words, so a name that is a type name
            // could be taken for the type.
            if (findPlyType(p.name)) failLine(name, line, "property name " + quote(p.name) + " is a type name");
            for (const auto& other : e.props)
                if (other.name == p.name) failLine(name, line, "second property " + quote(p.name) + " in element " + quote(e.name));
            const bool binary = h.encoding != PlyHeader::Encoding::Ascii;
            const bool isVertex = e.name == "vertex", isFace = e.name == "face";
            if (p.countType) {
                if (isFace && (p.name == "vertex_indices" || p.name == "vertex_index")) {
                    if (!e.props.empty()) failLine(name, line, "vertex_indices must be the first face property");
                    if (p.type->isFloat) failLine(name, line, "vertex_indices has a floating-point entry type");
                    p.role = PlyRole::Indices;
                } else if (isFace) {
                    p.role = PlyRole::DropList;
                } else if (h.faceElement < 0) {
                    // The reader skips one value for such a list, whatever its length, and loses
                    // its place; elements after the faces are never read.
                    failLine(name, line, "list property " + quote(p.name) + " in element " + quote(e.name) + " is not supported");
                }
            } else if (isVertex && (p.name == "x" || p.name == "y" || p.name == "z")) {
                p.role = PlyRole::Coordinate;
            } else if (isVertex && (p.name == "nx" || p.name == "ny" || p.name == "nz" || p.name == "u" || p.name == "v" ||
                                    p.name == "s" || p.name == "t")) {
                p.role = PlyRole::VertexFloat;
            } else if ((isVertex || isFace) && isColorName(p.name) && !(isFace && p.name.substr(0, 8) == "diffuse_")) {
                p.role = PlyRole::Color;
            } else if (isFace && p.name == "texnumber") {
                p.role = PlyRole::Integer;
            }
            // Binary values are converted by type; these pairs the reader cannot convert and
            // would not consume, losing its place in the data.
            if (binary && (p.role == PlyRole::Coordinate || p.role == PlyRole::VertexFloat) && !p.type->isFloat)
                failLine(name, line, "vertex property " + quote(p.name) + " must be float or double in binary PLY");
            if (binary && p.role == PlyRole::Color && p.type->isFloat && p.type->size != 4)
                failLine(name, line, "colour property " + quote(p.name) + " cannot be double in binary PLY");
            if (binary && p.role == PlyRole::Integer && p.type->isFloat)
                failLine(name, line, "property " + quote(p.name) + " must be an integer type");
            e.props.push_back(std::move(p));
        } else if (mayChangePlyLayout(tokens)) {
            failLine(name, line, "unknown PLY header keyword " + quote(key) +
                                     " (it could be a misspelt format, element or property line, which would change how the data is read)");
        } else {
            // Blender 2.4x writes "Created by Blender3D 247 - www.blender.org, source file: ..." as
            // a bare line; other readers skip such lines, and only format, element and property
            // lines say how the data is laid out.
            h.warnings.push_back(name + ":line " + std::to_string(line) + ": ignored a PLY header line that is no PLY keyword: " +
                                 quote(text.substr(0, 60)));
        }
    }
    if (!ended) fail(name, "truncated PLY header: no end_header line");
    if (h.formatText.empty()) fail(name, "PLY header has no format line");
    if (h.vertexElement < 0) fail(name, "PLY header has no vertex element");
    if (h.faceElement < 0) fail(name, "PLY header has no face element");
    const PlyElement& vertex = h.elements[size_t(h.vertexElement)];
    for (const char* axis : {"x", "y", "z"})
        if (std::none_of(vertex.props.begin(), vertex.props.end(), [&](const PlyProperty& p) { return p.name == axis; }))
            failLine(name, vertex.line, "vertex element has no " + std::string(axis) + " property");
    const PlyElement& face = h.elements[size_t(h.faceElement)];
    if (face.props.empty() || face.props[0].role != PlyRole::Indices) failLine(name, face.line, "face element has no vertex_indices list");
    return h;
}

// OpenMesh finds binary data by a fixed offset from the last header token and cannot skip
// comments or unknown lines reliably there; the validated header is therefore rewritten in a
// canonical form of exactly the same length, the spare bytes as spaces inside the format line.
void rewritePlyHeader(std::string& data, const PlyHeader& h, bool dropTrailingElements) {
    std::string body = h.formatText + " " + h.versionText + "\n";
    for (size_t ei = 0; ei < h.elements.size(); ++ei) {
        if (dropTrailingElements && int(ei) > h.faceElement) break;
        const PlyElement& e = h.elements[ei];
        body += "element " + e.name + " " + std::to_string(e.count) + "\n";
        for (const auto& p : e.props) {
            if (p.role == PlyRole::DropList) continue;
            if (p.countType)
                body += "property list " + std::string(p.countType->name) + " " + std::string(p.type->name) + " " + p.name + "\n";
            else
                body += "property " + std::string(p.type->name) + " " + p.name + "\n";
        }
    }
    body += "end_header\n";
    const std::string head = "ply\nformat ";
    // Never longer than the original: the original has every token at least once and at least
    // one separator between tokens.
    const size_t pad = h.dataOffset - head.size() - body.size();
    const std::string header = head + std::string(pad, ' ') + body;
    std::memcpy(data.data(), header.data(), header.size());
}

Prepass validatePlyAscii(std::string& data, const std::string& name, const PlyHeader& h) {
    Prepass out;
    rejectNul(data, name, h.dataOffset);
    const uint64_t nV = h.elements[size_t(h.vertexElement)].count;
    Tokens tokens(data, h.dataOffset, h.dataLine + 1);
    std::string_view tok;
    for (size_t ei = 0; ei <= size_t(h.faceElement); ++ei) {
        const PlyElement& e = h.elements[ei];
        const bool isVertex = int(ei) == h.vertexElement;
        // Each value needs a token and a separator: a cheap bound before walking.
        if (mulAdd(e.count, 2 * e.props.size(), 0) > data.size() - h.dataOffset + 1)
            failLine(name, e.line,
                     "truncated: header declares " + plural(e.count, e.name.c_str()) + " but the whole data section has only " +
                         plural(data.size() - h.dataOffset, "byte"));
        for (uint64_t i = 0; i < e.count; ++i) {
            for (const auto& p : e.props) {
                auto nextToken = [&] {
                    if (!tokens.next(tok))
                        failLine(name, tokens.line(),
                                 "truncated: file ends in " + e.name + " " + std::to_string(i) + " of " + std::to_string(e.count));
                };
                auto where = [&] { return e.name + " " + std::to_string(i) + ": "; };
                auto blankIfDropped = [&] {
                    if (p.role == PlyRole::DropList)
                        std::fill_n(data.begin() + (tok.data() - data.data()), tok.size(), ' ');
                };
                nextToken();
                if (p.countType) {
                    int64_t n;
                    if (!parseInteger(tok, n) || n < 0 || n > std::numeric_limits<int32_t>::max())
                        failLine(name, tokens.line(), where() + "bad list length " + quote(tok));
                    blankIfDropped();
                    if (p.role == PlyRole::Indices && n < 3) failLine(name, tokens.line(), where() + "face has fewer than 3 corners");
                    if (p.role == PlyRole::Indices) out.triangles += size_t(n) - 2;
                    for (int64_t k = 0; k < n; ++k) {
                        nextToken();
                        blankIfDropped();
                        if (p.role != PlyRole::Indices) continue;
                        int64_t index;
                        if (!parseInteger(tok, index)) failLine(name, tokens.line(), where() + "bad vertex index " + quote(tok));
                        if (index < 0 || uint64_t(index) >= nV)
                            failLine(name, tokens.line(), where() + "vertex index " + std::to_string(index) +
                                                              " is out of range (the file has " + plural(nV, "vertex") + ")");
                    }
                    continue;
                }
                const bool readsFloat = p.role == PlyRole::Coordinate || p.role == PlyRole::VertexFloat ||
                                        (p.role == PlyRole::Color && p.type->isFloat && p.type->size == 4);
                const bool readsInt = p.role == PlyRole::Integer || (p.role == PlyRole::Color && !readsFloat);
                if (readsFloat) {
                    float value;
                    const Num status = parseFloat(tok, value);
                    if (status != Num::Ok)
                        failLine(name, tokens.line(),
                                 (isVertex && p.role == PlyRole::Coordinate ? "vertex " + std::to_string(i) + ": "
                                                                            : where() + p.name + ": ") +
                                     describeBadFloat(status, tok));
                } else if (readsInt) {
                    int64_t value;
                    if (!parseInteger(tok, value) || value < std::numeric_limits<int32_t>::min() ||
                        value > std::numeric_limits<int32_t>::max())
                        failLine(name, tokens.line(), where() + p.name + ": " + quote(tok) + " is not an integer");
                }
            }
        }
    }
    out.vertices = nV;
    return out;
}

Prepass validatePlyBinary(std::string& data, const std::string& name, const PlyHeader& h, bool& compacted) {
    Prepass out;
    const bool be = h.encoding == PlyHeader::Encoding::BinaryBe;
    const uint64_t nV = h.elements[size_t(h.vertexElement)].count;

    // Smallest data the header allows: every scalar, every list length, three corners a face.
    uint64_t need = 0;
    for (const auto& e : h.elements) {
        uint64_t record = 0;
        for (const auto& p : e.props)
            record += p.countType ? uint64_t(p.countType->size) + (p.role == PlyRole::Indices ? 3u * uint64_t(p.type->size) : 0u)
                                  : uint64_t(p.type->size);
        need = mulAdd(e.count, record, need);
    }
    const uint64_t have = data.size() - h.dataOffset;
    if (need > have)
        failOffset(name, h.dataOffset,
                   "truncated: the header's element counts need at least " + std::to_string(need) + " bytes of data but only " +
                       std::to_string(have) + " follow");

    size_t pos = h.dataOffset;
    // Face lists the reader cannot skip are squeezed out as the walk goes: every kept value
    // moves to `kept`, which never passes `pos`, so nothing is overwritten before it is read.
    size_t kept = pos;
    auto take = [&](size_t bytes, const PlyElement& e, uint64_t i) {
        if (data.size() - pos < bytes)
            failOffset(name, pos, "truncated: file ends in " + e.name + " " + std::to_string(i) + " of " + std::to_string(e.count));
        const char* p = data.data() + pos;
        pos += bytes;
        return p;
    };
    for (size_t ei = 0; ei <= size_t(h.faceElement); ++ei) {
        const PlyElement& e = h.elements[ei];
        for (uint64_t i = 0; i < e.count; ++i) {
            for (const auto& p : e.props) {
                const size_t at = pos;
                if (p.countType) {
                    const char* c = take(size_t(p.countType->size), e, i);
                    const int64_t n = p.countType->isSigned ? readSigned(c, p.countType->size, be)
                                                            : int64_t(readUnsigned(c, p.countType->size, be));
                    if (n < 0) failOffset(name, at, e.name + " " + std::to_string(i) + ": negative list length " + std::to_string(n));
                    if (p.role == PlyRole::Indices && n < 3)
                        failOffset(name, at, e.name + " " + std::to_string(i) + ": face has fewer than 3 corners");
                    if (uint64_t(n) * uint64_t(p.type->size) > data.size() - pos)
                        failOffset(name, at, "truncated: " + e.name + " " + std::to_string(i) + " lists " + std::to_string(n) +
                                                 " values but the file ends first");
                    if (p.role == PlyRole::Indices) {
                        out.triangles += size_t(n) - 2;
                        for (int64_t k = 0; k < n; ++k) {
                            const size_t indexAt = pos;
                            const char* v = take(size_t(p.type->size), e, i);
                            const int64_t index = p.type->isSigned ? readSigned(v, p.type->size, be)
                                                                   : int64_t(readUnsigned(v, p.type->size, be));
                            if (index < 0 || uint64_t(index) >= nV)
                                failOffset(name, indexAt, "face " + std::to_string(i) + ": vertex index " + std::to_string(index) +
                                                              " is out of range (the file has " + plural(nV, "vertex") + ")");
                        }
                    } else {
                        pos += size_t(n) * size_t(p.type->size);
                    }
                } else {
                    const char* v = take(size_t(p.type->size), e, i);
                    if (p.role == PlyRole::Coordinate) {
                        const double value = p.type->size == 4 ? readFloat32(v, be) : readFloat64(v, be);
                        if (!std::isfinite(value) || std::fabs(value) > double(FLT_MAX))
                            failOffset(name, at, "vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
                    }
                }
                if (p.role == PlyRole::DropList) continue;
                if (kept != at) std::memmove(data.data() + kept, data.data() + at, pos - at);
                kept += pos - at;
            }
        }
    }
    // The reader stops after the faces; with lists removed, what follows would be misplaced.
    compacted = kept != pos;
    if (compacted) data.resize(kept);
    out.vertices = nV;
    return out;
}

Prepass validatePly(std::string& data, const std::string& name) {
    const PlyHeader h = parsePlyHeader(data, name);
    bool compacted = false;
    Prepass out = h.encoding == PlyHeader::Encoding::Ascii ? validatePlyAscii(data, name, h)
                                                           : validatePlyBinary(data, name, h, compacted);
    rewritePlyHeader(data, h, compacted);
    out.warnings = h.warnings;
    return out;
}

// ---------------------------------------------------------------------------------------------
// OM (OpenMesh's own binary format)

// Layout of OMFormat::Chunk::Header, a little-endian uint16.
struct OmChunk {
    unsigned name, entity, type, isFloat, dim, bits;
    explicit OmChunk(unsigned v)
        : name((v >> 1) & 1), entity((v >> 2) & 7), type((v >> 5) & 15), isFloat((v >> 10) & 1), dim(((v >> 11) & 7) + 1),
          bits((v >> 14) & 3) {}
};

enum OmEntity { kOmVertex = 0, kOmMesh = 1, kOmFace = 2, kOmEdge = 4, kOmHalfedge = 6, kOmSentinel = 7 };
enum OmType { kOmPos = 0, kOmNormal = 1, kOmTexcoord = 2, kOmStatus = 3, kOmColor = 4, kOmCustom = 6, kOmTopology = 7 };
constexpr unsigned kOmNewestVersion = (2 << 5) | 2;  // 2.2, what OpenMesh 9 writes and reads
constexpr unsigned kOmHalfedgeVersion = (2 << 5) | 0;

Prepass validateOm(std::string& data, const std::string& name) {
    Prepass out;
    if (data.size() < 2 || data[0] != 'O' || data[1] != 'M') fail(name, "not an OM file (no 'OM' magic)");
    if (data.size() < 16) fail(name, "truncated OM header (" + plural(data.size(), "byte") + ")");
    const char meshType = data[2];
    if (meshType != 'T' && meshType != 'Q' && meshType != 'P') failOffset(name, 2, "not an OM file (unknown mesh type)");
    const auto version = static_cast<unsigned char>(data[3]);
    if (version > kOmNewestVersion)
        failOffset(name, 3, "OM version " + std::to_string(version >> 5) + "." + std::to_string(version & 31) +
                                " is newer than the reader (2.2)");
    const uint64_t nV = readUnsigned(data.data() + 4, 4, false);
    const uint64_t nF = readUnsigned(data.data() + 8, 4, false);
    const uint64_t nE = readUnsigned(data.data() + 12, 4, false);
    if (nV > uint64_t(std::numeric_limits<int32_t>::max()) || nF > uint64_t(std::numeric_limits<int32_t>::max()) ||
        nE > uint64_t(std::numeric_limits<int32_t>::max() / 2))
        failOffset(name, 4, "OM element counts too large");

    size_t pos = 16;
    auto need = [&](size_t at, uint64_t bytes, const char* what) {
        if (bytes > data.size() - pos)
            failOffset(name, at, std::string("truncated: ") + what + " needs " + std::to_string(bytes) + " bytes but only " +
                                     std::to_string(data.size() - pos) + " are left");
    };
    while (pos < data.size()) {
        const size_t at = pos;
        need(at, 2, "chunk header");
        const OmChunk c(unsigned(readUnsigned(data.data() + pos, 2, false)));
        pos += 2;
        if (c.name) {
            need(at, 1, "property name");
            const auto len = static_cast<unsigned char>(data[pos]);
            need(at, 1 + uint64_t(len), "property name");
            pos += 1 + len;
        }
        if (c.entity == kOmSentinel) break;
        uint64_t elements;
        switch (c.entity) {
        case kOmVertex: elements = nV; break;
        case kOmFace: elements = nF; break;
        case kOmEdge: elements = nE; break;
        case kOmHalfedge: elements = 2 * nE; break;
        case kOmMesh: elements = 1; break;
        default: failOffset(name, at, "unknown OM chunk entity " + std::to_string(c.entity));
        }
        const uint64_t intSize = uint64_t(1) << c.bits;
        auto vectors = [&](unsigned dim, uint64_t bytesEach) {
            // The reader asserts on these dimensions.
            if (c.dim != dim) failOffset(name, at, "OM chunk has dimension " + std::to_string(c.dim) + ", expected " + std::to_string(dim));
            need(at, elements * bytesEach, "chunk data");
            return elements * bytesEach;
        };
        auto floatVectors = [&](const char* what) {
            // The reader picks float or double by the size field alone and reads nothing for
            // other sizes, losing its place.
            if (c.bits > 1) failOffset(name, at, std::string("unsupported ") + what + " format in OM chunk");
            return vectors(3, c.bits == 0 ? 12 : 24);
        };
        uint64_t bytes = 0;
        if (c.type == kOmCustom) {
            if (version > ((2 << 5) | 1)) {  // from 2.2 on, custom chunks name their type
                need(at, 1, "property type");
                const auto len = static_cast<unsigned char>(data[pos]);
                need(at, 1 + uint64_t(len), "property type");
                // OpenMesh 9 creates a property of a known type in the importer's empty kernel
                // whatever the options say, restores no data into it and then asserts. No type
                // is called "???", so the reader skips the block.
                std::fill_n(data.begin() + long(pos) + 1, len, '?');
                pos += 1 + len;
            }
            need(at, 4, "property size");
            bytes = 4 + readUnsigned(data.data() + pos, 4, false);
            need(at, bytes, "property data");
        } else if (c.entity == kOmVertex && c.type == kOmPos) {
            bytes = floatVectors("position");
            out.vertices = size_t(nV);  // only now known to be backed by data
            for (uint64_t v = 0; v < nV; ++v) {
                for (int k = 0; k < 3; ++k) {
                    const size_t offset = pos + size_t(v * (c.bits == 0 ? 12 : 24)) + size_t(k * (c.bits == 0 ? 4 : 8));
                    const double value = c.bits == 0 ? readFloat32(data.data() + offset, false) : readFloat64(data.data() + offset, false);
                    if (!std::isfinite(value) || std::fabs(value) > double(FLT_MAX))
                        failOffset(name, offset, "vertex " + std::to_string(v) + " has a NaN or infinite coordinate");
                }
            }
        } else if ((c.entity == kOmVertex || c.entity == kOmFace) && c.type == kOmNormal) {
            bytes = floatVectors("normal");
        } else if ((c.entity == kOmVertex || c.entity == kOmHalfedge) && c.type == kOmTexcoord) {
            bytes = vectors(2, 8);  // always read as two floats
        } else if ((c.entity == kOmVertex || c.entity == kOmFace) && c.type == kOmColor) {
            bytes = vectors(3, 3);  // always read as three bytes
        } else if (c.type == kOmStatus && c.entity != kOmMesh) {
            bytes = vectors(1, 4);
        } else if (c.type == kOmTopology && c.entity == kOmVertex) {
            bytes = nV * intSize;
            need(at, bytes, "vertex topology");
        } else if (c.type == kOmTopology && c.entity == kOmHalfedge) {
            bytes = nE * 6 * intSize;
            need(at, bytes, "halfedge topology");
        } else if (c.type == kOmTopology && c.entity == kOmFace) {
            if (version >= kOmHalfedgeVersion) {
                bytes = nF * intSize;
                need(at, bytes, "face topology");
                out.triangles += size_t(nF);
            } else {
                // Before 2.0 faces list their vertex indices: 3 or 4 each, or a uint16 count each.
                size_t p = pos;
                for (uint64_t f = 0; f < nF; ++f) {
                    uint64_t corners = meshType == 'T' ? 3 : 4;
                    if (meshType == 'P') {
                        if (data.size() - p < 2) failOffset(name, p, "truncated: file ends in face " + std::to_string(f));
                        corners = readUnsigned(data.data() + p, 2, false);
                        p += 2;
                    }
                    if (corners < 3) failOffset(name, p, "face " + std::to_string(f) + " has fewer than 3 corners");
                    if (corners * intSize > data.size() - p) failOffset(name, p, "truncated: file ends in face " + std::to_string(f));
                    for (uint64_t k = 0; k < corners; ++k, p += size_t(intSize)) {
                        const uint64_t index = readUnsigned(data.data() + p, int(intSize), false);
                        if (index >= nV)
                            failOffset(name, p, "face " + std::to_string(f) + ": vertex index " + std::to_string(index) +
                                                    " is out of range (the file has " + plural(nV, "vertex") + ")");
                    }
                    out.triangles += size_t(corners) - 2;
                }
                bytes = p - pos;
            }
        } else {
            failOffset(name, at, "unsupported OM chunk (entity " + std::to_string(c.entity) + ", type " + std::to_string(c.type) + ")");
        }
        pos += size_t(bytes);
    }
    return out;
}

}  // namespace

Prepass validateMesh(MeshFormat format, std::string& data, const std::string& name) {
    switch (format) {
    case MeshFormat::Obj: return validateObj(data, name);
    case MeshFormat::Off: return validateOff(data, name);
    case MeshFormat::Ply: return validatePly(data, name);
    case MeshFormat::Stl: return validateStl(data, name);
    case MeshFormat::Om: return validateOm(data, name);
    }
    fail(name, "unknown mesh format");
}

}  // namespace rtwall::detail
