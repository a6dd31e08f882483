#include "files.h"

#include <fstream>
#include <sstream>

namespace rtwall::test {

std::string fileBytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace rtwall::test
