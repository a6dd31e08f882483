// Whole files as bytes, for tests that compare what two runs wrote.
#pragma once

#include <filesystem>
#include <string>

namespace rtwall::test {

// The file's bytes (empty when it cannot be read: a comparison with a written file then fails).
std::string fileBytes(const std::filesystem::path& path);

}  // namespace rtwall::test
