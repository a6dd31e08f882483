#include "commands.h"

#include <rtwall/engine.h>

#include <progress.h>

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rtwall::cli {

namespace {

toml::array boundsArray(const Bounds3& b) {
    return toml::array{toml::array{double(b.lo.x), double(b.lo.y), double(b.lo.z)},
                       toml::array{double(b.hi.x), double(b.hi.y), double(b.hi.z)}};
}

toml::table meshInfo(const std::filesystem::path& path, bool shareCongruent) {
    ImportReport report;
    const auto loaded = std::make_shared<const TriangleMesh>(loadMesh(path, &report));
    const TriangleMesh& mesh = *loaded;
    // Repeated bodies, as `rtwall render FILE` stores them (shareCongruentBodies).
    int64_t sharedMeshes = 1, sharedInstances = 1, sharedTriangles = int64_t(mesh.triangleCount()), congruent = 0;
    if (shareCongruent) {
        const Assembly a = shareCongruentBodies(loaded, path.stem().string());
        sharedMeshes = int64_t(a.meshes.size());
        sharedInstances = int64_t(a.instances.size());
        sharedTriangles = 0;
        for (const auto& m : a.meshes) sharedTriangles += int64_t(m->triangleCount());
        congruent = int64_t(a.congruentMeshes);
    }
    return toml::table{{"file", path.string()},
                       {"format", report.format},
                       {"triangles", int64_t(mesh.triangleCount())},
                       {"vertices", int64_t(mesh.vertexCount())},
                       {"bounds", boundsArray(mesh.bounds())},
                       {"normals", mesh.hasNormals()},
                       {"colors", mesh.hasColors()},
                       {"uvs", mesh.hasUVs()},
                       {"polygons_triangulated", int64_t(report.polygonsTriangulated)},
                       // how: convex ones fanned, the rest ear-clipped; those with no area, or whose
                       // boundary crosses itself, fanned (in part) and counted apart
                       {"polygons_fanned", int64_t(report.polygonsFanned)},
                       {"polygons_ear_clipped", int64_t(report.polygonsEarClipped)},
                       {"polygons_degenerate", int64_t(report.polygonsDegenerate)},
                       {"polygons_self_intersecting", int64_t(report.polygonsSelfIntersecting)},
                       {"degenerate_triangles", int64_t(report.degenerateTriangles)},
                       {"strips_triangulated", int64_t(report.stripsTriangulated)},
                       {"cells_skipped", int64_t(report.cellsSkipped)},
                       // bounds are relative to origin (CAD files far from their origin are recentred)
                       {"origin", toml::array{mesh.origin()[0], mesh.origin()[1], mesh.origin()[2]}},
                       {"resident_bytes", int64_t(mesh.residentBytes())},
                       // bodies found congruent to another and stored once; the meshes, instances
                       // and unique triangles of the scene the file becomes (1, 1, triangles: none)
                       {"congruent_bodies", congruent},
                       {"scene_meshes", sharedMeshes},
                       {"scene_instances", sharedInstances},
                       {"scene_unique_triangles", sharedTriangles}};
}

// A scene (file or builtin): the counts; for a scene file that brings in assemblies, their part
// tree in `tree`, each part with the instances it places and how many of them [parts] hides or
// highlights (the names `--hide` and the wall's keys go by).
toml::table sceneInfo(const std::string& scene, std::string* tree) {
    const SceneDesc desc = loadScene(scene);
    if (tree && !desc.parts.empty()) {
        std::vector<size_t> placed(desc.parts.size()), hiddenIn(desc.parts.size()), highlightedIn(desc.parts.size());
        for (const InstanceDesc& in : desc.instances)
            if (in.part >= 0 && size_t(in.part) < desc.parts.size()) {
                ++placed[size_t(in.part)];
                hiddenIn[size_t(in.part)] += in.visibility == Visibility::Hidden;
                highlightedIn[size_t(in.part)] += in.visibility == Visibility::Highlighted;
            }
        std::vector<int> depth(desc.parts.size(), 0);
        for (size_t i = 0; i < desc.parts.size(); ++i) {
            const PartDesc& p = desc.parts[i];
            depth[i] = p.parent >= 0 && size_t(p.parent) < i ? depth[size_t(p.parent)] + 1 : 0;
            *tree += std::string(2 * size_t(depth[i]), ' ') + p.name;
            if (placed[i] > 0) {
                *tree += "  [" + std::to_string(placed[i]) + (placed[i] == 1 ? " instance" : " instances");
                if (hiddenIn[i]) *tree += ", " + std::to_string(hiddenIn[i]) + " hidden";
                if (highlightedIn[i]) *tree += ", " + std::to_string(highlightedIn[i]) + " highlighted";
                *tree += "]";
            }
            *tree += "\n";
        }
    }
    int64_t unique = 0, instanced = 0;
    for (const MeshDesc& m : desc.meshes) unique += int64_t(m.mesh->triangleCount());
    for (const InstanceDesc& in : desc.instances) instanced += int64_t(desc.meshes[in.mesh].mesh->triangleCount());
    toml::array cameras;
    for (const CameraDesc& c : desc.cameras) cameras.push_back(c.name);
    int64_t hidden = 0, highlighted = 0;  // [parts]
    for (const InstanceDesc& in : desc.instances) {
        hidden += in.visibility == Visibility::Hidden;
        highlighted += in.visibility == Visibility::Highlighted;
    }
    // Section planes in use (slot order), their points in the file's coordinates.
    toml::array sections;
    for (size_t i = 0; i < desc.sections.size(); ++i) {
        const SectionPlane& p = desc.sections[i];
        if (!p.enabled && p == SectionPlane{}) continue;
        sections.push_back(toml::table{
            {"slot", int64_t(i)},
            {"enabled", p.enabled},
            {"point", toml::array{desc.origin[0] + p.point.x, desc.origin[1] + p.point.y, desc.origin[2] + p.point.z}},
            {"normal", toml::array{p.normal.x, p.normal.y, p.normal.z}},
            {"cap_color", toml::array{p.capColor.x, p.capColor.y, p.capColor.z}},
            {"caps", p.caps}});
    }
    return toml::table{{"file", scene},
                       {"sections", sections},
                       {"parts", int64_t(desc.parts.size())},
                       {"instances_hidden", hidden},
                       {"instances_highlighted", highlighted},
                       {"meshes", int64_t(desc.meshes.size())},
                       {"instances", int64_t(desc.instances.size())},
                       {"materials", int64_t(desc.materials.size())},
                       {"lights", int64_t(desc.lights.size())},
                       {"cameras", cameras},
                       {"triangles", unique},
                       {"instanced_triangles", instanced},
                       {"bounds", boundsArray(desc.worldBounds())},
                       {"origin", toml::array{desc.origin[0], desc.origin[1], desc.origin[2]}}};
}

// An assembly (glTF, STEP, IGES): the counts, and the part tree, one entry per node with its
// path, its parent and the instances it places.
toml::table assemblyInfo(const std::filesystem::path& path, const AssemblyOptions& options, std::string* tree) {
    const auto t0 = std::chrono::steady_clock::now();
    const Assembly a = loadAssembly(path, options);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    int64_t unique = 0, instanced = 0;
    for (const auto& m : a.meshes) unique += int64_t(m->triangleCount());
    std::vector<std::vector<uint32_t>> placed(a.parts.size());
    // World bounds: each instance's mesh bounds, its 8 corners through its transform (which
    // includes the mesh's origin), in double.
    std::array<double, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (const AssemblyInstance& in : a.instances) {
        instanced += int64_t(a.meshes[in.mesh]->triangleCount());
        placed[in.part].push_back(in.mesh);
        const Bounds3 b = a.meshes[in.mesh]->bounds();
        if (b.empty()) continue;
        const auto& t = in.transform;
        for (int corner = 0; corner < 8; ++corner) {
            const double p[3] = {corner & 1 ? b.hi.x : b.lo.x, corner & 2 ? b.hi.y : b.lo.y, corner & 4 ? b.hi.z : b.lo.z};
            for (size_t r = 0; r < 3; ++r) {
                const double w = t[r * 4] * p[0] + t[r * 4 + 1] * p[1] + t[r * 4 + 2] * p[2] + t[r * 4 + 3];
                lo[r] = std::min(lo[r], w);
                hi[r] = std::max(hi[r], w);
            }
        }
    }
    std::vector<std::string> paths(a.parts.size());
    std::vector<int> depth(a.parts.size(), 0);
    toml::array parts;
    for (size_t i = 0; i < a.parts.size(); ++i) {
        const AssemblyPart& p = a.parts[i];
        paths[i] = p.parent >= 0 ? paths[size_t(p.parent)] + "/" + p.name : p.name;
        depth[i] = p.parent >= 0 ? depth[size_t(p.parent)] + 1 : 0;
        toml::array meshes;
        for (uint32_t m : placed[i]) meshes.push_back(a.meshNames[m]);
        parts.push_back(toml::table{{"name", p.name},
                                    {"path", paths[i]},
                                    {"parent", int64_t(p.parent)},
                                    {"meshes", meshes},
                                    {"instances", int64_t(placed[i].size())}});
        if (tree) {
            *tree += std::string(2 * size_t(depth[i]), ' ') + p.name;
            if (!placed[i].empty()) {
                *tree += "  [";
                for (size_t k = 0; k < placed[i].size(); ++k) *tree += (k ? ", " : "") + a.meshNames[placed[i][k]];
                *tree += "]";
            }
            *tree += "\n";
        }
    }
    toml::array materials;
    for (const AssemblyMaterial& m : a.materials) materials.push_back(m.name);
    size_t bytes = 0, mapped = 0;
    for (const auto& m : a.meshes) {
        bytes += m->residentBytes();
        mapped += m->mappedBytes();
    }
    return toml::table{{"file", path.string()},
                       {"format", a.format},
                       {"load_seconds", seconds},
                       {"cache", a.cache.empty() ? std::string("off") : a.cache},
                       // STEP/IGES imported: "direct" (rtwall's own structure reader), "xde" or
                       // "xde: <why not direct>"; empty from a cache or for other formats
                       {"reader", a.reader},
                       {"mesh_bytes", int64_t(bytes)},  // unique meshes' buffers, mapped cache pages included
                       {"mesh_bytes_mapped", int64_t(mapped)},
                       {"meshes", int64_t(a.meshes.size())},
                       {"congruent_meshes", int64_t(a.congruentMeshes)},  // found congruent to another, stored once
                       {"instances", int64_t(a.instances.size())},
                       {"materials", materials},
                       {"triangles", unique},
                       {"instanced_triangles", instanced},
                       // what the lean storage costs: the unique meshes' bytes per unique
                       // triangle, and an instance's record (transform, mesh, material, part)
                       {"bytes_per_unique_triangle", unique > 0 ? double(bytes) / double(unique) : 0.0},
                       {"bytes_per_instance", int64_t(sizeof(AssemblyInstance))},
                       {"bounds", a.instances.empty() || lo[0] > hi[0]
                                      ? toml::array{}
                                      : toml::array{toml::array{lo[0], lo[1], lo[2]}, toml::array{hi[0], hi[1], hi[2]}}},
                       {"parts", parts}};
}

}  // namespace

void addInfo(CLI::App& app, Run& run) {
    struct Options {
        std::string file;
        bool json = false, cache = false, noCongruence = false, stepXde = false;
        double deflection = 0.1, angularDeflection = 0.5;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("info", "Print what a mesh file or scene file holds");
    cmd->add_option("file", o->file, "Mesh file (.obj .off .ply .stl .om .vtk .vtp .vtu .wrl), assembly (.gltf .glb .step .stp .iges .igs), scene file (.toml) or builtin:NAME")
        ->required();
    cmd->add_flag("--json", o->json, "Print JSON instead of TOML-style text");
    cmd->add_option("--deflection", o->deflection, "STEP/IGES: tessellation tolerance in file units (0.1)")->check(CLI::Range(1e-6, 1e6));
    cmd->add_option("--angular-deflection", o->angularDeflection, "STEP/IGES: angular tolerance, radians (0.5)")
        ->check(CLI::Range(1e-3, 3.14));
    cmd->add_flag("--cache", o->cache, "STEP/IGES: use FILE.rtwasm when it matches, else write it");
    cmd->add_flag("--no-congruence", o->noCongruence,
                  "Assemblies and mesh files: keep every mesh (every body) the file has (no congruent-shape detection)");
    cmd->add_flag("--step-xde", o->stepXde,
                  "STEP: read the product structure through OCCT's XDE document, not rtwall's direct reader (the same "
                  "assembly; XDE's time grows as the square of the part instances)");
    cmd->callback([&run, o] {
        run = [o] {
            if (isAssemblyFile(o->file)) {
                // The text form lists the tree indented, one part a line, instead of the parts table.
                std::string tree;
                AssemblyOptions ao;
                ao.linearDeflection = o->deflection;
                ao.angularDeflection = o->angularDeflection;
                ao.cache = o->cache;
                ao.shareCongruent = !o->noCongruence;
                ao.stepThroughXde = o->stepXde;
                // A progress bar on a terminal; Ctrl-C stops the import.
                bench::installInterruptHandler();
                std::optional<bench::ProgressBar> bar;
                ao.progress = bar.emplace("importing", 1, "").fn();
                toml::table info = assemblyInfo(o->file, ao, o->json ? nullptr : &tree);
                if (o->json) {
                    std::cout << toml::json_formatter{info} << "\n";
                } else {
                    info.erase("parts");
                    std::cout << info << "\n\n# assembly tree (part  [meshes it places])\n" << tree;
                }
                return 0;
            }
            std::string tree;
            const toml::table info = sceneSourceKind(o->file) == SceneSourceKind::MeshFile
                                         ? meshInfo(o->file, !o->noCongruence)
                                         : sceneInfo(o->file, o->json ? nullptr : &tree);
            if (o->json) std::cout << toml::json_formatter{info} << "\n";
            else std::cout << info << "\n" << (tree.empty() ? "" : "\n# part tree of its assemblies (part  [instances])\n" + tree);
            return 0;
        };
    });
}

}  // namespace rtwall::cli
