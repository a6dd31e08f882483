// The mesh pre-passes for OBJ, OFF, STL and OM (PLY: validate_ply.cpp), and the entry that picks
// one by format.
#include "validate_scan.h"

namespace rtwall::detail {
namespace {

using namespace scan;

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

// The vertex positions of an OM chunk at `pos` (float or double by `bits`): finite and within
// float range.
void checkOmPositions(const std::string& data, const std::string& name, size_t pos, uint64_t nV, unsigned bits) {
    for (uint64_t v = 0; v < nV; ++v) {
        for (int k = 0; k < 3; ++k) {
            const size_t offset = pos + size_t(v * (bits == 0 ? 12 : 24)) + size_t(k * (bits == 0 ? 4 : 8));
            const double value = bits == 0 ? readFloat32(data.data() + offset, false) : readFloat64(data.data() + offset, false);
            if (!std::isfinite(value) || std::fabs(value) > double(FLT_MAX))
                failOffset(name, offset, "vertex " + std::to_string(v) + " has a NaN or infinite coordinate");
        }
    }
}

// The face chunk of an OM file before 2.0, at `pos`; returns its size in bytes.
uint64_t omLegacyFaces(const std::string& data, const std::string& name, size_t pos, uint64_t nF, uint64_t nV, char meshType,
                       uint64_t intSize, Prepass& out) {
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
        return p - pos;
}

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
            checkOmPositions(data, name, pos, nV, c.bits);
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
                bytes = omLegacyFaces(data, name, pos, nF, nV, meshType, intSize, out);
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
