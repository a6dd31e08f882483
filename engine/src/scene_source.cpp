// Scenes by name: the one place that decides what a scene name given to rtwall means.
#include <rtwall/engine.h>

#include <algorithm>
#include <cctype>

namespace rtwall {

SceneSourceKind sceneSourceKind(const std::string& nameOrPath) {
    if (nameOrPath.starts_with("builtin:")) return SceneSourceKind::Builtin;
    std::string ext = std::filesystem::path(nameOrPath).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".toml" ? SceneSourceKind::SceneFile : SceneSourceKind::MeshFile;
}

SceneDesc loadScene(const std::string& nameOrPath, const SceneLoadOptions& options) {
    switch (sceneSourceKind(nameOrPath)) {
    case SceneSourceKind::Builtin: return builtinScene(nameOrPath.substr(8), options.builtinTriangles);
    case SceneSourceKind::SceneFile: return loadSceneFile(nameOrPath, options);
    case SceneSourceKind::MeshFile: break;
    }
    return sceneFromMeshFile(nameOrPath, options);
}

}  // namespace rtwall
