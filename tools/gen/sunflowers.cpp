// `rtwall gen sunflowers`: a field of about ten sunflower kinds (~36,000 triangles each),
// ~28,000 plants placed through two levels of groups (plant -> patch -> field), plus a few
// multi-million-triangle trees: about 10^9 triangles once instanced. Each plant is four meshes
// (stem, head, petals, leaves) so that materials and alpha masks can later be given per part;
// leaves are their own OBJ files for that reason.
#include "generators.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <sstream>

namespace rtwall::gen {

namespace {

constexpr double kPi = std::numbers::pi;

struct Rng {
    std::mt19937_64 g;
    double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(g); }
    int pick(int a, int b) { return std::uniform_int_distribution<int>(a, b)(g); }
};

MeshBuilder makeStem(Rng& r, double height, int64_t budget) {
    MeshBuilder m;
    const int sides = 12;
    const int points = int(std::max<int64_t>(2, budget / (2 * sides)));
    std::vector<Vec3> path;
    const double bend = r.uni(-0.15, 0.15);
    for (int i = 0; i < points; ++i) {
        const double t = double(i) / (points - 1);
        path.push_back({bend * t * t * height, t * height, 0.3 * bend * std::sin(3 * t) * height});
    }
    addTube(m, path, 0.02 * height / 2, sides);
    return m;
}

// Seeds on a Fermat spiral, each a low pyramid (4 triangles), on a backing disc.
MeshBuilder makeHead(Rng& r, double radius, int64_t budget) {
    MeshBuilder m;
    const int seeds = int(std::max<int64_t>(16, budget / 4));
    const double golden = kPi * (3 - std::sqrt(5.0)), s = radius / std::sqrt(double(seeds)) * 0.55;
    const double tilt = r.uni(0.2, 0.5);
    for (int i = 0; i < seeds; ++i) {
        const double rr = radius * std::sqrt((i + 0.5) / seeds), a = i * golden;
        const double x = rr * std::cos(a), y = rr * std::sin(a);
        const double z = 0.02 * radius + 0.1 * radius * (1 - rr / radius);
        // A face-on disc in the xy plane, tilted later by the plant group.
        const uint32_t b0 = m.vertex(x - s, y - s, z), b1 = m.vertex(x + s, y - s, z), b2 = m.vertex(x + s, y + s, z),
                       b3 = m.vertex(x - s, y + s, z), top = m.vertex(x, y, z + s * (1 + tilt));
        m.triangle(b0, b1, top);
        m.triangle(b1, b2, top);
        m.triangle(b2, b3, top);
        m.triangle(b3, b0, top);
    }
    addTube(m, {{0, 0, -0.05 * radius}, {0, 0, 0.02 * radius}}, radius * 1.02, 48);
    return m;
}

// Petals: curved strips around the head.
MeshBuilder makePetals(Rng& r, double radius, int64_t budget) {
    MeshBuilder m;
    const int petals = r.pick(20, 34);
    const int segs = int(std::max<int64_t>(2, budget / (4 * petals)));
    for (int p = 0; p < petals; ++p) {
        const double a = 2 * kPi * p / petals + r.uni(-0.05, 0.05), len = radius * r.uni(0.7, 1.0), w = radius * 0.18;
        const double ca = std::cos(a), sa = std::sin(a);
        uint32_t prevL = 0, prevR = 0;
        for (int i = 0; i <= segs; ++i) {
            const double t = double(i) / segs, d = radius + len * t, half = w * std::sin(kPi * std::min(1.0, t * 1.1 + 0.05)) / 2;
            const double z = -0.15 * len * t * t;
            const uint32_t L = m.vertex(d * ca - half * sa, d * sa + half * ca, z), R = m.vertex(d * ca + half * sa, d * sa - half * ca, z);
            if (i > 0) {
                m.quad(prevL, prevR, R, L);
                m.quad(prevR, prevL, L, R);  // two-sided
            }
            prevL = L;
            prevR = R;
        }
    }
    return m;
}

MeshBuilder makeLeaves(Rng& r, double height, int64_t budget) {
    MeshBuilder m;
    const int leaves = r.pick(4, 8);
    const int grid = int(std::max<double>(2, std::sqrt(double(budget) / (2.0 * leaves))));
    for (int l = 0; l < leaves; ++l) {
        const double y0 = height * (0.15 + 0.6 * l / leaves), a = r.uni(0, 2 * kPi), len = height * r.uni(0.15, 0.25);
        const double ca = std::cos(a), sa = std::sin(a);
        const uint32_t first = uint32_t(m.vertices());
        for (int i = 0; i <= grid; ++i)
            for (int j = 0; j <= grid; ++j) {
                const double u = double(i) / grid, v = double(j) / grid - 0.5;
                const double width = len * 0.5 * std::sin(kPi * u), d = len * u, droop = -0.3 * len * u * u;
                const double x = d, z = v * width;
                m.vertex(x * ca - z * sa, y0 + droop + 0.1 * len * (0.25 - v * v), x * sa + z * ca);
            }
        for (int i = 0; i < grid; ++i)
            for (int j = 0; j < grid; ++j) {
                const uint32_t a0 = first + uint32_t(i * (grid + 1) + j);
                m.quad(a0, a0 + 1, a0 + uint32_t(grid) + 2, a0 + uint32_t(grid) + 1);
            }
    }
    return m;
}

// A tree: a trunk and three levels of branches as tubes, and leaf clusters as small quads.
MeshBuilder makeTree(Rng& r, int64_t budget) {
    MeshBuilder m;
    const double height = r.uni(14, 22);
    std::vector<std::pair<std::vector<Vec3>, double>> branches;
    branches.push_back({{{0, 0, 0}, {0, height * 0.5, 0}, {r.uni(-0.5, 0.5), height, r.uni(-0.5, 0.5)}}, 0.5});
    for (int level = 0; level < 3; ++level) {
        const size_t count = branches.size();
        for (size_t b = 0; b < count; ++b) {
            const auto path = branches[b].first;
            const double radius = branches[b].second;
            for (int k = 0; k < 5; ++k) {
                const Vec3 s = path[size_t(r.pick(1, int(path.size()) - 1))];
                const double a = r.uni(0, 2 * kPi), l = height * 0.35 / (level + 1);
                branches.push_back({{s, {s[0] + l * std::cos(a), s[1] + l * 0.6, s[2] + l * std::sin(a)}}, radius * 0.45});
            }
        }
    }
    for (const auto& [path, radius] : branches) addTube(m, path, radius, 16);
    const int64_t leafBudget = std::max<int64_t>(0, budget - int64_t(m.triangles()));
    const size_t tips = branches.size();
    for (int64_t q = 0; q < leafBudget / 2; ++q) {
        const Vec3& tip = branches[size_t(r.pick(int(tips / 4), int(tips) - 1))].first.back();
        const double x = tip[0] + r.uni(-1.5, 1.5), y = tip[1] + r.uni(-1.5, 1.5), z = tip[2] + r.uni(-1.5, 1.5);
        const double a = r.uni(0, 2 * kPi), s = 0.08;
        const uint32_t v0 = m.vertex(x, y, z), v1 = m.vertex(x + s * std::cos(a), y + s, z + s * std::sin(a)),
                       v2 = m.vertex(x + 2 * s * std::cos(a), y, z + 2 * s * std::sin(a)), v3 = m.vertex(x + s * std::cos(a), y - s, z + s * std::sin(a));
        m.quad(v0, v1, v2, v3);
    }
    return m;
}

}  // namespace

