// loadAssembly: the assembly formats by extension.
#include "rtwall/mesh.h"

#include "assembly_import.h"
#include "mesh_internal.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <optional>

namespace rtwall {
namespace {

std::string lowerExtension(const std::filesystem::path& file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

Assembly shareCongruent(Assembly a, const AssemblyOptions& options) {
    if (options.shareCongruent) a.congruentMeshes = detail::shareCongruentMeshes(a, options.congruenceTolerance);
    return a;
}

}  // namespace

bool isAssemblyFile(const std::filesystem::path& file) {
    const std::string ext = lowerExtension(file);
    return ext == ".gltf" || ext == ".glb" || ext == ".step" || ext == ".stp" || ext == ".iges" || ext == ".igs";
}

Assembly loadAssembly(const std::filesystem::path& file, const AssemblyOptions& options) {
    if (!isAssemblyFile(file)) throw InputError(file.string() + ": not an assembly file (.gltf, .glb, .step, .stp, .iges, .igs)");
    const std::string ext = lowerExtension(file);
    Assembly a;
    if (ext == ".gltf" || ext == ".glb") {
        a = detail::importGltf(file);
    } else if (!options.cache) {
        a = detail::importCad(file, options, {}, nullptr).assembly;
    } else {
        // Tessellation is the slow part: the cache is keyed by the file's content and the deflections.
        detail::AssemblyKey key;
        key.hash = detail::hashFileContent(file, key.size);
        key.linearDeflection = options.linearDeflection;
        key.angularDeflection = options.angularDeflection;
        const std::filesystem::path cacheFile = detail::assemblyCachePath(file, options.cacheDir);
        std::string why;
        if (std::optional<Assembly> cached = detail::readAssemblyCache(cacheFile, key, &why)) {
            cached->cache = "hit";
            return shareCongruent(std::move(*cached), options);
        }
        std::string dirError;
        try {
            if (!options.cacheDir.empty()) std::filesystem::create_directories(options.cacheDir);
        } catch (const std::exception& e) {
            dirError = e.what();
        }
        detail::CadImport imported = detail::importCad(file, options, key, dirError.empty() ? &cacheFile : nullptr);
        a = std::move(imported.assembly);
        // A read-only folder must not stop the model from loading.
        if (!dirError.empty()) a.cache = "not written: " + dirError;
        else if (!imported.cacheError.empty()) a.cache = "not written: " + imported.cacheError;
        else a.cache = why == "no cache" ? "written" : "rebuilt: " + why;
    }
    for (const std::string& w : a.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    return shareCongruent(std::move(a), options);
}

}  // namespace rtwall
