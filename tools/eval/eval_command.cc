#include "tools/eval/eval_command.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <fstream>
#include <map>
#include <numbers>
#include <memory>
#include <utility>
#include <string>
#include <vector>

#include "common/config/config_error.h"
#include "common/config/config_loader.h"
#include "common/bus/typed_cdr.h"
#include "common/mcap/mcap_reader.h"
#include "tools/demo/demo_artifacts.h"
#include "tools/demo/demo_metrics.h"
#include "tools/eval/image_folder.h"
#include "tools/eval/map_replay.h"
#include "tools/eval/recorded_run.h"
#include "tools/eval/odometry_replay.h"
#include "tools/eval/patch_normalised_sad.h"
#include "tools/eval/template_difference_matrix.h"
#include "tools/eval/trajectory_csv.h"
#include "tools/eval/vpr_evaluation.h"
#include "tools/sim/sim_node.h"

#include <opencv2/imgcodecs.hpp>

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

struct MapCommandOptions {
  std::string recording;
  std::string config_file = RSLAM_EVAL_DEFAULT_DEMO_CONFIG;
  std::vector<std::string> overrides;
  std::string robot;
  bool recorded_actions = false;
  bool odometry_again = false;
  std::string out_dir;
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

// The recording's frames with ground truth, with their recorded odometry/velocity.
std::vector<ReplayedFrame> RecordedFrames(const RecordedRun& run) {
  std::vector<ReplayedFrame> out;
  for (const RecordedFrame& f : run.frames) {
    if (!f.truth) continue;
    ReplayedFrame& frame = out.emplace_back();
    frame.frame_seq = f.frame_seq;
    frame.stamp_ns = f.stamp_ns;
    frame.truth = *f.truth;
    if (f.velocity) {
      frame.recorded_vtrans_mps = f.velocity->vtrans_mps;
      frame.recorded_vrot_radps = f.velocity->vrot_radps;
    }
  }
  return out;
}

// Replaces the run's odometry/velocity by the odometry read again (config's `odometry` section)
// on its frames rendered anew at the recorded truth; a frame without truth loses its velocity.
OdometryReplayResult ReadOdometryAgain(const YAML::Node& config, const sim::SimConfig& sim,
                                       const sim::WorldMap& world, RecordedRun& run) {
  odometry::OdometryNodeConfig odometry;
  LoadConfigSection(config, "odometry", odometry);
  const std::vector<ReplayedFrame> frames = RecordedFrames(run);
  std::vector<msg::Velocity> messages;
  const OdometryReplayResult result = ReplayOdometry(world, sim, odometry, frames, &messages);
  auto message = messages.begin();
  for (RecordedFrame& f : run.frames) {
    f.velocity.reset();
    if (!f.truth) continue;
    f.velocity = std::move(*message++);
    f.velocity->header.robot_id = run.robot;
  }
  return result;
}

void RunOdometry(const OdometryCommandOptions& options, std::ostream& out, std::ostream& err) {
  try {
    YAML::Node config = LoadYamlFile(options.config_file);
    for (const std::string& assignment : options.overrides) ApplyOverride(config, assignment);
    sim::SimNodeConfig sim;
    LoadConfigSection(config, "sim", sim);
    odometry::OdometryNodeConfig odometry;
    LoadConfigSection(config, "odometry", odometry);
    const RecordedRun run = ReadRecordedRun(options.recording, options.robot);
    const std::string& robot = run.robot;
    const std::vector<ReplayedFrame> frames = RecordedFrames(run);
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
          {"straight_frames_misread", r.straight_frames_misread},
          {"turn_error_sum_rad", r.turn_error_sum_rad},
          {"frames_recorded", r.frames_recorded},
          {"frames_differing_from_recorded", r.frames_differing_from_recorded},
      };
      out << json.dump() << "\n";
    } else {
      char line[400];
      std::snprintf(line, sizeof line,
                    "%s: %zu frames; dead reckoning ATE %.3f m (scale %.3f), heading RMS %.3f rad, final heading "
                    "error %.3f rad; %zu turning frames misread (> 0.03 rad), %zu straight frames read turning "
                    "(> 0.03 rad), turn error %.2f rad in all; %zu of %zu recorded velocities differ",
                    robot.c_str(), r.frames, r.ate_m, r.scale, r.heading_rms_rad, r.final_heading_error_rad,
                    r.turn_frames_misread, r.straight_frames_misread, r.turn_error_sum_rad,
                    r.frames_differing_from_recorded, r.frames_recorded);
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

void RunMap(const MapCommandOptions& options, std::ostream& out, std::ostream& err) {
  try {
    YAML::Node config = LoadYamlFile(options.config_file);
    for (const std::string& assignment : options.overrides) ApplyOverride(config, assignment);
    sim::SimNodeConfig sim;
    LoadConfigSection(config, "sim", sim);
    MapReplayConfig replay;
    LoadConfigSection(config, "pose_cells", replay.pose_cells);
    LoadConfigSection(config, "experience_map", replay.experience_map);
    LoadConfigSection(config, "occupancy", replay.occupancy);
    replay.recorded_actions = options.recorded_actions;
    RecordedRun run = ReadRecordedRun(options.recording, options.robot);
    if (run.frames.empty()) Fail(err, "map", options.recording + " holds no frames of a robot");
    for (const std::string& skipped : run.skipped) err << "rslam eval map: left out " << skipped << "\n";
    const sim::WorldMap world = sim::WorldMap::LoadFromYaml(sim::ResolveWorldPath(sim.sim.world_yaml));
    std::optional<OdometryReplayResult> odometry_again;
    if (options.odometry_again) odometry_again = ReadOdometryAgain(config, sim.sim, world, run);
    const MapReplayResult r = ReplayMap(run, replay);

    // Judged as `rslam demo` judges its run (tools/demo/demo_metrics.h).
    const Pose2D start = sim::StartPoseOf(sim, world);
    const std::vector<Eigen::Vector2i> reachable =
        demo::ReachableFootprint(world, start, sim.sim.motion.robot_radius_m);
    const Pose2D map_origin =
        demo::MapOrigin(start, replay.experience_map.map.exp_initial_em_deg * std::numbers::pi / 180);
    const demo::RunFigures figures = demo::JudgeRun(world, reachable, map_origin, r.seen);
    nlohmann::json json = demo::FiguresJson(figures, r.seen, map_origin, world.resolution());
    json["robot"] = run.robot;
    json["actions"] = options.recorded_actions ? "recorded" : "replayed";
    json["odometry_read_again"] =
        odometry_again ? nlohmann::json{{"dead_reckoning_ate_m", odometry_again->ate_m},
                                        {"scale", odometry_again->scale},
                                        {"frames_differing_from_recorded", odometry_again->frames_differing_from_recorded}}
                       : nlohmann::json(nullptr);
    json["actions_compared"] = r.actions_compared;
    json["actions_differing"] = r.actions_differing;
    json["profiles_kept"] = r.profiles_kept;
    json["walls_axes"] = r.axes_fixed ? nlohmann::json{{"frame", r.axes_fixed->frame}, {"rad", r.axes_fixed->rad}}
                                      : nlohmann::json(nullptr);
    nlohmann::json recaptures = nlohmann::json::array();
    std::size_t toward_truth = 0;
    for (const RecaptureError& e : JudgeRecaptures(r.heading_recaptures, r.seen, map_origin)) {
      recaptures.push_back({{"frame", e.frame}, {"taken_rad", e.taken_rad}, {"error_before_rad", e.error_before_rad},
                            {"error_after_rad", e.error_after_rad}});
      if (e.TowardTruth()) ++toward_truth;
    }
    json["heading_recaptures"] = {
        {"count", r.heading_recaptures.size()}, {"toward_truth", toward_truth}, {"against_truth", recaptures}};
    nlohmann::json judged = nlohmann::json::array();
    for (const ScanLinkError& e : JudgeScanLinks(r.scan_links, demo::ExperienceGroundTruth(r.seen)))
      judged.push_back({{"from", e.from_id}, {"to", e.to_id}, {"position_m", e.position_m}, {"heading_rad", e.heading_rad}});
    json["scan_links"] = {{"registered", r.scan_registrations}, {"kept", r.scan_links.size()}, {"against_truth", judged}};
    json["skipped_channels"] = run.skipped;
    if (!options.out_dir.empty()) {
      const std::filesystem::path dir(options.out_dir);
      std::filesystem::create_directories(dir);
      std::ofstream(dir / "summary.json") << json.dump(2) << "\n";
      cv::imwrite((dir / "experience_map.png").string(),
                  demo::RenderExperienceMap(world, r.seen.ground_truth, &*r.seen.map, figures.ate ? &*figures.ate : nullptr));
      demo::WriteExperiencesCsv(*r.seen.map, r.seen, figures.ate ? &*figures.ate : nullptr, dir / "experiences.csv");
      cv::imwrite((dir / "grid_errors.png").string(),
                  demo::RenderGridComparison(world, reachable, figures.map_to_world.value_or(map_origin), *r.seen.grid,
                                             world.resolution()));
    }
    if (options.json) {
      out << json.dump() << "\n";
      return;
    }
    const auto number = [](const nlohmann::json& v, const char* format) {
      if (v.is_null()) return std::string("n/a");
      char text[32];
      std::snprintf(text, sizeof text, format, v.get<double>());
      return std::string(text);
    };
    out << run.robot << ": " << json["frames"] << " frames, " << json["experiences"] << " experiences, "
        << json["loop_closures"] << " loop closures (" << number(json["loop_closure_precision"], "%.3f")
        << " right); coverage " << number(json["coverage"], "%.4f") << ", map precision "
        << number(json["map_precision"], "%.4f") << ", ATE " << number(json["ate_m"], "%.3f") << " m (odometry "
        << number(json["ate_odometry_m"], "%.3f") << " m); " << r.heading_recaptures.size()
        << " heading recaptures (" << toward_truth << " toward the truth); ";
    if (options.recorded_actions)
      out << "recorded actions applied\n";
    else
      out << r.actions_differing << " of " << r.actions_compared << " recorded actions differ\n";
  } catch (const CLI::Error&) {
    throw;
  } catch (const ConfigError& e) {
    Fail(err, "map", "bad config " + options.config_file + ": " + e.what());
  } catch (const std::exception& e) {
    Fail(err, "map", e.what());
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

  auto map_options = std::make_shared<MapCommandOptions>();
  CLI::App* map = eval->add_subcommand(
      "map", "A simulated run's map built again: its recorded odometry and views through the pose cells and the "
             "experience map, its obstacle profiles into a grid, judged against the truth as rslam demo judges");
  map->add_option("recording", map_options->recording, "MCAP recording of a run (rslam demo's recording.mcap)")
      ->required()
      ->check(CLI::ExistingFile);
  map->add_option("--config", map_options->config_file,
                  "config with the run's sim, pose_cells, experience_map and occupancy sections (default: "
                  "deploy/config/demo.yaml)")
      ->check(CLI::ExistingFile);
  map->add_option("--set", map_options->overrides, "override a config key (section.key=value), repeatable");
  map->add_option("--robot", map_options->robot, "the robot to replay (default: the first recorded)");
  CLI::Option* odometry_again =
      map->add_flag("--odometry-again", map_options->odometry_again,
                    "read the odometry again (the config's odometry section) on frames rendered anew at the "
                    "recorded truth, as `rslam eval odometry` does, instead of the recorded odometry/velocity");
  map->add_flag("--recorded-actions", map_options->recorded_actions,
                "apply the recorded pose_cells/action instead of running the pose cells again");
  odometry_again->excludes("--recorded-actions");
  map->add_option("--out", map_options->out_dir, "also write summary.json, experience_map.png and grid_errors.png here");
  map->add_flag("--json", map_options->json, "Print the result as one JSON object");
  map->callback([map_options, &out, &err] { RunMap(*map_options, out, err); });
}

void RegisterEvalCommand(CLI::App& rslam) { RegisterEvalCommand(rslam, std::cout, std::cerr); }

}  // namespace rslam::eval
