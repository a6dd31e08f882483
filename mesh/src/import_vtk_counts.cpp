// VTK headers before VTK reads them: what kind of file the bytes are, and the counts a header
// declares checked against the file's size (VTK's readers allocate what the header says before
// reading any of it). No VTK here: plain text and byte scanning.
#include "import_vtk.h"

#include <charconv>
#include <string>
#include <vector>

namespace rtwall::detail {

namespace vtkheader {

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw InputError(name + ": " + what); }

bool startsWith(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }

std::string_view lineAt(std::string_view data, size_t pos) {
    const size_t end = data.find('\n', pos);
    std::string_view line = data.substr(pos, end == std::string_view::npos ? std::string_view::npos : end - pos);
    if (line.size() > 256) line = line.substr(0, 256);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line;
}

// Splits a header line into whitespace-separated tokens.
std::vector<std::string_view> tokens(std::string_view line) {
    std::vector<std::string_view> out;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        size_t j = i;
        while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
        if (j > i) out.push_back(line.substr(i, j - i));
        i = j;
    }
    return out;
}

}  // namespace vtkheader

namespace {

using namespace vtkheader;

// ---------------------------------------------------------------------------------------------
// Header counts

struct Limits {
    uint64_t values;  // the most numbers the file can hold
};

bool parseCount(std::string_view t, uint64_t& v) {
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

void walkLegacyBinary(std::string_view data, size_t pos, const std::string& name);

void checkLegacy(std::string_view data, const std::string& name) {
    // Every number takes at least one byte in a binary file and two ("0 ") in an ASCII one.
    const bool binary = [&] {
        size_t pos = 0;
        for (int line = 0; line < 2 && pos != std::string_view::npos; ++line) {
            pos = data.find('\n', pos);
            if (pos != std::string_view::npos) ++pos;
        }
        return pos != std::string_view::npos && startsWith(lineAt(data, pos), "BINARY");
    }();
    const uint64_t limit = binary ? data.size() : data.size() / 2 + 1;
    if (binary) {
        size_t pos = 0;
        for (int line = 0; line < 4 && pos != std::string_view::npos; ++line) {
            pos = data.find('\n', pos);
            if (pos != std::string_view::npos) ++pos;
        }
        if (pos == std::string_view::npos) fail(name, "legacy VTK header is incomplete");
        walkLegacyBinary(data, pos, name);
    }
    static const char* kCounted[] = {"POINTS",     "POLYGONS", "TRIANGLE_STRIPS", "LINES",     "VERTICES",
                                     "CELLS",      "CELL_TYPES", "POINT_DATA",    "CELL_DATA", "LOOKUP_TABLE",
                                     "FIELD",      "OFFSETS",  "CONNECTIVITY",    "DIMENSIONS"};
    size_t lineNo = 1;
    for (size_t pos = 0; pos < data.size(); ++lineNo) {
        const std::string_view line = lineAt(data, pos);
        // Lines of ASCII numbers are data, not headers.
        const char c0 = line.empty() ? ' ' : line[0];
        const bool dataLine = (c0 >= '0' && c0 <= '9') || c0 == '-' || c0 == '+' || c0 == '.';
        const std::vector<std::string_view> t = dataLine ? std::vector<std::string_view>{} : tokens(line);
        if (!t.empty()) {
            const bool keyword = std::any_of(std::begin(kCounted), std::end(kCounted), [&](const char* k) { return t[0] == k; });
            if (keyword && t[0] == "DIMENSIONS") fail(name + ":line " + std::to_string(lineNo), "structured data sets are not supported (polydata and unstructured grids are)");
            // A field array header "name components tuples type" allocates components x tuples.
            uint64_t a = 0, b = 0;
            static const char* kTypes[] = {"bit", "unsigned_char", "char", "unsigned_short", "short", "unsigned_int", "int",
                                           "unsigned_long", "long", "float", "double", "vtktypeint64", "vtktypeuint64", "string"};
            const bool fieldArray = !keyword && t.size() == 4 && parseCount(t[1], a) && parseCount(t[2], b) &&
                                    std::any_of(std::begin(kTypes), std::end(kTypes), [&](const char* k) { return t[3] == k; });
            if (keyword || fieldArray) {
                uint64_t total = 0;
                for (size_t k = 1; k < t.size() && k < 3; ++k) {
                    uint64_t v = 0;
                    if (!parseCount(t[k], v)) continue;
                    if (v > limit) fail(name + ":line " + std::to_string(lineNo), std::string(t[0]) + " declares " + std::to_string(v) + " entries, more than the file's " + std::to_string(data.size()) + " bytes can hold");
                    total = fieldArray ? (k == 1 ? v : total * v) : total + (t[0] == "POINTS" ? 3 * v : v);
                }
                if (total > (fieldArray ? limit : 3 * limit))
                    fail(name + ":line " + std::to_string(lineNo), std::string(t[0]) + " declares " + std::to_string(total) + " numbers, more than the file's " + std::to_string(data.size()) + " bytes can hold");
            }
        }
        const size_t next = data.find('\n', pos);
        if (next == std::string_view::npos) break;
        pos = next + 1;
    }
}

// Binary legacy files: every section's payload must be in the file before VTK reads it. VTK's
// legacy reader does not stop cleanly on a truncated binary section (it crashed in our tests),
// so the whole section structure is walked here first.
size_t typeSize(std::string_view t) {
    if (t == "unsigned_char" || t == "char") return 1;
    if (t == "unsigned_short" || t == "short") return 2;
    if (t == "unsigned_int" || t == "int" || t == "float") return 4;
    if (t == "unsigned_long" || t == "long" || t == "double" || t == "vtktypeint64" || t == "vtktypeuint64") return 8;
    return 0;
}

void walkLegacyBinary(std::string_view data, size_t pos, const std::string& name) {
    auto failAt = [&](size_t at, const std::string& what) { fail(name + ":offset " + std::to_string(at), what); };
    auto skipSpace = [&] {
        while (pos < data.size() && (data[pos] == '\n' || data[pos] == '\r' || data[pos] == ' ' || data[pos] == '\t')) ++pos;
    };
    auto nextLine = [&](size_t& at) {
        skipSpace();
        at = pos;
        const std::string_view line = lineAt(data, pos);
        const size_t end = data.find('\n', pos);
        pos = end == std::string_view::npos ? data.size() : end + 1;
        return tokens(line);
    };
    auto count = [&](std::string_view t, size_t at) {
        uint64_t v = 0;
        if (!parseCount(t, v)) failAt(at, "expected a count, got '" + std::string(t.substr(0, 20)) + "'");
        return v;
    };
    auto payload = [&](uint64_t values, size_t size, size_t at, const std::string& what) {
        if (size == 0) failAt(at, what + ": unsupported data type");
        if (values > data.size() || values * size > data.size() - pos)
            failAt(at, what + ": truncated: needs " + std::to_string(values) + " values of " + std::to_string(size) +
                           " bytes, the file has " + std::to_string(data.size() - pos) + " bytes left");
        pos += size_t(values * size);
    };
    uint64_t attributeCount = 0;
    while (true) {
        size_t at = 0;
        const std::vector<std::string_view> t = nextLine(at);
        if (at >= data.size()) return;
        if (t.empty()) continue;
        const std::string_view k = t[0];
        const std::string key(k.substr(0, 32));
        if (k == "POINTS" && t.size() == 3) {
            payload(3 * count(t[1], at), typeSize(t[2]), at, key);
        } else if ((k == "VERTICES" || k == "LINES" || k == "POLYGONS" || k == "TRIANGLE_STRIPS" || k == "CELLS") && t.size() == 3) {
            const uint64_t n = count(t[1], at), m = count(t[2], at);
            const size_t save = pos;
            size_t at2 = 0;
            const std::vector<std::string_view> off = nextLine(at2);
            if (!off.empty() && off[0] == "OFFSETS" && off.size() == 2) {
                payload(n, typeSize(off[1]), at2, "OFFSETS");
                const std::vector<std::string_view> conn = nextLine(at2);
                if (conn.size() != 2 || conn[0] != "CONNECTIVITY") failAt(at2, "expected CONNECTIVITY after OFFSETS");
                payload(m, typeSize(conn[1]), at2, "CONNECTIVITY");
            } else {
                pos = save;
                payload(m, 4, at, key);
            }
        } else if (k == "CELL_TYPES" && t.size() == 2) {
            payload(count(t[1], at), 4, at, key);
        } else if ((k == "POINT_DATA" || k == "CELL_DATA") && t.size() == 2) {
            attributeCount = count(t[1], at);
        } else if ((k == "NORMALS" || k == "VECTORS") && t.size() == 3) {
            payload(3 * attributeCount, typeSize(t[2]), at, key);
        } else if (k == "TENSORS" && t.size() == 3) {
            payload(9 * attributeCount, typeSize(t[2]), at, key);
        } else if (k == "TEXTURE_COORDINATES" && t.size() == 4) {
            payload(count(t[2], at) * attributeCount, typeSize(t[3]), at, key);
        } else if (k == "COLOR_SCALARS" && t.size() == 3) {
            payload(count(t[2], at) * attributeCount, 1, at, key);
        } else if (k == "SCALARS" && (t.size() == 3 || t.size() == 4)) {
            const uint64_t comps = t.size() == 4 ? count(t[3], at) : 1;
            size_t at2 = 0;
            const size_t save = pos;
            const std::vector<std::string_view> lut = nextLine(at2);
            if (lut.empty() || lut[0] != "LOOKUP_TABLE") pos = save;
            payload(comps * attributeCount, typeSize(t[2]), at, key);
        } else if (k == "LOOKUP_TABLE" && t.size() == 3) {
            payload(4 * count(t[2], at), 1, at, key);
        } else if (k == "FIELD" && t.size() == 3) {
            const uint64_t arrays = count(t[2], at);
            if (arrays > data.size()) failAt(at, "FIELD declares more arrays than the file can hold");
            for (uint64_t a = 0; a < arrays; ++a) {
                size_t at2 = 0;
                const std::vector<std::string_view> arr = nextLine(at2);
                if (arr.size() == 1 && arr[0] == "NULL_ARRAY") continue;
                if (arr.size() != 4) failAt(at2, "expected a field array header 'name components tuples type'");
                const uint64_t comps = count(arr[1], at2), tuples = count(arr[2], at2);
                if (comps > data.size() || tuples > data.size()) failAt(at2, "field array larger than the file");
                payload(comps * tuples, typeSize(arr[3]), at2, "field array");
            }
        } else if (k == "METADATA") {
            // Text until an empty line.
            while (pos < data.size()) {
                const std::string_view line = lineAt(data, pos);
                const size_t end = data.find('\n', pos);
                pos = end == std::string_view::npos ? data.size() : end + 1;
                if (line.find_first_not_of(" \t\r") == std::string_view::npos) break;
            }
        } else {
            failAt(at, "unexpected section '" + key + "' in a binary legacy VTK file");
        }
    }
}

void checkXml(std::string_view data, const std::string& name) {
    // zlib and LZ4 blocks can expand by up to about 1032 times (zlib's limit); raw, base64 and
    // ASCII data take at least one byte per number.
    const bool compressed = data.find("compressor=") != std::string_view::npos;
    const uint64_t limit = compressed ? uint64_t(data.size()) * 1032 : data.size();
    for (size_t pos = data.find("NumberOf"); pos != std::string_view::npos; pos = data.find("NumberOf", pos + 8)) {
        const size_t eq = data.find("=\"", pos);
        if (eq == std::string_view::npos || eq - pos > 40) continue;
        const std::string_view key = data.substr(pos, eq - pos);
        const size_t end = data.find('"', eq + 2);
        if (end == std::string_view::npos || end - eq > 40) continue;
        uint64_t v = 0;
        const std::string_view text = data.substr(eq + 2, end - eq - 2);
        if (!parseCount(text, v)) {
            if (!text.empty() && text[0] == '-') fail(name + ":offset " + std::to_string(pos), std::string(key) + " is negative");
            continue;
        }
        const uint64_t numbers = key == "NumberOfPoints" ? 3 * v : v;
        if (v > limit || numbers > limit)
            fail(name + ":offset " + std::to_string(pos), std::string(key) + "=" + std::to_string(v) + " is more than the file's " + std::to_string(data.size()) + " bytes can hold");
    }
}

}  // namespace

VtkKind sniffVtk(std::string_view head) {
    if (startsWith(head, "# vtk DataFile Version")) return VtkKind::Legacy;
    if (startsWith(head, "#VRML V2.0")) return VtkKind::Vrml;
    head = head.substr(0, 4096);
    const size_t file = head.find("<VTKFile");
    if (file == std::string_view::npos) return VtkKind::None;
    const size_t close = head.find('>', file);
    const std::string_view tag = head.substr(file, close == std::string_view::npos ? std::string_view::npos : close - file);
    if (tag.find("type=\"PolyData\"") != std::string_view::npos) return VtkKind::XmlPolyData;
    if (tag.find("type=\"UnstructuredGrid\"") != std::string_view::npos) return VtkKind::XmlUnstructuredGrid;
    return VtkKind::None;
}

void checkVtkCounts(VtkKind kind, std::string_view data, const std::string& name) {
    if (kind == VtkKind::Legacy) checkLegacy(data, name);
    else if (kind != VtkKind::Vrml) checkXml(data, name);  // VRML has no counts: its arrays grow as read
}

}  // namespace rtwall::detail
