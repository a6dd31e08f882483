// The PLY pre-pass: the header (types, elements, properties, suspicious names), normalised in
// place for OpenMesh, and the ASCII or binary body checked against it.
#include "validate_scan.h"

namespace rtwall::detail {
namespace {

using namespace scan;

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

// A 'format <encoding> <version>' line.
void readPlyFormat(PlyHeader& h, const std::vector<std::string_view>& tokens, const std::string& name, size_t line) {
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
}

// An 'element <name> <count>' line.
void readPlyElement(PlyHeader& h, const std::vector<std::string_view>& tokens, const std::string& name, size_t line) {
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
}

// A 'property <type> <name>' or 'property list <count type> <entry type> <name>' line of the
// last element; texture coordinate names are normalised in `data`.
void readPlyProperty(PlyHeader& h, std::string& data, const std::vector<std::string_view>& tokens, const std::string& name,
                     size_t line) {
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
            readPlyFormat(h, tokens, name, line);
        } else if (key == "element") {
            readPlyElement(h, tokens, name, line);
        } else if (key == "property") {
            readPlyProperty(h, data, tokens, name, line);
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

}  // namespace

Prepass validatePly(std::string& data, const std::string& name) {
    const PlyHeader h = parsePlyHeader(data, name);
    bool compacted = false;
    Prepass out = h.encoding == PlyHeader::Encoding::Ascii ? validatePlyAscii(data, name, h)
                                                           : validatePlyBinary(data, name, h, compacted);
    rewritePlyHeader(data, h, compacted);
    out.warnings = h.warnings;
    return out;
}

}  // namespace rtwall::detail
