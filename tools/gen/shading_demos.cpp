// rtwall gen office|headlight: the shading demo scenes (also written by `rtwall bench shading`). Each writes a scene file and the
// meshes, textures and volume it needs into one directory; render it by naming the scene. The scene
// files themselves are tools/gen/scenes/*.toml, built into the library as they are.
#include "generators.h"

#include <rtwall/image.h>
#include <rtwall/mesh.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <string>

namespace rtwall::gen {

namespace {

namespace fs = std::filesystem;

std::ofstream openOut(const fs::path& file) {
    std::ofstream out(file, std::ios::binary);
    if (!out) throw InputError(file.string() + ": cannot write");
    return out;
}

// OBJ with per-vertex normals (the importer keeps them when every vertex has one).
struct ObjWriter {
    std::string v, vn, f;
    int count = 0;
    int vertex(double x, double y, double z, double nx, double ny, double nz) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "v %.6f %.6f %.6f\n", x, y, z);
        v += buf;
        const double l = std::sqrt(nx * nx + ny * ny + nz * nz);
        std::snprintf(buf, sizeof buf, "vn %.6f %.6f %.6f\n", nx / l, ny / l, nz / l);
        vn += buf;
        return ++count;
    }
    void tri(int a, int b, int c) { f += "f " + std::to_string(a) + "//" + std::to_string(a) + " " + std::to_string(b) + "//" +
                                          std::to_string(b) + " " + std::to_string(c) + "//" + std::to_string(c) + "\n"; }
    void write(const fs::path& file) const {
        auto out = openOut(file);
        out << "# written by rtwall gen\n" << v << vn << f;
    }
};

// A paraboloid reflector z = r^2 / (4 focal), open towards +z, from rMin (the bulb hole) to rMax.
void writeParaboloid(const fs::path& file, double focal, double rMin, double rMax, int rings, int segments) {
    ObjWriter o;
    for (int i = 0; i <= rings; ++i) {
        const double r = rMin + (rMax - rMin) * i / rings;
        for (int j = 0; j < segments; ++j) {
            const double a = 2 * std::numbers::pi * j / segments;
            const double x = r * std::cos(a), y = r * std::sin(a), z = r * r / (4 * focal);
            // The inside (facing the focus) is the reflecting side: normal (-x/2f, -y/2f, 1).
            o.vertex(x, y, z, -x / (2 * focal), -y / (2 * focal), 1.0);
        }
    }
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const int a = 1 + i * segments + j, b = 1 + i * segments + (j + 1) % segments;
            const int c = a + segments, d = b + segments;
            o.tri(a, b, d);
            o.tri(a, d, c);
        }
    o.write(file);
}

// A procedural poster for the office wall (an image texture).
void writePoster(const fs::path& file) {
    Image img;
    img.width = 128;
    img.height = 96;
    img.rgb.resize(size_t(img.width) * img.height * 3);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            uint8_t* p = img.pixel(x, y);
            const double u = x / 128.0, v = y / 96.0;
            const double sun = std::hypot(u - 0.7, v - 0.3) < 0.12 ? 1.0 : 0.0;
            const double hill = v > 0.65 + 0.08 * std::sin(u * 9.0) ? 1.0 : 0.0;
            p[0] = uint8_t(hill ? 40 : sun ? 250 : 90 + 100 * v);
            p[1] = uint8_t(hill ? 120 : sun ? 200 : 140 + 80 * v);
            p[2] = uint8_t(hill ? 50 : sun ? 60 : 230);
        }
    writePng(img, file);
}

// A leaf-shaped alpha mask: white inside an ellipse with a notch, black outside.
void writeLeafMask(const fs::path& file) {
    Image img;
    img.width = img.height = 64;
    img.rgb.resize(64 * 64 * 3);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const double u = (x + 0.5) / 32.0 - 1.0, v = (y + 0.5) / 32.0 - 1.0;
            const bool inside = u * u / 0.2 + v * v < 0.9 && !(std::fabs(u) < 0.04 && v > 0.6);
            uint8_t* p = img.pixel(x, y);
            p[0] = p[1] = p[2] = inside ? 255 : 0;
        }
    writePng(img, file);
}

// A smoke-like volume as legacy VTK structured points (ASCII).
void writeSmoke(const fs::path& file, int n) {
    auto out = openOut(file);
    out << "# vtk DataFile Version 3.0\nrtwall gen smoke\nASCII\nDATASET STRUCTURED_POINTS\n"
        << "DIMENSIONS " << n << " " << n << " " << n << "\nORIGIN 0 0 0\nSPACING 1 1 1\n"
        << "POINT_DATA " << n * n * n << "\nSCALARS density float 1\nLOOKUP_TABLE default\n";
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const double x = 2.0 * i / (n - 1) - 1, y = 2.0 * j / (n - 1) - 1, z = 2.0 * k / (n - 1) - 1;
                const double plume = std::exp(-4.0 * (x * x + z * z) / (0.3 + 0.5 * (y + 1)));
                const double swirl = 0.5 + 0.5 * std::sin(7 * y + 3 * x) * std::cos(5 * z - 2 * y);
                const double edge = std::max(0.0, 1.0 - std::max({std::fabs(x), std::fabs(y), std::fabs(z)}));
                char buf[32];
                std::snprintf(buf, sizeof buf, "%.4f ", plume * (0.4 + 0.6 * swirl) * std::min(1.0, 4 * edge));
                out << buf;
            }
            out << "\n";
        }
}

void writeSceneText(const fs::path& file, const std::string& text) { openOut(file) << text; }

}  // namespace

extern const char* const kOfficeScene;     // tools/gen/scenes/office.toml
extern const char* const kHeadlightScene;  // tools/gen/scenes/headlight.toml

std::filesystem::path writeShadingDemo(const std::string& name, const std::filesystem::path& d) {
    fs::create_directories(d);
    if (name == "office") {
        writePoster(d / "poster.png");
        writeLeafMask(d / "leaf_mask.png");
        writeSmoke(d / "smoke.vtk", 32);
        writeSceneText(d / "office.toml", kOfficeScene);
        return d / "office.toml";
    }
    if (name != "headlight") throw InputError("unknown demo scene '" + name + "' (office, headlight)");
    writeParaboloid(d / "reflector.obj", 1.0, 0.45, 3.0, 48, 128);
    writeSceneText(d / "headlight.toml", kHeadlightScene);
    return d / "headlight.toml";
}

}  // namespace rtwall::gen
