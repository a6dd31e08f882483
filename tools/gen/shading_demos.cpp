// rtwall gen office|headlight: the shading demo scenes (also written by `rtwall bench shading`). Each writes a scene file and the
// meshes, textures and volume it needs into one directory; render it by naming the scene.
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

const char* kOffice = R"(# rtwall gen office: shadows, a mirror, glass, procedural and image textures, a bump map,
# alpha-masked leaves and a smoke volume on the desk.
# Render:  rtwall render office.toml --out office.png        (add --gi --frames 16 for GI)

[image]
width = 800
height = 600
tile = 32

[render]
max_depth = 16
supersample = 1
background = [0.6, 0.7, 0.85]
ambient = [0.05, 0.05, 0.06]
prune_threshold = 0.002

[[mesh]]
name = "quad"
shape = "quad"

[[mesh]]
name = "box"
shape = "box"

[[mesh]]
name = "sphere"
shape = "sphere"
rings = 32
segments = 64

[[material]]
name = "parquet"
type = "lambert"
color = [0.65, 0.45, 0.25]
texture = "wood"
texture_color2 = [0.35, 0.2, 0.1]
texture_scale = 0.7

[[material]]
name = "wall"
type = "lambert"
color = [0.85, 0.83, 0.78]
bump = 0.02
bump_scale = 0.05

[[material]]
name = "poster"
type = "lambert"
texture = "image"
texture_file = "poster.png"
texture_mapping = "xz"
texture_scale = 2.0

[[material]]
name = "marble"
type = "phong"
color = [0.9, 0.9, 0.88]
specular = [0.3, 0.3, 0.3]
shininess = 80
texture = "marble"
texture_color2 = [0.3, 0.3, 0.35]
texture_scale = 0.3

[[material]]
name = "steel"
type = "metal"
color = [0.75, 0.75, 0.78]
roughness = 0.25

[[material]]
name = "mirror"
type = "mirror"
color = [0.95, 0.95, 0.95]

[[material]]
name = "glass"
type = "glass"
color = [0.95, 1.0, 0.97]
ior = 1.5
absorption = [0.6, 0.1, 0.4]

[[material]]
name = "tiles"
type = "lambert"
color = [0.8, 0.8, 0.8]
texture = "checker"
texture_color2 = [0.15, 0.2, 0.4]
texture_scale = 0.25

[[material]]
name = "leaf"
type = "lambert"
color = [0.2, 0.55, 0.15]
alpha = "image"
alpha_file = "leaf_mask.png"
alpha_scale = 2.0

[[material]]
name = "smoke"
type = "volume"
volume_file = "smoke.vtk"
volume_step = 0.5
transfer = [[0.0, 0.9, 0.9, 0.9, 0.0], [0.2, 0.8, 0.8, 0.85, 2.0], [0.6, 1.0, 0.7, 0.4, 8.0]]

# The lamp panel shows the ceiling light: the area light's radiance (colour x intensity), on its
# parallelogram (0.01 behind it), so the renderer takes it for the light's visible face and counts
# the lamp once under GI (docs/shading.md). One-sided: its back does not light the ceiling.
[[material]]
name = "lamp"
type = "emissive"
emission = [6, 5.7, 5.1]

# Room: floor, back wall with a poster, side wall with a mirror, ceiling with a lamp panel.
[[instance]]
mesh = "quad"
material = "parquet"
scale = [4, 1, 4]

[[instance]]
mesh = "quad"
material = "wall"
scale = [4, 1, 1.5]
rotate = [90, 0, 0]
translate = [0, 1.5, -4]

[[instance]]
mesh = "quad"
material = "poster"
scale = [0.8, 1, 0.6]
rotate = [90, 0, 0]
translate = [-1.2, 1.7, -3.98]

[[instance]]
mesh = "quad"
material = "wall"
scale = [4, 1, 1.5]
rotate = [0, 0, -90]
translate = [-4, 1.5, 0]

[[instance]]
mesh = "quad"
material = "mirror"
scale = [1.2, 1, 0.8]
rotate = [0, 0, -90]
translate = [-3.97, 1.4, -0.8]

