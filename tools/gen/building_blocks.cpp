// Shapes and mesh file writers for the generators.
#include "generators.h"

#include <rtwall/double3.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <stdexcept>

namespace rtwall::gen {

namespace {

constexpr double kPi = std::numbers::pi;

Double3 d3(const Vec3& a) { return {a[0], a[1], a[2]}; }

// Two unit vectors perpendicular to d and to each other.
void frame(const Double3& d, Double3& u, Double3& v) {
    const Double3 helper = std::fabs(d.y) < 0.9 ? Double3{0, 1, 0} : Double3{1, 0, 0};
    u = d.cross(helper).normalized();
    v = d.cross(u);
}

void checkedClose(std::ofstream& out, const std::filesystem::path& file) {
    out.close();
    if (!out) throw std::runtime_error(file.string() + ": cannot write (disk full?)");
}

std::ofstream openOut(const std::filesystem::path& file) {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(file.string() + ": cannot create");
    return out;
}

// v's bytes in the given byte order (the mesh formats fix theirs).
template <std::endian Order, class T>
void putBytes(std::string& s, T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if constexpr (std::endian::native != Order)
        for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    s.append(reinterpret_cast<const char*>(b), sizeof(T));
}
template <class T> void putBE(std::string& s, T v) { putBytes<std::endian::big>(s, v); }
template <class T> void putLE(std::string& s, T v) { putBytes<std::endian::little>(s, v); }

}  // namespace

void addBox(MeshBuilder& m, Vec3 lo, Vec3 hi) {
    uint32_t v[8];
    for (int i = 0; i < 8; ++i) v[i] = m.vertex(i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
    m.quad(v[0], v[2], v[3], v[1]);  // -z
    m.quad(v[4], v[5], v[7], v[6]);  // +z
    m.quad(v[0], v[1], v[5], v[4]);  // -y
    m.quad(v[2], v[6], v[7], v[3]);  // +y
    m.quad(v[0], v[4], v[6], v[2]);  // -x
    m.quad(v[1], v[3], v[7], v[5]);  // +x
}

void addTube(MeshBuilder& m, const std::vector<Vec3>& path, double radius, int sides) {
    if (path.size() < 2) return;
    const uint32_t first = uint32_t(m.vertices());
    for (size_t i = 0; i < path.size(); ++i) {
        const Double3 d = (i + 1 < path.size() ? d3(path[i + 1]) - d3(path[i]) : d3(path[i]) - d3(path[i - 1])).normalized();
        Double3 u, v;
        frame(d, u, v);
        for (int s = 0; s < sides; ++s) {
            const double a = 2 * kPi * s / sides;
            const Double3 q = d3(path[i]) + (u * (radius * std::cos(a)) + v * (radius * std::sin(a)));
            m.vertex(q.x, q.y, q.z);
        }
    }
    for (size_t i = 0; i + 1 < path.size(); ++i)
        for (int s = 0; s < sides; ++s) {
            const uint32_t a = first + uint32_t(i * sides + s), b = first + uint32_t(i * sides + (s + 1) % sides);
            m.quad(a, b, b + uint32_t(sides), a + uint32_t(sides));
        }
    // Caps: fans around the end centres.
    const uint32_t c0 = m.vertex(path.front()[0], path.front()[1], path.front()[2]);
    const uint32_t c1 = m.vertex(path.back()[0], path.back()[1], path.back()[2]);
    const uint32_t last = first + uint32_t((path.size() - 1) * sides);
    for (int s = 0; s < sides; ++s) {
        m.triangle(c0, first + uint32_t((s + 1) % sides), first + uint32_t(s));
        m.triangle(c1, last + uint32_t(s), last + uint32_t((s + 1) % sides));
    }
}

void addIBeam(MeshBuilder& m, Vec3 a, Vec3 b, double h, double w) {
    // The profile (flanges and web) swept along a-b: 12 corners, long quads between the ends.
    const Double3 d = (d3(b) - d3(a)).normalized();
    Double3 u, v;
    frame(d, u, v);
    const double t = 0.1 * h;  // flange and web thickness
    const double px[12] = {-w / 2, w / 2, w / 2, t / 2, t / 2, w / 2, w / 2, -w / 2, -w / 2, -t / 2, -t / 2, -w / 2};
    const double py[12] = {-h / 2, -h / 2, -h / 2 + t, -h / 2 + t, h / 2 - t, h / 2 - t, h / 2, h / 2, h / 2 - t, h / 2 - t, -h / 2 + t, -h / 2 + t};
    uint32_t ring[2][12];
    for (int e = 0; e < 2; ++e)
        for (int k = 0; k < 12; ++k) {
            const Double3 q = d3(e ? b : a) + (u * px[k] + v * py[k]);
            ring[e][k] = m.vertex(q.x, q.y, q.z);
        }
    for (int k = 0; k < 12; ++k) m.quad(ring[0][k], ring[0][(k + 1) % 12], ring[1][(k + 1) % 12], ring[1][k]);
    // End caps as three rectangles each (bottom flange, web, top flange).
    const int rects[3][4] = {{0, 1, 2, 11}, {10, 3, 4, 9}, {8, 5, 6, 7}};
    for (const auto& r : rects) {
        m.quad(ring[0][r[3]], ring[0][r[2]], ring[0][r[1]], ring[0][r[0]]);
        m.quad(ring[1][r[0]], ring[1][r[1]], ring[1][r[2]], ring[1][r[3]]);
    }
}

void addTank(MeshBuilder& m, Vec3 base, double radius, double height, int sides) {
    const int rings = std::max(2, sides / 4);
    const uint32_t first = uint32_t(m.vertices());
    // Wall (bottom ring, top ring), then dome rings, then the apex.
    for (int r = 0; r <= rings + 1; ++r) {
        double y, rr;
        if (r == 0) {
            y = 0;
            rr = radius;
        } else {
            const double phi = 0.5 * kPi * (r - 1) / rings;
            y = height + radius * 0.6 * std::sin(phi);
            rr = radius * std::cos(phi);
        }
        for (int s = 0; s < sides; ++s) {
            const double a = 2 * kPi * s / sides;
            m.vertex(base[0] + rr * std::cos(a), base[1] + y, base[2] - rr * std::sin(a));
        }
    }
    for (int r = 0; r <= rings; ++r)
        for (int s = 0; s < sides; ++s) {
            const uint32_t a = first + uint32_t(r * sides + s), b = first + uint32_t(r * sides + (s + 1) % sides);
            m.quad(a, b, b + uint32_t(sides), a + uint32_t(sides));
        }
    const uint32_t apex = m.vertex(base[0], base[1] + height + radius * 0.6, base[2]);
    const uint32_t bottom = m.vertex(base[0], base[1], base[2]);
    const uint32_t top = first + uint32_t((rings + 1) * sides);
    for (int s = 0; s < sides; ++s) {
        m.triangle(top + uint32_t(s), top + uint32_t((s + 1) % sides), apex);
        m.triangle(bottom, first + uint32_t((s + 1) % sides), first + uint32_t(s));
    }
}

void addSphere(MeshBuilder& m, Vec3 c, double radius, int rings, int segments) {
    const uint32_t first = uint32_t(m.vertices());
    for (int r = 0; r <= rings; ++r) {
        const double th = kPi * r / rings;
        for (int s = 0; s < segments; ++s) {
            const double ph = 2 * kPi * s / segments;
            m.vertex(c[0] + radius * std::sin(th) * std::cos(ph), c[1] + radius * std::cos(th),
                     c[2] - radius * std::sin(th) * std::sin(ph));
        }
    }
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            const uint32_t a = first + uint32_t(r * segments + s), b = first + uint32_t(r * segments + (s + 1) % segments);
            if (r > 0) m.triangle(a, a + uint32_t(segments), b);
            if (r + 1 < rings) m.triangle(b, a + uint32_t(segments), b + uint32_t(segments));
        }
}

void writeText(const std::filesystem::path& file, const std::string& text) {
    std::ofstream out = openOut(file);
    out << text;
    checkedClose(out, file);
}

void writePlyBinary(const std::filesystem::path& file, const MeshBuilder& m) {
    std::string s = "ply\nformat binary_little_endian 1.0\ncomment rtwall gen\nelement vertex " + std::to_string(m.vertices()) +
                    "\nproperty float x\nproperty float y\nproperty float z\n";
    if (!m.n.empty()) s += "property float nx\nproperty float ny\nproperty float nz\n";
    s += "element face " + std::to_string(m.triangles()) + "\nproperty list uchar int vertex_indices\nend_header\n";
    s.reserve(s.size() + m.vertices() * 24 + m.triangles() * 13);
    for (size_t v = 0; v < m.vertices(); ++v) {
        for (int k = 0; k < 3; ++k) putLE(s, float(m.p[3 * v + size_t(k)]));
        if (!m.n.empty())
            for (int k = 0; k < 3; ++k) putLE(s, m.n[3 * v + size_t(k)]);
    }
    for (size_t t = 0; t < m.triangles(); ++t) {
        s.push_back(3);
        for (int k = 0; k < 3; ++k) putLE(s, int32_t(m.tri[3 * t + size_t(k)]));
    }
    writeText(file, s);
}

void writeObj(const std::filesystem::path& file, const MeshBuilder& m) {
    std::string s = "# rtwall gen\n";
    char line[128];
    for (size_t v = 0; v < m.vertices(); ++v) {
        std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", m.p[3 * v], m.p[3 * v + 1], m.p[3 * v + 2]);
        s += line;
    }
    for (size_t t = 0; t < m.triangles(); ++t) {
        std::snprintf(line, sizeof line, "f %u %u %u\n", m.tri[3 * t] + 1, m.tri[3 * t + 1] + 1, m.tri[3 * t + 2] + 1);
        s += line;
    }
    writeText(file, s);
}

void writeVtkLegacyBinary(const std::filesystem::path& file, const MeshBuilder& m) {
    // Legacy binary VTK is big-endian.
    std::string s = "# vtk DataFile Version 3.0\nrtwall gen\nBINARY\nDATASET POLYDATA\nPOINTS " + std::to_string(m.vertices()) + " double\n";
    s.reserve(s.size() + m.vertices() * 24 + m.triangles() * 16 + 64);
    for (double x : m.p) putBE(s, x);
    s += "\nPOLYGONS " + std::to_string(m.triangles()) + " " + std::to_string(4 * m.triangles()) + "\n";
    for (size_t t = 0; t < m.triangles(); ++t) {
        putBE(s, int32_t(3));
        for (int k = 0; k < 3; ++k) putBE(s, int32_t(m.tri[3 * t + size_t(k)]));
    }
    s += "\n";
    writeText(file, s);
}

namespace {

// The appended-data block of an XML VTK file: a UInt64 byte count, then the bytes.
template <class T>
void appendBlock(std::string& data, const std::vector<T>& values) {
    putLE(data, uint64_t(values.size() * sizeof(T)));
    for (const T& v : values) putLE(data, v);
}

std::string xmlFile(const char* type, const std::string& piece, const std::string& data) {
    return std::string("<?xml version=\"1.0\"?>\n<VTKFile type=\"") + type +
           "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <" + type + ">\n" + piece + "  </" +
           type + ">\n  <AppendedData encoding=\"raw\">\n   _" + data + "\n  </AppendedData>\n</VTKFile>\n";
}

}  // namespace

void writeVtp(const std::filesystem::path& file, const MeshBuilder& m) {
    std::vector<int64_t> conn(m.tri.begin(), m.tri.end()), offsets(m.triangles());
    for (size_t t = 0; t < m.triangles(); ++t) offsets[t] = int64_t(3 * (t + 1));
    std::string data;
    data.reserve(m.vertices() * 24 + m.triangles() * 32 + 64);
    appendBlock(data, m.p);
    const size_t connAt = data.size();
    appendBlock(data, conn);
    const size_t offAt = data.size();
    appendBlock(data, offsets);
    size_t normAt = 0;
    if (!m.n.empty()) {
        normAt = data.size();
        appendBlock(data, m.n);
    }
    std::string piece = "    <Piece NumberOfPoints=\"" + std::to_string(m.vertices()) + "\" NumberOfPolys=\"" +
                        std::to_string(m.triangles()) + "\">\n";
    if (!m.n.empty())
        piece += "      <PointData Normals=\"Normals\">\n        <DataArray type=\"Float32\" Name=\"Normals\" NumberOfComponents=\"3\" format=\"appended\" offset=\"" +
                 std::to_string(normAt) + "\"/>\n      </PointData>\n";
    piece += "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>\n      </Points>\n"
             "      <Polys>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"" +
             std::to_string(connAt) + "\"/>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" +
             std::to_string(offAt) + "\"/>\n      </Polys>\n    </Piece>\n";
    writeText(file, xmlFile("PolyData", piece, data));
}

void writeVtu(const std::filesystem::path& file, const MeshBuilder& m) {
    std::vector<int64_t> conn(m.tri.begin(), m.tri.end()), offsets(m.triangles());
    std::vector<uint8_t> types(m.triangles(), 5);  // VTK_TRIANGLE
    for (size_t t = 0; t < m.triangles(); ++t) offsets[t] = int64_t(3 * (t + 1));
    std::string data;
    appendBlock(data, m.p);
    const size_t connAt = data.size();
    appendBlock(data, conn);
    const size_t offAt = data.size();
    appendBlock(data, offsets);
    const size_t typeAt = data.size();
    appendBlock(data, types);
    const std::string piece =
        "    <Piece NumberOfPoints=\"" + std::to_string(m.vertices()) + "\" NumberOfCells=\"" + std::to_string(m.triangles()) +
        "\">\n      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>\n      </Points>\n"
        "      <Cells>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"" +
        std::to_string(connAt) + "\"/>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" +
        std::to_string(offAt) + "\"/>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"" +
        std::to_string(typeAt) + "\"/>\n      </Cells>\n    </Piece>\n";
    writeText(file, xmlFile("UnstructuredGrid", piece, data));
}

}  // namespace rtwall::gen
