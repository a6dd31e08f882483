// Scene generators for `rtwall gen`: test and benchmark scenes written as real mesh files plus
// a TOML scene file, so that loading them goes through the importers.
//
// Adding a generator: write `void genFoo(const GenOptions&)` in its own file and add one line
// to generators() in generators.cpp.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace rtwall::gen {

// Options every generator understands; a generator ignores what it does not use.
struct GenOptions {
    std::filesystem::path out;       // directory; created if missing; scene.toml goes there
    int64_t triangles = 0;           // 0: the generator's default size
    int64_t instances = 0;           // 0: the generator's default (sunflowers: plants)
    int copies = 1;                  // powerplant: plants side by side
    int trees = -1;                  // sunflowers: large trees (-1: default)
    int64_t treeTriangles = 0;       // sunflowers: triangles per tree (0: default)
    uint64_t seed = 1;
    bool cache = true;               // write [load] cache = true into the scene
    bool rows = false;               // step, step-curved, iges: modules grouped into one sub-assembly per row
    bool flat = false;               // step, iges: every part a solid of its own, its placement baked into its
                                     // geometry (as meshers and flat exports write), plus a mirrored bracket
    std::string stepUnit{};          // step, step-curved: the file's length unit as OCCT's write.step.unit
                                     // names it ("MM", "M", "INCH", ...); empty: millimetres
};

struct Generator {
    std::string help;
    std::function<void(const GenOptions&)> run;
};

// Name -> generator, in the order `rtwall gen --help` lists them.
const std::map<std::string, Generator>& generators();

void genPowerplant(const GenOptions& o);
void genSunflowers(const GenOptions& o);
// The shading demos (shading_demos.cpp): writes `name` ("office" or "headlight") into `dir`;
// returns the scene file.
std::filesystem::path writeShadingDemo(const std::string& name, const std::filesystem::path& dir);
void genStep(const GenOptions& o);  // step_assembly.cpp: OpenCASCADE, the generator's only OCCT unit
void genIges(const GenOptions& o);  // step_assembly.cpp: the same assembly as IGES
void genStepCurved(const GenOptions& o);  // step_assembly.cpp: curved parts (fillets, spheres, tori)

// ---- building blocks shared by the generators ------------------------------------------------

// A triangle mesh under construction, positions in double precision (CAD coordinates).
struct MeshBuilder {
    std::vector<double> p;        // 3 per vertex
    std::vector<float> n;         // 3 per vertex, or empty
    std::vector<uint32_t> tri;    // 3 per triangle
    uint32_t vertex(double x, double y, double z) {
        p.insert(p.end(), {x, y, z});
        return uint32_t(p.size() / 3 - 1);
    }
    void triangle(uint32_t a, uint32_t b, uint32_t c) { tri.insert(tri.end(), {a, b, c}); }
    void quad(uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
        triangle(a, b, c);
        triangle(a, c, d);
    }
    size_t vertices() const { return p.size() / 3; }
    size_t triangles() const { return tri.size() / 3; }
};

using Vec3 = std::array<double, 3>;

// Shapes appended to a builder (all closed, wound counter-clockwise from outside).
void addBox(MeshBuilder& m, Vec3 lo, Vec3 hi);
// A tube of `radius` with `sides` sides along the polyline `path` (open ends capped).
void addTube(MeshBuilder& m, const std::vector<Vec3>& path, double radius, int sides);
// An I-beam from a to b (long thin triangles, as CAD girders are).
void addIBeam(MeshBuilder& m, Vec3 a, Vec3 b, double height, double width);
// A vertical cylinder tank with a domed top.
void addTank(MeshBuilder& m, Vec3 base, double radius, double height, int sides);
// A UV sphere.
void addSphere(MeshBuilder& m, Vec3 c, double radius, int rings, int segments);

// Mesh file writers. Positions are written in double where the format allows (VTK), else float.
void writePlyBinary(const std::filesystem::path& file, const MeshBuilder& m);
void writeObj(const std::filesystem::path& file, const MeshBuilder& m);
void writeVtkLegacyBinary(const std::filesystem::path& file, const MeshBuilder& m);
void writeVtp(const std::filesystem::path& file, const MeshBuilder& m);  // appended raw, Float64 points
// An unstructured grid of triangle cells (type 5).
void writeVtu(const std::filesystem::path& file, const MeshBuilder& m);

// Writes the text atomically enough for a generator (whole file, then close, checked).
void writeText(const std::filesystem::path& file, const std::string& text);

}  // namespace rtwall::gen