void genSunflowers(const GenOptions& o) {
    const int64_t plants = o.instances > 0 ? o.instances : 28'000;
    const int64_t perPlant = o.triangles > 0 ? o.triangles : 36'000;
    const int trees = o.trees >= 0 ? o.trees : 4;
    const int64_t treeTriangles = o.treeTriangles > 0 ? o.treeTriangles : 2'500'000;
    constexpr int kKinds = 10;
    std::filesystem::create_directories(o.out / "meshes");
    Rng r{std::mt19937_64(o.seed)};

    std::ostringstream scene;
    scene << "# Generated by: rtwall gen sunflowers --instances " << plants << " --triangles " << perPlant << " --trees " << trees
          << " --tree-triangles " << treeTriangles << " --seed " << o.seed << "\n\n"
          << "[image]\nwidth = 1600\nheight = 1200\n\n[render]\nambient = [0.15, 0.16, 0.2]\nbackground = [0.45, 0.6, 0.85]\n\n"
          << "[bvh]\nquality = \"medium\"\n\n[load]\ncache = " << (o.cache ? "true" : "false") << "\n\n"
          << "[[material]]\nname = \"stem\"\ncolor = [0.25, 0.5, 0.15]\n\n[[material]]\nname = \"leaf\"\ncolor = [0.2, 0.45, 0.12]\n"
             "# Alpha-masked foliage: marble veins cut holes in the leaves, for camera and shadow rays.\n"
             "alpha = \"marble\"\nalpha_color2 = [0, 0, 0]\nalpha_scale = 0.25\nalpha_cutoff = 0.35\n\n"
          << "[[material]]\nname = \"seeds\"\ncolor = [0.25, 0.15, 0.05]\n\n[[material]]\nname = \"petal\"\ntype = \"phong\"\ncolor = [0.95, 0.75, 0.1]\nspecular = [0.1, 0.1, 0.1]\n\n"
          << "[[material]]\nname = \"bark\"\ncolor = [0.35, 0.25, 0.18]\n\n";

    for (int k = 0; k < kKinds; ++k) {
        const double height = r.uni(1.4, 2.6), head = r.uni(0.12, 0.22);
        const std::string id = std::to_string(k);
        writePlyBinary(o.out / "meshes" / ("stem" + id + ".ply"), makeStem(r, height, perPlant / 10));
        writePlyBinary(o.out / "meshes" / ("head" + id + ".ply"), makeHead(r, head, perPlant * 55 / 100));
        writeObj(o.out / "meshes" / ("petals" + id + ".obj"), makePetals(r, head, perPlant / 10));
        writeObj(o.out / "meshes" / ("leaves" + id + ".obj"), makeLeaves(r, height, perPlant / 4));
        for (const char* part : {"stem", "head", "leaves"}) {
            const std::string ext = std::string(part) == "leaves" ? "obj" : "ply";
            scene << "[[mesh]]\nname = \"" << part << id << "\"\nfile = \"meshes/" << part << id << "." << ext << "\"\n";
        }
        scene << "[[mesh]]\nname = \"petals" << id << "\"\nfile = \"meshes/petals" << id << ".obj\"\n\n";
        // The plant: its head tilted towards the sun at the top of the stem.
        char head_t[160];
        std::snprintf(head_t, sizeof head_t, "rotate = [-20, 0, 0]\ntranslate = [0, %.4f, 0.05]\n", height);
        scene << "[[group]]\nname = \"plant" << id << "\"\n"
              << "[[group.instance]]\nmesh = \"stem" << id << "\"\nmaterial = \"stem\"\n"
              << "[[group.instance]]\nmesh = \"leaves" << id << "\"\nmaterial = \"leaf\"\n"
              << "[[group.instance]]\nmesh = \"head" << id << "\"\nmaterial = \"seeds\"\n" << head_t
              << "[[group.instance]]\nmesh = \"petals" << id << "\"\nmaterial = \"petal\"\n" << head_t << "\n";
    }

    // Patches of up to 70 plants (10 x 7, jittered), forty variants; the field places patches.
    const int perPatch = int(std::min<int64_t>(70, plants));
    const int variants = int(std::min<int64_t>(40, (plants + perPatch - 1) / perPatch));
    for (int v = 0; v < variants; ++v) {
        scene << "[[group]]\nname = \"patch" << v << "\"\n";
        for (int p = 0; p < perPatch; ++p) {
            char line[200];
            std::snprintf(line, sizeof line, "[[group.instance]]\ngroup = \"plant%d\"\nscale = %.3f\nrotate = [0, %.1f, 0]\ntranslate = [%.3f, 0, %.3f]\n",
                          r.pick(0, kKinds - 1), r.uni(0.85, 1.15), r.uni(0, 360), (p % 10) * 0.7 + r.uni(-0.15, 0.15),
                          (p / 10) * 0.7 + r.uni(-0.15, 0.15));
            scene << line;
        }
        scene << "\n";
    }
    const int64_t patches = (plants + perPatch - 1) / perPatch;
    const int cols = int(std::ceil(std::sqrt(double(patches))));
    for (int64_t p = 0; p < patches; ++p) {
        char line[200];
        std::snprintf(line, sizeof line, "[[instance]]\ngroup = \"patch%d\"\nrotate = [0, %d, 0]\ntranslate = [%.2f, 0, %.2f]\n\n",
                      int(p % variants), r.pick(0, 1) * 180, (p % cols) * 7.5, (p / cols) * 5.5);
        scene << line;
    }
    const double fieldX = cols * 7.5, fieldZ = double((patches + cols - 1) / cols) * 5.5;
    scene << "[[mesh]]\nname = \"ground\"\nshape = \"quad\"\n\n[[material]]\nname = \"soil\"\ncolor = [0.3, 0.22, 0.15]\n\n"
          << "[[instance]]\nmesh = \"ground\"\nmaterial = \"soil\"\nscale = [" << fieldX * 0.7 + 40 << ", 1, " << fieldZ * 0.7 + 40
          << "]\ntranslate = [" << fieldX / 2 << ", 0, " << fieldZ / 2 << "]\n\n";
    for (int t = 0; t < trees; ++t) {
        const std::string name = "tree" + std::to_string(t);
        writeVtp(o.out / "meshes" / (name + ".vtp"), makeTree(r, treeTriangles));
        scene << "[[mesh]]\nname = \"" << name << "\"\nfile = \"meshes/" << name << ".vtp\"\n\n[[instance]]\nmesh = \"" << name
              << "\"\nmaterial = \"bark\"\ntranslate = [" << -8.0 - 6 * t << ", 0, " << fieldZ * (t + 0.5) / std::max(1, trees) << "]\n\n";
    }
    scene << "[[light]]\ntype = \"directional\"\ndirection = [-0.3, -1.0, -0.5]\nintensity = 3\n\n"
          << "[[camera]]\nname = \"overview\"\nposition = [" << -0.15 * fieldX << ", " << 0.35 * std::max(fieldX, fieldZ) + 3 << ", " << -0.2 * fieldZ
          << "]\nlook_at = [" << fieldX / 2 << ", 0, " << fieldZ / 2 << "]\nfov = 55\n\n"
          << "[[camera]]\nname = \"ground\"\nposition = [-1.0, 1.7, -1.0]\nlook_at = [3.0, 1.2, 3.0]\nfov = 60\n";
    writeText(o.out / "scene.toml", scene.str());
}

}  // namespace rtwall::gen
