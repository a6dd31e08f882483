#include "scene_files.h"

#include <rtwall/mesh.h>

#include <fstream>
#include <iterator>

namespace rtwall {

namespace {
thread_local const SceneFiles* tCurrent = nullptr;
}

ScopedSceneFiles::ScopedSceneFiles(const SceneFiles* files) : previous_(tCurrent) { tCurrent = files; }
ScopedSceneFiles::~ScopedSceneFiles() { tCurrent = previous_; }

std::shared_ptr<const std::vector<uint8_t>> readSceneFile(const std::string& path, const char* what) {
    if (tCurrent) {
        auto it = tCurrent->find(path);
        if (it != tCurrent->end() && it->second) return it->second;
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open the " + what);
    return std::make_shared<const std::vector<uint8_t>>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace rtwall
