#pragma once
// Files for the eval tests (written into the test's ScratchFolderForTest, tests/support), and the
// eval command run in the test's process.

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tools/eval/eval_command.h"

namespace rslam::eval::testing {

inline void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

// Runs `rslam <args>` with only the eval command; returns what it printed.
inline std::string RunRslam(std::vector<std::string> args) {
  std::ostringstream out, err;
  CLI::App app{"rslam"};
  RegisterEvalCommand(app, out, err);
  std::reverse(args.begin(), args.end());  // CLI11 takes the arguments last-first
  app.parse(args);
  return out.str();
}

}  // namespace rslam::eval::testing
