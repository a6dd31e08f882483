// In-memory file contents for the texture images and volumes a scene's materials name
// (SceneDesc::files). Material models open their files through readSceneFile(), which looks in
// the files of the scene being built before the disk: a render client gets the bytes from the
// master by content hash and needs no copy of the files.
//
// The files reach the material constructors as a scoped, per-thread context set by Scene while
// it builds models (ScopedSceneFiles), so that no material class has to pass them along.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace rtwall {

using SceneFiles = std::map<std::string, std::shared_ptr<const std::vector<uint8_t>>>;

// Makes `files` the current thread's scene files until destroyed (nesting restores the outer).
class ScopedSceneFiles {
public:
    explicit ScopedSceneFiles(const SceneFiles* files);
    ~ScopedSceneFiles();
    ScopedSceneFiles(const ScopedSceneFiles&) = delete;
    ScopedSceneFiles& operator=(const ScopedSceneFiles&) = delete;

private:
    const SceneFiles* previous_;
};

// The bytes of `path`: from the current scene files when they hold it, else read from disk.
// Throws InputError "path: cannot open the WHAT" when neither has it.
std::shared_ptr<const std::vector<uint8_t>> readSceneFile(const std::string& path, const char* what);

}  // namespace rtwall
