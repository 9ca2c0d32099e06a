#include "tools/run/run_command.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "common/config/config_error.h"
#include "services/camera/frame_source.h"
#include "tools/run/progress_reporter.h"
#include "tools/run/ratslam_config.h"
#include "tools/run/ratslam_runner.h"
#include "tools/run/run_output_writer.h"
#include "tools/run/run_statistics.h"

namespace rslam::run {

namespace {

constexpr int kExitInput = 1;
constexpr int kExitConfig = 2;

// An error with its exit code, caught once at the top of the command.
struct CommandFailure : std::runtime_error {
  CommandFailure(int code, const std::string& reason) : std::runtime_error(reason), exit_code(code) {}
  int exit_code;
};

std::filesystem::path DefaultPresetDir() {
#ifdef RSLAM_RUN_DEFAULT_PRESET_DIR
  return RSLAM_RUN_DEFAULT_PRESET_DIR;
#else
  return "deploy/presets";
#endif
}

ProgressReporter::Style ProgressStyle(RunOptions::Progress progress) {
  switch (progress) {
    case RunOptions::Progress::kBar: return ProgressReporter::Style::kBar;
    case RunOptions::Progress::kLines: return ProgressReporter::Style::kLines;
    case RunOptions::Progress::kQuiet: return ProgressReporter::Style::kQuiet;
    case RunOptions::Progress::kAuto: break;
  }
  return ::isatty(STDERR_FILENO) ? ProgressReporter::Style::kBar : ProgressReporter::Style::kLines;
}

RatSlamConfig LoadConfig(const RunOptions& options) {
  try {
    std::filesystem::path preset_file;
    if (!options.preset.empty()) preset_file = FindPreset(options.preset, DefaultPresetDir());
    return RatSlamConfigFromYaml(ComposeRunYaml(preset_file, options.config_file, options.overrides));
  } catch (const ConfigError& e) {
    throw CommandFailure(kExitConfig, std::string("bad configuration: ") + e.what());
  }
}

std::unique_ptr<camera::FrameSource> OpenSource(const RunOptions& options, double fps) {
  try {
    if (!options.images.empty()) return camera::OpenImageSequence(options.images, fps);
    return camera::OpenVideoFile(options.video);
  } catch (const std::exception& e) {
    throw CommandFailure(kExitInput, e.what());
  }
}

int Run(const RunOptions& options, std::ostream& out, std::ostream& err) {
  const auto wall_start = std::chrono::steady_clock::now();
  if (options.images.empty() == options.video.empty()) {
    throw CommandFailure(kExitConfig, "give exactly one of --images DIR|LIST and --video FILE");
  }
  if (options.out_dir.empty()) throw CommandFailure(kExitConfig, "--out DIR is required");
  if (options.fps && !(*options.fps > 0)) throw CommandFailure(kExitConfig, "--fps must be positive");
  if (options.max_frames < 0) throw CommandFailure(kExitConfig, "--max-frames must be >= 0");

  const RatSlamConfig config = LoadConfig(options);
  const double fps = options.fps.value_or(config.odometry.visual.camera_hz);
  // Video stamps come from the file unless a rate is forced.
  const bool stamps_from_rate = !options.images.empty() || options.fps.has_value();
  std::unique_ptr<camera::FrameSource> source = OpenSource(options, fps);

  int64_t total = source->size();
  if (options.max_frames > 0) total = total < 0 ? options.max_frames : std::min(total, options.max_frames);
  ProgressReporter progress(err, ProgressStyle(options.progress), total);

  RatSlamRunner runner(config);
  RunStatistics statistics;
  const int64_t period_ns = static_cast<int64_t>(1e9 / fps);
  while (options.max_frames == 0 || static_cast<int64_t>(statistics.frames()) < options.max_frames) {
    std::optional<camera::Frame> frame;
    try {
      frame = source->Next();
    } catch (const std::exception& e) {
      throw CommandFailure(kExitInput, e.what());
    }
    if (!frame) break;
    const int64_t stamp_ns = stamps_from_rate ? static_cast<int64_t>(frame->seq) * period_ns : frame->stamp_ns;
    try {
      const FrameRecord record = runner.ProcessFrame(frame->image, stamp_ns);
      statistics.Add(record, static_cast<uint32_t>(runner.templates().size()));
    } catch (const std::invalid_argument& e) {
      std::string reason = "frame " + std::to_string(frame->seq) + " (" + frame->name + "): " + e.what();
      if (!stamps_from_rate) reason += " (the video's timestamps are unusable: give --fps)";
      throw CommandFailure(kExitInput, reason);
    }
    progress.Update(statistics.frames(), runner.templates().size(), runner.experience_map().experiences().size());
  }
  progress.Finish(statistics.frames(), runner.templates().size(), runner.experience_map().experiences().size());
  if (statistics.frames() == 0) throw CommandFailure(kExitInput, source->Describe() + ": no frames");

  const RelaxResult relax = runner.RelaxToConvergence();
  RunDescription description;
  description.preset = options.preset;
  description.config_file = options.config_file;
  description.source = source->Describe();
  description.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const nlohmann::json summary = MakeSummary(runner, statistics, relax, description);
  try {
    WriteRunOutputs(options.out_dir, runner, statistics, summary);
  } catch (const std::exception& e) {
    throw CommandFailure(kExitInput, e.what());
  }
  if (options.progress != RunOptions::Progress::kQuiet) {
    char line[256];
    std::snprintf(line, sizeof line,
                  "%llu frames, %zu templates, %zu experiences, %zu links, %llu loop closures; core %.0f frames/s",
                  static_cast<unsigned long long>(statistics.frames()), runner.templates().size(),
                  runner.experience_map().experiences().size(), runner.experience_map().links().size(),
                  static_cast<unsigned long long>(runner.loop_closures()), statistics.CoreFramesPerSecond());
    out << line << "\n";
    if (runner.odometry_restarts() > 0) {
      out << "note: the odometry restarted on " << runner.odometry_restarts()
          << " frames (frame gap beyond odometry.max_frame_gap_s = " << config.odometry.max_frame_gap_s
          << " s, or an image size change); those frames carry no motion, as in the services\n";
    }
    out << "wrote " << options.out_dir << "/{summary.json,experiences.csv,templates.csv,"
        << "experience_map.png,templates.png}\n";
  }
  return 0;
}

}  // namespace

int RunRatSlamCommand(const RunOptions& options, std::ostream& out, std::ostream& err) {
  try {
    return Run(options, out, err);
  } catch (const CommandFailure& e) {
    err << "rslam run: " << e.what() << "\n";
    return e.exit_code;
  } catch (const ConfigError& e) {
    err << "rslam run: bad configuration: " << e.what() << "\n";
    return kExitConfig;
  } catch (const std::exception& e) {
    err << "rslam run: " << e.what() << "\n";
    return kExitInput;
  }
}

void RegisterRunCommand(CLI::App& rslam, std::ostream& out, std::ostream& err) {
  auto options = std::make_shared<RunOptions>();
  auto quiet = std::make_shared<bool>(false);
  auto fps = std::make_shared<double>(0.0);
  CLI::App* run =
      rslam.add_subcommand("run",
                           "Run the RatSLAM core (odometry, templates, pose cells, experience map) in one process on "
                           "recorded frames; writes summary.json, experiences.csv, templates.csv and pictures");
  auto* images =
      run->add_option("--images", options->images, "Image folder (name order) or list file, one path a line");
  auto* video = run->add_option("--video", options->video, "Video file (stamps from the file unless --fps)");
  images->excludes(video);
  run->add_option("--preset", options->preset,
                  "Preset name: deploy/presets/<P>.yaml (stlucia, irat, oxford, nordland)");
  run->add_option("--config", options->config_file,
                  "YAML file with sections odometry, templates, pose_cells, "
                  "experience_map (over the preset)");
  run->add_option("--set", options->overrides, "Override section.key=value (repeatable)");
  auto* fps_option = run->add_option("--fps", *fps, "Frame rate for the stamps (default: odometry.camera_hz)");
  run->add_option("--out", options->out_dir, "Output folder")->required();
  run->add_option("--max-frames", options->max_frames, "Stop after N frames (0 = all)")->capture_default_str();
  run->add_flag("--quiet", *quiet, "No progress and no result lines");
  run->callback([options, quiet, fps, fps_option, &out, &err] {
    if (fps_option->count() > 0) options->fps = *fps;
    if (*quiet) options->progress = RunOptions::Progress::kQuiet;
    const int code = RunRatSlamCommand(*options, out, err);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

void RegisterRunCommand(CLI::App& rslam) { RegisterRunCommand(rslam, std::cout, std::cerr); }

}  // namespace rslam::run