[[instance]]
mesh = "quad"
material = "wall"
scale = [4, 1, 4]
rotate = [180, 0, 0]
translate = [0, 3, 0]

[[instance]]
mesh = "quad"
material = "lamp"
scale = [0.6, 1, 0.6]
rotate = [180, 0, 0]
translate = [0, 2.99, -1]

# Desk: marble top on steel legs.
[[instance]]
mesh = "box"
material = "marble"
scale = [1.2, 0.04, 0.6]
translate = [0, 0.76, -1.5]

[[instance]]
mesh = "box"
material = "steel"
scale = [0.03, 0.36, 0.03]
translate = [-1.1, 0.36, -1.0]

[[instance]]
mesh = "box"
material = "steel"
scale = [0.03, 0.36, 0.03]
translate = [1.1, 0.36, -1.0]

[[instance]]
mesh = "box"
material = "steel"
scale = [0.03, 0.36, 0.03]
translate = [-1.1, 0.36, -2.0]

[[instance]]
mesh = "box"
material = "steel"
scale = [0.03, 0.36, 0.03]
translate = [1.1, 0.36, -2.0]

# On the desk: a glass ball, a glass block, a tiled box, the smoke volume.
[[instance]]
mesh = "sphere"
material = "glass"
scale = 0.18
translate = [-0.6, 0.98, -1.3]

[[instance]]
mesh = "box"
material = "glass"
scale = [0.12, 0.12, 0.12]
translate = [-0.2, 0.92, -1.7]

[[instance]]
mesh = "box"
material = "tiles"
scale = [0.15, 0.1, 0.15]
translate = [0.3, 0.9, -1.2]

[[instance]]
mesh = "box"
material = "smoke"
scale = [0.25, 0.35, 0.25]
translate = [0.7, 1.15, -1.7]

# A plant: alpha-masked leaves on a steel stem.
[[instance]]
mesh = "box"
material = "steel"
scale = [0.02, 0.6, 0.02]
translate = [2.5, 0.6, -2.5]

[[instance]]
mesh = "quad"
material = "leaf"
scale = [0.35, 1, 0.35]
rotate = [30, 20, 0]
translate = [2.5, 1.1, -2.3]

[[instance]]
mesh = "quad"
material = "leaf"
scale = [0.35, 1, 0.35]
rotate = [-35, 70, 0]
translate = [2.6, 0.9, -2.6]

[[instance]]
mesh = "quad"
material = "leaf"
scale = [0.35, 1, 0.35]
rotate = [40, -60, 10]
translate = [2.35, 1.3, -2.55]

[[light]]
type = "area"
position = [-0.6, 2.98, -1.6]
edge1 = [1.2, 0, 0]
edge2 = [0, 0, 1.2]
color = [1, 0.95, 0.85]
intensity = 6

[[light]]
type = "point"
position = [2.5, 2.5, 1.5]
intensity = 4

[[camera]]
name = "desk"
position = [1.8, 1.7, 2.4]
look_at = [-0.2, 0.9, -1.6]
fov = 55

[[camera]]
name = "mirror"
position = [1.5, 1.5, 0.5]
look_at = [-4, 1.3, -0.8]
fov = 50
)";

const char* kHeadlight = R"(# rtwall gen headlight: a parabolic reflector, a bulb and a structured lens; paths of up to
# 32 reflections and refractions, pruned by contribution.
# Render:  rtwall render headlight.toml --out headlight.png    (--view depth shows the ray depth)

[image]
width = 800
height = 600
tile = 32

[render]
max_depth = 32
supersample = 1
background = [0.02, 0.02, 0.03]
ambient = [0.02, 0.02, 0.02]
prune_threshold = 0.002

[[mesh]]
name = "reflector"
file = "reflector.obj"

[[mesh]]
name = "sphere"
shape = "sphere"
rings = 32
segments = 64

[[mesh]]
name = "box"
shape = "box"

[[mesh]]
name = "quad"
shape = "quad"

