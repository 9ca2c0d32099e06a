#pragma once
// Files for the eval tests (written into the test's ScratchFolderForTest, tests/support).

#include <filesystem>
#include <fstream>
#include <string>

namespace rslam::eval::testing {

inline void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

}  // namespace rslam::eval::testing
