#include "commands.h"

#include <rtwall/engine.h>

#include <toml++/toml.h>

#include <iostream>
#include <memory>

namespace rtwall::cli {

namespace {

toml::array boundsArray(const Bounds3& b) {
    return toml::array{toml::array{double(b.lo.x), double(b.lo.y), double(b.lo.z)},
                       toml::array{double(b.hi.x), double(b.hi.y), double(b.hi.z)}};
}

toml::table meshInfo(const std::filesystem::path& path) {
    ImportReport report;
    const TriangleMesh mesh = loadMesh(path, &report);
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
                       {"resident_bytes", int64_t(mesh.residentBytes())}};
}

toml::table sceneInfo(const std::string& scene) {
    const SceneDesc desc = loadScene(scene);
    int64_t unique = 0, instanced = 0;
    for (const MeshDesc& m : desc.meshes) unique += int64_t(m.mesh->triangleCount());
    for (const InstanceDesc& in : desc.instances) instanced += int64_t(desc.meshes[in.mesh].mesh->triangleCount());
    toml::array cameras;
    for (const CameraDesc& c : desc.cameras) cameras.push_back(c.name);
    return toml::table{{"file", scene},
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

}  // namespace

void addInfo(CLI::App& app, Run& run) {
    struct Options {
        std::string file;
        bool json = false;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("info", "Print what a mesh file or scene file holds");
    cmd->add_option("file", o->file, "Mesh file (.obj .off .ply .stl .om .vtk .vtp .vtu .wrl), scene file (.toml) or builtin:NAME")
        ->required();
    cmd->add_flag("--json", o->json, "Print JSON instead of TOML-style text");
    cmd->callback([&run, o] {
        run = [o] {
            const toml::table info =
                sceneSourceKind(o->file) == SceneSourceKind::MeshFile ? meshInfo(o->file) : sceneInfo(o->file);
            if (o->json) std::cout << toml::json_formatter{info} << "\n";
            else std::cout << info << "\n";
            return 0;
        };
    });
}

}  // namespace rtwall::cli