# A polished reflector, as real headlight reflectors (vacuum-metallised) are: it images the
# filament. A glossy one (roughness > 0) shows the point light's highlight instead, whose
# one-sample lobe is the noisiest thing a pruned deep path can reach.
[[material]]
name = "chrome"
type = "metal"
color = [0.92, 0.92, 0.95]
roughness = 0

[[material]]
name = "bulb_glass"
type = "glass"
color = [1, 1, 1]
ior = 1.5

[[material]]
name = "filament"
type = "emissive"
emission = [30, 26, 18]

[[material]]
name = "lens"
type = "glass"
color = [0.97, 0.98, 1.0]
ior = 1.52
absorption = [0.02, 0.02, 0.01]
bump = 0.02
bump_scale = 0.6

[[material]]
name = "lenslet"
type = "glass"
color = [0.98, 0.98, 1.0]
ior = 1.52

[[material]]
name = "housing"
type = "phong"
color = [0.05, 0.05, 0.05]
specular = [0.2, 0.2, 0.2]
shininess = 40

[[material]]
name = "floor"
type = "lambert"
color = [0.5, 0.5, 0.5]
texture = "checker"
texture_color2 = [0.3, 0.3, 0.3]
texture_scale = 2.0

# The reflector (focus at z = 1), the bulb around the focus, a filament behind it.
[[instance]]
mesh = "reflector"
material = "chrome"

[[instance]]
mesh = "sphere"
material = "bulb_glass"
scale = 0.35
translate = [0, 0, 1]

[[instance]]
mesh = "box"
material = "filament"
scale = [0.05, 0.05, 0.12]
translate = [0, 0, 0.75]

# The lens: a bumped glass plate with a 5 x 5 grid of flattened glass lenslets just in front
# (not overlapping it: every glass surface has air on its other side, which is what the glass
# material assumes; overlapping solids gave rays a glass-to-glass interface it treats as air).
[[instance]]
mesh = "box"
material = "lens"
scale = [3.1, 3.1, 0.08]
translate = [0, 0, 2.35]
)";

const char* kHeadlightTail = R"(
# Housing behind the reflector, a floor the beam falls on.
[[instance]]
mesh = "box"
material = "housing"
scale = [3.3, 3.3, 0.1]
translate = [0, 0, -0.2]

[[instance]]
mesh = "quad"
material = "floor"
scale = 40
translate = [0, -3.5, 0]

[[light]]
type = "point"
position = [0, 0, 1]
color = [1, 0.92, 0.8]
intensity = 20

[[light]]
type = "directional"
direction = [-0.3, -1, -0.5]
intensity = 0.3

[[camera]]
name = "front"
position = [7, 3.0, 14.0]
look_at = [0, 0, 1.2]
fov = 35

[[camera]]
name = "axis"
position = [0, 0, 9.0]
look_at = [0, 0, 0]
fov = 35
)";

}  // namespace

std::filesystem::path writeShadingDemo(const std::string& name, const std::filesystem::path& d) {
    fs::create_directories(d);
    if (name == "office") {
        writePoster(d / "poster.png");
        writeLeafMask(d / "leaf_mask.png");
        writeSmoke(d / "smoke.vtk", 32);
        writeSceneText(d / "office.toml", kOffice);
        return d / "office.toml";
    }
    if (name != "headlight") throw InputError("unknown demo scene '" + name + "' (office, headlight)");
    writeParaboloid(d / "reflector.obj", 1.0, 0.45, 3.0, 48, 128);
    std::string scene = kHeadlight;
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j) {
            char buf[200];
            std::snprintf(buf, sizeof buf,
                          "\n[[instance]]\nmesh = \"sphere\"\nmaterial = \"lenslet\"\nscale = [0.5, 0.5, 0.12]\n"
                          "translate = [%.2f, %.2f, 2.56]\n",
                          (i - 2) * 1.1, (j - 2) * 1.1);
            scene += buf;
        }
    scene += kHeadlightTail;
    writeSceneText(d / "headlight.toml", scene);
    return d / "headlight.toml";
}

}  // namespace rtwall::gen
