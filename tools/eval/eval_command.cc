#include "tools/eval/eval_command.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <utility>
#include <string>
#include <vector>

#include "common/config/config_error.h"
#include "common/config/config_loader.h"
#include "common/bus/typed_cdr.h"
#include "common/mcap/mcap_reader.h"
#include "tools/eval/image_folder.h"
#include "tools/eval/odometry_replay.h"
#include "tools/eval/patch_normalised_sad.h"
#include "tools/eval/template_difference_matrix.h"
#include "tools/eval/trajectory_csv.h"
#include "tools/eval/vpr_evaluation.h"
#include "tools/sim/sim_node.h"

namespace rslam::eval {

namespace {

constexpr int kAutoContrastWindow = -1;
// SeqSLAM's local contrast enhancement helps only sequence matching (on the Nordland dev set it
// lowers single-frame recall@1 from 0.117 to 0.03 and lifts L=10 from 0.04 to 0.84).
constexpr int kSequenceContrastWindow = 10;

struct VprCommandOptions {
  std::string reference_dir;
  std::string query_dir;
  int tolerance = 2;
  int sequence_length = 1;
  int contrast_window = kAutoContrastWindow;
  std::string preset;
  std::string config_file;
  std::string matcher = "template";
  std::size_t limit = 0;
  bool json = false;
};

struct TrajectoryCommandOptions {
  std::string estimate_file;
  std::string truth_file;
  bool no_scale = false;
  double max_stamp_gap_ms = 10.0;
  bool json = false;
};

struct OdometryCommandOptions {
  std::string recording;
  std::string config_file = RSLAM_EVAL_DEFAULT_DEMO_CONFIG;
  std::vector<std::string> overrides;
  std::string robot;
  bool json = false;
};

// CLI11 exits silently on RuntimeError, so the reason is printed here first.
[[noreturn]] void Fail(std::ostream& err, const std::string& command, const std::string& reason) {
  const std::string message = "rslam eval " + command + ": " + reason;
  err << message << "\n";
  throw CLI::RuntimeError(message, 1);
}

// A preset name -> its file: $RSLAM_PRESET_DIR, ./deploy/presets, then the source tree's.
std::filesystem::path FindPreset(const std::string& name, std::ostream& err) {
  std::vector<std::filesystem::path> folders;
  if (const char* env = std::getenv("RSLAM_PRESET_DIR")) folders.emplace_back(env);
  folders.emplace_back("deploy/presets");
#ifdef RSLAM_EVAL_DEFAULT_PRESET_DIR
  folders.emplace_back(RSLAM_EVAL_DEFAULT_PRESET_DIR);
#endif
  std::string tried;
  for (const auto& folder : folders) {
    const std::filesystem::path candidate = folder / (name + ".yaml");
    if (std::filesystem::is_regular_file(candidate)) return candidate;
    tried += (tried.empty() ? "" : ", ") + candidate.string();
  }
  Fail(err, "vpr", "no preset '" + name + "' (looked for " + tried + ")");
}

void RunVpr(const VprCommandOptions& options, std::ostream& out, std::ostream& err) {
  std::string preset_source;
  try {
    YAML::Node preset;
    if (!options.preset.empty()) preset_source = FindPreset(options.preset, err).string();
    if (!options.config_file.empty()) preset_source = options.config_file;
    if (!preset_source.empty()) preset = LoadYamlFile(preset_source);

    const FrameAlignedSets sets = LoadFrameAlignedSets(options.reference_dir, options.query_dir, options.limit);
    const bool baseline = options.matcher == "baseline";
    const DifferenceMatrix differences =
        baseline ? BaselinePatchSad(sets.references.images, sets.queries.images)
                 : BuildTemplateDifferences(sets.references.images, sets.queries.images, preset);

    VprEvaluationOptions evaluation;
    evaluation.tolerance = options.tolerance;
    evaluation.sequence.length = options.sequence_length;
    evaluation.sequence.contrast_window = options.contrast_window != kAutoContrastWindow ? options.contrast_window
                                          : options.sequence_length > 1                  ? kSequenceContrastWindow
                                                                                         : 0;
    const VprResult result = EvaluateFrameAligned(differences, evaluation);
    const std::string matcher = baseline ? std::string("baseline_patch_sad") : PlaceMatcherName();

    if (options.json) {
      nlohmann::json json = {
          {"recall_at_1", result.recall_at_1},
          {"recall_at_100_precision", result.recall_at_100_precision},
          {"recall_at_100_precision_by_difference", result.recall_at_100_precision_by_difference},
          {"queries", result.queries},
          {"references", result.references},
          {"mode", options.sequence_length > 1 ? "sequence" : "single"},
          {"sequence", options.sequence_length},
          {"contrast_window", evaluation.sequence.contrast_window},
          {"tolerance", options.tolerance},
          {"matcher", matcher},
          {"preset", preset_source},
      };
      out << json.dump() << "\n";
    } else {
      char line[256];
      std::snprintf(line, sizeof line,
                    "recall@1 %.3f  recall@100%%P %.3f  (%d queries, %d references, %s, L=%d, tolerance %d, %s)",
                    result.recall_at_1, result.recall_at_100_precision, result.queries, result.references,
                    options.sequence_length > 1 ? "sequence" : "single frame", options.sequence_length,
                    options.tolerance, matcher.c_str());
      out << line << "\n";
    }
  } catch (const CLI::Error&) {
    throw;
  } catch (const ConfigError& e) {
    Fail(err, "vpr", "bad config " + preset_source + ": " + e.what());
  } catch (const std::exception& e) {
    Fail(err, "vpr", e.what());
  }
}

void RunTrajectory(const TrajectoryCommandOptions& options, std::ostream& out, std::ostream& err) {
  try {
    const std::vector<StampedPose2D> estimate = ReadTrajectoryCsvFile(options.estimate_file);
    const std::vector<StampedPose2D> truth = ReadTrajectoryCsvFile(options.truth_file);
    const auto gap = std::chrono::duration_cast<Duration>(std::chrono::duration<double, std::milli>(options.max_stamp_gap_ms));
    const TrajectoryError error = AlignAndCompare(estimate, truth, !options.no_scale, gap);
    if (options.json) {
      nlohmann::json json = {
          {"ate_m", error.ate_m},
          {"pairs", error.pairs},
          {"scale", error.scale},
          {"with_scale", !options.no_scale},
          {"mean_error_m", error.mean_error_m},
          {"max_error_m", error.max_error_m},
          {"unmatched", error.unmatched},
          {"rotation_rad", error.rotation_rad},
          {"translation_m", {error.translation_x, error.translation_y}},
      };
      if (error.heading_rms_rad) json["heading_rms_rad"] = *error.heading_rms_rad;
      out << json.dump() << "\n";
    } else {
      char line[256];
      std::snprintf(line, sizeof line, "ATE %.4f m RMS over %zu pairs (scale %.4f%s, max %.4f m, %zu unmatched)",
                    error.ate_m, error.pairs, error.scale, options.no_scale ? " fixed" : "", error.max_error_m,
                    error.unmatched);
      out << line;
      if (error.heading_rms_rad) out << ", heading RMS " << *error.heading_rms_rad << " rad";
      out << "\n";
    }
  } catch (const CLI::Error&) {
    throw;
  } catch (const std::exception& e) {
    Fail(err, "trajectory", e.what());
  }
}

// The recording's frames (sim/ground_truth) with their recorded odometry/velocity, of one robot
// (the first one seen, unless named).
std::vector<ReplayedFrame> RecordedFrames(const std::string& path, std::string& robot) {
  std::map<uint64_t, ReplayedFrame> frames;
  std::map<std::pair<std::string, uint64_t>, msg::Velocity> velocities;  // by robot and frame
  const mcap::McapReader reader(path);
  reader.ForEachMessage({}, [&](const mcap::MessageView& m) {
    const std::string& topic = m.channel->topic;
    const bool truth = topic.ends_with("/sim/ground_truth"), velocity = topic.ends_with("/odometry/velocity");
    if (!truth && !velocity) return;
    const std::span<const uint8_t> cdr(reinterpret_cast<const uint8_t*>(m.data.data()), m.data.size());
    if (truth) {
      const auto t = bus::FromCdr<msg::GroundTruthPose>(cdr);
      if (robot.empty()) robot = t.header.robot_id;
      if (t.header.robot_id != robot) return;
      ReplayedFrame& frame = frames[t.header.frame_seq];
      frame.frame_seq = t.header.frame_seq;
      frame.stamp_ns = t.header.stamp_ns;
      frame.truth = {t.x_m, t.y_m, t.theta_rad};
    } else {
      auto v = bus::FromCdr<msg::Velocity>(cdr);
      velocities[{v.header.robot_id, v.header.frame_seq}] = std::move(v);
    }
  });
  std::vector<ReplayedFrame> out;
  out.reserve(frames.size());
  for (auto& [seq, frame] : frames) {
    const auto v = velocities.find({robot, seq});
    if (v != velocities.end()) {
      frame.recorded_vtrans_mps = v->second.vtrans_mps;
      frame.recorded_vrot_radps = v->second.vrot_radps;
    }
    out.push_back(frame);
  }
  return out;
}

void RunOdometry(const OdometryCommandOptions& options, std::ostream& out, std::ostream& err) {
  try {
    YAML::Node config = LoadYamlFile(options.config_file);
    for (const std::string& assignment : options.overrides) ApplyOverride(config, assignment);
    sim::SimNodeConfig sim;
    LoadConfigSection(config, "sim", sim);
    odometry::OdometryNodeConfig odometry;
    LoadConfigSection(config, "odometry", odometry);
    std::string robot = options.robot;
    const std::vector<ReplayedFrame> frames = RecordedFrames(options.recording, robot);
    if (frames.size() < 2) Fail(err, "odometry", options.recording + " holds fewer than two sim/ground_truth frames");
    const sim::WorldMap world = sim::WorldMap::LoadFromYaml(sim::ResolveWorldPath(sim.sim.world_yaml));
    const OdometryReplayResult r = ReplayOdometry(world, sim.sim, odometry, frames);
    if (options.json) {
      const nlohmann::json json = {
          {"robot", robot},
          {"frames", r.frames},
          {"ate_m", r.ate_m},
          {"scale", r.scale},
          {"heading_rms_rad", r.heading_rms_rad},
          {"final_heading_error_rad", r.final_heading_error_rad},
          {"turn_frames_misread", r.turn_frames_misread},
          {"turn_error_sum_rad", r.turn_error_sum_rad},
          {"frames_recorded", r.frames_recorded},
          {"frames_differing_from_recorded", r.frames_differing_from_recorded},
      };
      out << json.dump() << "\n";
    } else {
      char line[400];
      std::snprintf(line, sizeof line,
                    "%s: %zu frames; dead reckoning ATE %.3f m (scale %.3f), heading RMS %.3f rad, final heading "
                    "error %.3f rad; %zu turning frames misread (> 0.03 rad), turn error %.2f rad in all; %zu of %zu "
                    "recorded velocities differ",
                    robot.c_str(), r.frames, r.ate_m, r.scale, r.heading_rms_rad, r.final_heading_error_rad,
                    r.turn_frames_misread, r.turn_error_sum_rad, r.frames_differing_from_recorded, r.frames_recorded);
      out << line << "\n";
    }
  } catch (const CLI::Error&) {
    throw;
  } catch (const ConfigError& e) {
    Fail(err, "odometry", "bad config " + options.config_file + ": " + e.what());
  } catch (const std::exception& e) {
    Fail(err, "odometry", e.what());
  }
}

}  // namespace

void RegisterEvalCommand(CLI::App& rslam, std::ostream& out, std::ostream& err) {
  CLI::App* eval = rslam.add_subcommand("eval", "Evaluate place recognition and trajectories");
  eval->require_subcommand(1);

  auto vpr_options = std::make_shared<VprCommandOptions>();
  CLI::App* vpr = eval->add_subcommand("vpr", "Visual place recognition on frame-aligned image sets "
                                              "(same file name = same place): recall@1, recall@100%precision");
  vpr->add_option("--reference", vpr_options->reference_dir, "Folder of reference images (learnt as templates)")
      ->required();
  vpr->add_option("--query", vpr_options->query_dir, "Folder of query images, same file names")->required();
  vpr->add_option("--tolerance", vpr_options->tolerance, "Frames from the true place that still count as correct")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000000));
  vpr->add_option("--sequence", vpr_options->sequence_length,
                  "Sequence length L for SeqSLAM-style matching; 1 = single frame")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  vpr->add_option("--contrast-window", vpr_options->contrast_window,
                  "Local contrast enhancement window in references (0 off; default 0 single frame, 10 sequence)")
      ->check(CLI::Range(0, 100000));
  auto* preset = vpr->add_option("--preset", vpr_options->preset, "Preset name (deploy/presets/<name>.yaml)");
  auto* config = vpr->add_option("--config", vpr_options->config_file, "Preset YAML file (section templates:)")
                     ->check(CLI::ExistingFile);
  preset->excludes(config);
  vpr->add_option("--matcher", vpr_options->matcher,
                  "template: the template library (default); baseline: patch-normalised SAD, 8x8 blocks")
      ->capture_default_str()
      ->check(CLI::IsMember({"template", "baseline"}));
  vpr->add_option("--limit", vpr_options->limit, "Use only the first N frames of each set (0 = all)")
      ->capture_default_str();
  vpr->add_flag("--json", vpr_options->json, "Print the result as one JSON object");
  vpr->callback([vpr_options, &out, &err] { RunVpr(*vpr_options, out, err); });

  auto trajectory_options = std::make_shared<TrajectoryCommandOptions>();
  CLI::App* trajectory = eval->add_subcommand(
      "trajectory", "Absolute trajectory error after 2-D similarity alignment; CSV header stamp_ns,x,y[,theta]");
  trajectory->add_option("--estimate", trajectory_options->estimate_file, "Estimated trajectory CSV")->required();
  trajectory->add_option("--ground-truth", trajectory_options->truth_file, "Ground-truth trajectory CSV")->required();
  trajectory->add_flag("--no-scale", trajectory_options->no_scale, "Align by rotation and translation only (SE(2))");
  trajectory->add_option("--max-stamp-gap-ms", trajectory_options->max_stamp_gap_ms,
                         "Largest stamp difference for associating poses (0 = exact stamps)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e9));
  trajectory->add_flag("--json", trajectory_options->json, "Print the result as one JSON object");
  trajectory->callback([trajectory_options, &out, &err] { RunTrajectory(*trajectory_options, out, err); });

  auto odometry_options = std::make_shared<OdometryCommandOptions>();
  CLI::App* odometry = eval->add_subcommand(
      "odometry", "A simulated run's odometry read again: its frames rendered anew at the recorded ground truth, "
                  "read as the odometry service reads them, dead-reckoned against the truth");
  odometry->add_option("recording", odometry_options->recording, "MCAP recording with sim/ground_truth (rslam demo)")
      ->required()
      ->check(CLI::ExistingFile);
  odometry->add_option("--config", odometry_options->config_file,
                       "config with the run's sim and odometry sections (default: deploy/config/demo.yaml)")
      ->check(CLI::ExistingFile);
  odometry->add_option("--set", odometry_options->overrides, "override a config key (section.key=value), repeatable");
  odometry->add_option("--robot", odometry_options->robot, "the robot to replay (default: the first recorded)");
  odometry->add_flag("--json", odometry_options->json, "Print the result as one JSON object");
  odometry->callback([odometry_options, &out, &err] { RunOdometry(*odometry_options, out, err); });
}

void RegisterEvalCommand(CLI::App& rslam) { RegisterEvalCommand(rslam, std::cout, std::cerr); }

}  // namespace rslam::eval
