// Inside the scene-file loader: what its parts share. scene_file.cpp reads the settings, the
// materials, lights, section planes, cameras and [parts], and rebases; scene_file_geometry.cpp
// reads [[mesh]], [[group]] and [[instance]]; scene_from_mesh.cpp makes scenes of one mesh or
// assembly file and holds the framing and rebasing both kinds of scene use.
#pragma once

#include <rtwall/engine.h>
#include <rtwall/toml_reader.h>

#include <array>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

namespace rtwall::scene_file {

// [import]: the STEP/IGES tessellation every [[mesh]] of such a file gets unless it says otherwise.
struct ImportSettings {
    double linearDeflection = 0.1;
    double angularDeflection = 0.5;
    bool shareCongruent = true;  // AssemblyOptions::shareCongruent
    double congruenceTolerance = 1e-5;
};

// An assembly file (glTF, STEP, IGES) named by a [[mesh]]: its meshes, materials and parts joined
// the scene once per file and tolerance; each [[instance]] of the entry places all of its
// instances, its own transform applied on top.
struct PlacedAssembly {
    uint32_t firstMesh = 0, firstMaterial = 0;
    int32_t firstPart = 0;
    std::vector<AssemblyInstance> instances;
};

// One scene file being loaded.
struct Load {
    Load(const std::filesystem::path& f, const SceneLoadOptions& o)
        : file(f), dir(f.parent_path()), options(o), stats(o.stats ? *o.stats : localStats) {}
    Load(const Load&) = delete;
    Load& operator=(const Load&) = delete;

    const std::filesystem::path& file;
    const std::filesystem::path dir;
    const SceneLoadOptions& options;
    SceneDesc scene;
    LoadOptions meshOptions;
    SceneLoadStats localStats;
    SceneLoadStats& stats;
    ImportSettings import;
    // Progress is counted in bytes of mesh files, which a first pass sums.
    double bytesTotal = 0, bytesDone = 0;

    std::map<std::string, uint32_t> meshIndex, materialIndex;
    std::map<std::filesystem::path, std::shared_ptr<const TriangleMesh>> loadedFiles;  // one copy per file
    std::vector<PlacedAssembly> assemblies;
    std::map<std::string, uint32_t> assemblyIndex;  // [[mesh]] name -> assemblies
    std::map<std::tuple<std::filesystem::path, double, double>, uint32_t> loadedAssemblies;
};

void readDeflections(toml_reader::Reader& r, ImportSettings& s);
// What one import took (its cache outcome, "hit", "written", "rebuilt ..." or "", and seconds)
// into the statistics.
void countImport(SceneLoadStats& stats, const std::string& cache, double seconds);

// [[mesh]] entries: files (read once each), assembly files and shapes.
void readMeshes(toml_reader::Reader& top, Load& load);
// [[group]] and [[instance]], flattened into the scene's instances.
void readInstances(toml_reader::Reader& top, Load& load);

// The centre of the instances' world bounds, rounded to a whole number, when the scene lies
// further from the origin than its own size (and at least 1024 units); else the origin.
std::array<double, 3> rebaseOrigin(const SceneDesc& scene);
// A camera that frames the bounds.
CameraDesc framingCamera(const Bounds3& bounds);

}  // namespace rtwall::scene_file
