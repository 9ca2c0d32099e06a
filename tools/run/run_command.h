#pragma once
// `rslam run`: the RatSLAM core (odometry, templates, pose cells, experience map) in one process
// on recorded frames, the same calls the distributed services make (ratslam_runner.h).
//
//   rslam run --images DIR|LIST | --video FILE [--preset P] [--config FILE] [--set k=v ...]
//             [--fps F] --out DIR [--max-frames N] [--quiet]
//
// Config: the preset (deploy/presets/<P>.yaml; $RSLAM_PRESET_DIR first), then --config over it,
// then each --set section.key=value. Frame stamps: image folders and lists at --fps (default:
// odometry.camera_hz, the rate the preset was tuned at); videos from the file's timestamps, or
// at --fps when given. Writes summary.json, experiences.csv, templates.csv, experience_map.png,
// templates.png to DIR (run_output_writer.h) after relaxing the map to convergence.
//
// Exit codes: 0 done; 1 bad input (missing folder, no images, unreadable image, unwritable
// output); 2 bad configuration or command line (unknown preset, section or key, bad value).
// The reason is printed to err first (CLI11 prints nothing for a RuntimeError).

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace rslam::run {

struct RunOptions {
  std::string images;  // folder or list file
  std::string video;
  std::string preset;
  std::string config_file;
  std::vector<std::string> overrides;  // section.key=value
  std::optional<double> fps;
  std::string out_dir;
  int64_t max_frames = 0;  // 0 = all
  enum class Progress { kAuto, kBar, kLines, kQuiet } progress = Progress::kAuto;
};

// Runs the whole command; returns the exit code. Results go to out, progress and errors to err.
int RunRatSlamCommand(const RunOptions& options, std::ostream& out, std::ostream& err);

// Adds `run` to the rslam app; results go to out, progress and failures to err (both must
// outlive the app). A failure throws CLI::RuntimeError with the exit code above.
void RegisterRunCommand(CLI::App& rslam, std::ostream& out, std::ostream& err);
// std::cout / std::cerr.
void RegisterRunCommand(CLI::App& rslam);

}  // namespace rslam::run
