// What the mesh validators share (validate.cpp, validate_ply.cpp): one-line errors naming the
// file and the line or offset, tokenising lines, parsing numbers as the readers' streams would
// (whole tokens only), and reading binary fields of either byte order with overflow checks.
// Internal to rtwall_mesh.
#pragma once

#include "validate.h"

#include "rtwall/mesh.h"

#include <algorithm>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace rtwall::detail::scan {

// ---------------------------------------------------------------------------------------------
// Errors

[[noreturn]] inline void fail(const std::string& name, const std::string& what) { throw InputError(name + ": " + what); }

[[noreturn]] inline void failLine(const std::string& name, size_t line, const std::string& what) {
    throw InputError(name + ":line " + std::to_string(line) + ": " + what);
}

[[noreturn]] inline void failOffset(const std::string& name, size_t offset, const std::string& what) {
    throw InputError(name + ":offset " + std::to_string(offset) + ": " + what);
}

// Quotes a token for an error message. Tokens come from untrusted files, so they are shortened
// and control bytes are escaped: the message stays one printable line.
inline std::string quote(std::string_view token) {
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

inline std::string plural(uint64_t n, std::string_view noun) {
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

inline char lower(char c) { return (c >= 'A' && c <= 'Z') ? char(c - 'A' + 'a') : c; }

inline bool equalsNoCase(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return lower(x) == lower(y); });
}

inline void splitTokens(std::string_view line, std::vector<std::string_view>& tokens) {
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

inline void rejectNul(const std::string& data, const std::string& name, size_t from = 0) {
    const size_t nul = data.find('\0', from);
    if (nul != std::string::npos) failOffset(name, nul, "binary data (a NUL byte) in a text file");
}

// ---------------------------------------------------------------------------------------------
// Numbers, parsed the way std::istream would accept them (the readers use operator>>), but
// requiring the whole token: istream would stop at the first bad character and leave the rest
// for the next read, which misaligns every value after it.

enum class Num { Ok, Bad, NonFinite, TooLarge };

inline Num parseFloat(std::string_view t, float& out) {
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

inline bool parseInteger(std::string_view t, int64_t& out) {
    if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
    auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
    return ec == std::errc() && ptr == t.data() + t.size();
}

inline std::string describeBadFloat(Num status, std::string_view token) {
    switch (status) {
    case Num::NonFinite: return "NaN or infinite value " + quote(token);
    case Num::TooLarge: return "value " + quote(token) + " is too large for a float";
    default: return quote(token) + " is not a number";
    }
}

// ---------------------------------------------------------------------------------------------
// Binary reading

inline uint64_t readUnsigned(const char* p, int bytes, bool bigEndian) {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) {
        const auto b = static_cast<unsigned char>(p[bigEndian ? i : bytes - 1 - i]);
        v = (v << 8) | b;
    }
    return v;
}

inline int64_t readSigned(const char* p, int bytes, bool bigEndian) {
    const uint64_t u = readUnsigned(p, bytes, bigEndian);
    const int shift = 64 - 8 * bytes;
    return static_cast<int64_t>(u << shift) >> shift;
}

inline float readFloat32(const char* p, bool bigEndian) {
    const auto u = static_cast<uint32_t>(readUnsigned(p, 4, bigEndian));
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

inline double readFloat64(const char* p, bool bigEndian) {
    const uint64_t u = readUnsigned(p, 8, bigEndian);
    double d;
    std::memcpy(&d, &u, 8);
    return d;
}

// a * b + c, saturating instead of wrapping: header counts are untrusted.
inline uint64_t mulAdd(uint64_t a, uint64_t b, uint64_t c) {
    constexpr uint64_t kMax = std::numeric_limits<uint64_t>::max();
    if (b != 0 && a > (kMax - c) / b) return kMax;
    return a * b + c;
}

}  // namespace rtwall::detail::scan

namespace rtwall::detail {

// PLY, in validate_ply.cpp.
Prepass validatePly(std::string& data, const std::string& name);

}  // namespace rtwall::detail
