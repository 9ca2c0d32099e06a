// ReplayMap and `rslam eval map` on a recording written here: a robot driving a square twice in the
// shipped world, its odometry and views (the second lap recognising the first) through the pose cells
// as the service runs them, with obstacle profiles, written as `rslam record` writes a run. The demo
// system test replays a real run's recording and checks the map against the demo's own summary.
#include "tools/eval/map_replay.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "common/bus/typed_cdr.h"
#include "common/config/config_loader.h"
#include "common/mcap/mcap_writer.h"
#include "services/pose_cells/pose_cell_action_message.h"
#include "services/pose_cells/pose_cell_network.h"
#include "tests/support/child_process.h"
#include "tests/unit/eval/eval_test_files.h"
#include "tools/demo/demo_metrics.h"
#include "tools/eval/eval_command.h"
#include "tools/sim/sim_node.h"
#include "tools/sim/world_map.h"

namespace rslam::eval {
namespace {

using testing::RunRslam;

constexpr const char* kDemoConfig = RSLAM_SOURCE_DIR "/deploy/config/demo.yaml";
constexpr double kDt = 0.1;
constexpr int kSideFrames = 40;  // 1 m at 0.25 m/s
constexpr int kTurnFrames = 4;   // a quarter turn

class MapReplayTest : public ::testing::Test {
 protected:
  MapReplayTest() : demo_(LoadYamlFile(kDemoConfig)) {
    LoadConfigSection(demo_, "pose_cells", config_.pose_cells);
    LoadConfigSection(demo_, "experience_map", config_.experience_map);
    LoadConfigSection(demo_, "occupancy", config_.occupancy);
    sim::SimNodeConfig sim;
    LoadConfigSection(demo_, "sim", sim);
    const sim::WorldMap world = sim::WorldMap::LoadFromYaml(sim::ResolveWorldPath(sim.sim.world_yaml));
    Record(sim::StartPoseOf(sim, world));
  }

  // Two laps of a 1-m square: the first lap's views are new templates, the second's match them.
  void Record(Pose2D truth) {
    run_.robot = "robot1";
    pose_cells::PoseCellNetwork network(config_.pose_cells.network);
    pose_cells::FloorBoundary scratch;
    const int lap = 4 * (kSideFrames + kTurnFrames);
    for (int i = 0; i < 2 * lap; ++i) {
      RecordedFrame& f = run_.frames.emplace_back();
      f.frame_seq = static_cast<uint64_t>(i);
      f.stamp_ns = static_cast<int64_t>(i) * 100'000'000;
      msg::Header header;
      header.robot_id = run_.robot;
      header.frame_seq = f.frame_seq;
      header.stamp_ns = f.stamp_ns;
      const bool turning = i % (kSideFrames + kTurnFrames) >= kSideFrames;
      msg::Velocity v;
      v.header = header;
      v.dt_s = i == 0 ? 0.0 : kDt;
      v.vtrans_mps = i == 0 || turning ? 0.0 : 0.25;
      v.vrot_radps = i == 0 || !turning ? 0.0 : std::numbers::pi / 2 / (kTurnFrames * kDt);
      v.wall_seen = i > 0 && !turning;  // a wall along each side (the square's axes)
      truth = Compose(truth, {v.vtrans_mps * v.dt_s, 0.0, v.vrot_radps * v.dt_s});
      f.truth = truth;
      f.velocity = v;
      msg::ViewTemplate view;
      view.header = header;
      const int place = i % lap;
      view.template_id = static_cast<uint32_t>(place / 2);
      view.is_new = i < lap && place % 2 == 0;
      view.difference = view.is_new ? 0.0 : 0.01;
      view.template_count = static_cast<uint32_t>(std::min(i, lap - 1) / 2 + 1);
      f.view = view;
      f.action = pose_cells::StepFrame(network, header, &v, {v.vtrans_mps, v.vrot_radps, v.dt_s}, &view,
                                       static_cast<uint64_t>(i), scratch)
                     .message;
      msg::ObstacleProfile profile;  // floor seen free 1 m ahead, a wall at 1.2 m to the left
      profile.header = header;
      profile.bearing_min_rad = -0.5f;
      profile.bearing_step_rad = 0.1f;
      profile.max_range_m = 1.5f;
      for (int b = 0; b < 11; ++b)
        profile.bins.push_back({b < 10 ? msg::ProfileBinStatus::PROFILE_BIN_FREE : msg::ProfileBinStatus::PROFILE_BIN_OBSTACLE,
                                b < 10 ? 1.0f : 1.2f, 0.35f});
      f.profile = profile;
    }
  }

  // The run as `rslam record` writes it: each message on /robot1/<topic>, in CDR. With
  // old_actions, pose_cells/action as a build with another definition of it recorded them.
  std::string WriteRecording(bool old_actions = false) const {
    const std::string path = (dir_ / (old_actions ? "old.mcap" : "run.mcap")).string();
    mcap::McapWriter writer;
    writer.Open(path);
    std::map<std::string, uint16_t> channels;
    const auto write = [&](const std::string& topic, const msg::Header& h, auto message) {
      using Traits = bus::MessageTraits<decltype(message)>;
      if (!channels.count(topic))
        channels[topic] =
            writer.AddChannel(writer.AddSchema(Traits::kTypeName, "omgidl", Traits::kIdl), "/robot1/" + topic, "cdr", {});
      const std::vector<uint8_t> cdr = bus::ToCdr(message);
      writer.Write(channels[topic], static_cast<uint32_t>(h.frame_seq), static_cast<uint64_t>(h.stamp_ns),
                   static_cast<uint64_t>(h.stamp_ns), std::as_bytes(std::span(cdr)));
    };
    for (const RecordedFrame& f : run_.frames) {
      msg::GroundTruthPose t;
      t.header = f.velocity->header;
      t.x_m = f.truth->x;
      t.y_m = f.truth->y;
      t.theta_rad = f.truth->theta;
      write("sim/ground_truth", t.header, t);
      write("odometry/velocity", t.header, *f.velocity);
      write("templates/view", t.header, *f.view);
      if (old_actions) {
        if (!channels.count("pose_cells/action"))
          channels["pose_cells/action"] = writer.AddChannel(
              writer.AddSchema("rslam::msg::PoseCellAction", "omgidl",
                               "module rslam { module msg { @final struct PoseCellAction { uint64 action_seq; }; }; };"),
              "/robot1/pose_cells/action", "cdr", {});
        const std::vector<uint8_t> cdr = {0, 1, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0};
        writer.Write(channels["pose_cells/action"], 0, static_cast<uint64_t>(t.header.stamp_ns),
                     static_cast<uint64_t>(t.header.stamp_ns), std::as_bytes(std::span(cdr)));
      } else {
        write("pose_cells/action", t.header, *f.action);
      }
      write("occupancy/profile", t.header, *f.profile);
    }
    writer.Close();
    return path;
  }

  const YAML::Node demo_;
  MapReplayConfig config_;
  RecordedRun run_;
  const std::filesystem::path dir_ = rslam::testing::ScratchFolderForTest();
};

TEST_F(MapReplayTest, GivesBackTheRecordedActionsAndBuildsTheirMap) {
  const MapReplayResult r = ReplayMap(run_, config_);
  EXPECT_EQ(r.actions_compared, run_.frames.size());
  EXPECT_EQ(r.actions_differing, 0u);
  ASSERT_TRUE(r.seen.map.has_value());
  EXPECT_GT(r.seen.map->experiences.size(), 10u);
  bool closes_loop = false;
  for (const msg::ExperienceLink& l : r.seen.map->links) closes_loop = closes_loop || l.closes_loop;
  EXPECT_TRUE(closes_loop) << "the second lap recognises the first";
  EXPECT_EQ(r.seen.ground_truth.size(), run_.frames.size());
  EXPECT_EQ(r.seen.experience_poses.size(), run_.frames.size());
  EXPECT_EQ(r.seen.experience_first_frame.size(), r.seen.map->experiences.size());
  EXPECT_GT(r.profiles_kept, 0u);
  EXPECT_LT(r.profiles_kept, run_.frames.size());  // a standing or barely moved robot adds nothing
  ASSERT_TRUE(r.seen.grid.has_value());
  int free = 0;
  for (int8_t c : r.seen.grid->cells) free += c >= 0 && c <= 19;
  EXPECT_GT(free, 100);

  // The recorded actions applied build the same map.
  MapReplayConfig recorded = config_;
  recorded.recorded_actions = true;
  const MapReplayResult same = ReplayMap(run_, recorded);
  EXPECT_EQ(same.actions_compared, 0u);
  ASSERT_EQ(same.seen.map->experiences.size(), r.seen.map->experiences.size());
  for (size_t i = 0; i < r.seen.map->experiences.size(); ++i) {
    EXPECT_EQ(same.seen.map->experiences[i].x_m, r.seen.map->experiences[i].x_m);
    EXPECT_EQ(same.seen.map->experiences[i].y_m, r.seen.map->experiences[i].y_m);
  }
  EXPECT_EQ(same.seen.grid->cells, r.seen.grid->cells);
}

TEST_F(MapReplayTest, CountsActionsThatDifferAndRefusesAnEmptyRun) {
  run_.frames[100].action->offset_x_m += 0.01;
  EXPECT_EQ(ReplayMap(run_, config_).actions_differing, 1u);
  // Other pose-cell settings give other actions on the same input.
  MapReplayConfig other = config_;
  other.pose_cells.network.exp_delta_pc_threshold = 0.5;  // new experiences more often
  EXPECT_GT(ReplayMap(run_, other).actions_differing, 0u);

  RecordedRun empty;
  empty.robot = "robot1";
  empty.frames.push_back(run_.frames[0]);
  empty.frames[0].velocity.reset();
  empty.frames[0].view.reset();
  EXPECT_THROW(ReplayMap(empty, config_), std::invalid_argument);
}

TEST(JudgeScanLinks, MeasuresEachLinkAgainstItsEndsTrueRelativePose) {
  // Experience 3 truly 1 m ahead of 0 and turned a quarter; the link measures it 1.3 m ahead,
  // turned 0.1 rad less. Experience 7 has no truth: its link is left out.
  const std::map<uint32_t, Pose2D> truth = {{0, {2.0, 1.0, std::numbers::pi / 2}},
                                            {3, {2.0, 2.0, std::numbers::pi}}};
  experience_map::ScanLink right, wrong;
  right.link = {0, 3, 1.0, 0.0, std::numbers::pi / 2};
  wrong.link = {0, 3, 1.3, 0.0, std::numbers::pi / 2 - 0.1};
  experience_map::ScanLink unknown = right;
  unknown.link.to_id = 7;
  const std::vector<experience_map::ScanLink> links = {right, unknown, wrong};
  const std::vector<ScanLinkError> judged = JudgeScanLinks(links, truth);
  ASSERT_EQ(judged.size(), 2u);
  EXPECT_NEAR(judged[0].position_m, 0.0, 1e-12);
  EXPECT_NEAR(judged[0].heading_rad, 0.0, 1e-12);
  EXPECT_EQ(judged[1].to_id, 3u);
  EXPECT_NEAR(judged[1].position_m, 0.3, 1e-12);
  EXPECT_NEAR(judged[1].heading_rad, 0.1, 1e-12);
}

TEST(JudgeRecaptures, MeasuresTheHeadingErrorOnTheFramesBeforeAndAtEach) {
  // The map frame faces 0.5 rad left of the world's. Frame 11 turns a right heading 0.3 rad off,
  // frame 12 takes it back; frame 10 has no frame before it and frame 13 no truth: both are left
  // out.
  demo::DemoObservations seen;
  const double truth[] = {1.0, 1.2, 1.4, 1.6};
  const double error[] = {0.0, 0.3, 0.0, -0.2};
  for (int i = 0; i < 4; ++i) {
    const uint64_t frame = 10 + static_cast<uint64_t>(i);
    if (i < 3) seen.ground_truth.push_back({frame, 0, 0.0, 0.0, truth[i]});
    seen.experience_poses.push_back({frame, 0, 0.0, 0.0, truth[i] - 0.5 + error[i]});
  }
  const std::vector<MapReplayResult::Recapture> recaptures = {{10, 0.1}, {11, -0.3}, {12, 0.3}, {13, 0.1}};
  const Pose2D map_origin{3.0, -2.0, 0.5};
  const std::vector<RecaptureError> judged = JudgeRecaptures(recaptures, seen, map_origin);
  ASSERT_EQ(judged.size(), 2u);
  EXPECT_EQ(judged[0].frame, 11u);
  EXPECT_NEAR(judged[0].error_before_rad, 0.0, 1e-12);
  EXPECT_NEAR(judged[0].error_after_rad, 0.3, 1e-12);
  EXPECT_FALSE(judged[0].TowardTruth());
  EXPECT_EQ(judged[1].frame, 12u);
  EXPECT_NEAR(judged[1].taken_rad, 0.3, 1e-12);
  EXPECT_NEAR(judged[1].error_before_rad, 0.3, 1e-12);
  EXPECT_NEAR(judged[1].error_after_rad, 0.0, 1e-12);
  EXPECT_TRUE(judged[1].TowardTruth());
}

TEST_F(MapReplayTest, RecordsEachHeadingRecaptureAndJudgesItTowardTheTruth) {
  // The first lap's second quarter turn read 0.3 rad too far (one frame), so the third side's
  // walls come 0.3 rad off the axes, past the hold's widest gate; five of them in a row take it
  // back (no turning asked of them here). The views of the first lap are all new: no recognition
  // corrects it first.
  MapReplayConfig config = config_;
  config.experience_map.map.exp_manhattan_recapture_frames = 5;
  config.experience_map.map.exp_manhattan_recapture_turn_rad = 0.0;
  RecordedRun drifted = run_;
  const int misread = 2 * (kSideFrames + kTurnFrames) - 1;
  drifted.frames[misread].velocity->vrot_radps += 0.3 / kDt;
  const MapReplayResult r = ReplayMap(drifted, config);
  ASSERT_FALSE(r.heading_recaptures.empty());
  EXPECT_GT(r.heading_recaptures[0].frame, static_cast<uint64_t>(misread));
  EXPECT_NEAR(r.heading_recaptures[0].taken_rad, 0.3, 0.05);
  const Pose2D origin =
      demo::MapOrigin(*drifted.frames[0].truth, config.experience_map.map.exp_initial_em_deg * std::numbers::pi / 180);
  const std::vector<RecaptureError> judged = JudgeRecaptures(r.heading_recaptures, r.seen, origin);
  ASSERT_FALSE(judged.empty());
  EXPECT_NEAR(judged[0].error_before_rad, 0.3, 0.05);
  EXPECT_TRUE(judged[0].TowardTruth());
}

TEST_F(MapReplayTest, EvalMapReadsTheOdometryAgainOnFramesRenderedAtTheTruth) {
  // The recorded odometry here is the truth itself; read again from the frames rendered where the
  // robot stood, it is the camera's, which is not (and cannot follow the square's quarter turns in
  // 0.4 s, four times the simulator's turn rate).
  const std::string path = WriteRecording();
  EXPECT_TRUE(nlohmann::json::parse(RunRslam({"eval", "map", path, "--json"}))["odometry_read_again"].is_null());
  const auto json = nlohmann::json::parse(RunRslam({"eval", "map", path, "--json", "--odometry-again"}));
  const nlohmann::json& again = json["odometry_read_again"];
  ASSERT_TRUE(again.is_object());
  EXPECT_GT(again["frames_differing_from_recorded"].get<size_t>(), run_.frames.size() / 2);
  EXPECT_GT(again["dead_reckoning_ate_m"].get<double>(), 1e-3);
  EXPECT_GT(json["actions_differing"].get<size_t>(), 0u);
  EXPECT_GT(json["ate_odometry_m"].get<double>(), 1e-3);
  EXPECT_EQ(json["frames"].get<size_t>(), run_.frames.size());
  // The recorded actions do not use the odometry: the two flags together are refused.
  EXPECT_THROW(RunRslam({"eval", "map", path, "--odometry-again", "--recorded-actions"}), CLI::ExcludesError);
}

TEST_F(MapReplayTest, EvalMapReplaysARecordingAndJudgesItAsTheDemoDoes) {
  const std::string path = WriteRecording();
  const auto json = nlohmann::json::parse(RunRslam({"eval", "map", path, "--json", "--out", (dir_ / "out").string()}));
  EXPECT_EQ(json["robot"], "robot1");
  EXPECT_EQ(json["actions"], "replayed");
  EXPECT_EQ(json["actions_compared"].get<size_t>(), run_.frames.size());
  EXPECT_EQ(json["actions_differing"].get<size_t>(), 0u);
  EXPECT_EQ(json["frames"].get<size_t>(), run_.frames.size());
  for (const char* key : {"coverage", "map_precision", "experiences", "links", "loop_closures",
                          "loop_closure_precision", "ate_m", "ate_odometry_m", "grid"})
    EXPECT_TRUE(json.contains(key)) << key;
  EXPECT_EQ(json["scan_links"]["against_truth"].size(), json["scan_links"]["kept"].get<size_t>());
  // The odometry is the truth: the heading never drifts for a recapture to take back.
  EXPECT_EQ(json["heading_recaptures"]["count"].get<size_t>(), 0u);
  EXPECT_TRUE(json["heading_recaptures"]["against_truth"].empty());
  // The walls' axes: fixed by the first exp_manhattan_reference_frames wall directions (all agree).
  int walls = 0;
  uint64_t fixed_at = 0;
  const int reference_frames = config_.experience_map.map.exp_manhattan_reference_frames;
  for (const RecordedFrame& f : run_.frames)
    if (f.velocity->wall_seen && ++walls == reference_frames) fixed_at = f.frame_seq;
  ASSERT_TRUE(json["walls_axes"].is_object());
  EXPECT_EQ(json["walls_axes"]["frame"].get<uint64_t>(), fixed_at);
  EXPECT_NEAR(json["walls_axes"]["rad"].get<double>(), 0.0, 1e-9);
  EXPECT_GT(json["coverage"].get<double>(), 0.0);
  // The odometry here is the truth, so the map's error is small.
  EXPECT_LT(json["ate_odometry_m"].get<double>(), 1e-6);
  EXPECT_LT(json["ate_m"].get<double>(), 0.1);
  for (const char* file : {"summary.json", "experience_map.png", "grid_errors.png"})
    EXPECT_TRUE(std::filesystem::exists(dir_ / "out" / file)) << file;
  {
    // experiences.csv: a row per experience, each placed by the ATE's alignment; the RMS of their
    // distances from the truth is the ATE.
    std::ifstream csv(dir_ / "out" / "experiences.csv");
    std::string line;
    ASSERT_TRUE(std::getline(csv, line));
    EXPECT_EQ(line, "id,x,y,theta,frame_seq,truth_x,truth_y,truth_theta,aligned_x,aligned_y,error_m");
    size_t rows = 0, judged = 0;
    double sum_sq = 0.0;
    while (std::getline(csv, line)) {
      ++rows;
      const std::string error = line.substr(line.rfind(',') + 1);
      if (error.empty()) continue;
      ++judged;
      sum_sq += std::stod(error) * std::stod(error);
    }
    EXPECT_EQ(rows, json["experiences"].get<size_t>());
    ASSERT_GT(judged, 1u);
    EXPECT_NEAR(std::sqrt(sum_sq / judged), json["ate_m"].get<double>(), 1e-6);
  }

  const auto recorded = nlohmann::json::parse(RunRslam({"eval", "map", path, "--recorded-actions", "--json"}));
  EXPECT_EQ(recorded["actions"], "recorded");
  EXPECT_EQ(recorded["experiences"], json["experiences"]);
  EXPECT_EQ(recorded["ate_m"], json["ate_m"]);

  // A recording made before pose_cells/action changed replays without the recorded actions.
  const auto old = nlohmann::json::parse(RunRslam({"eval", "map", WriteRecording(true), "--json"}));
  EXPECT_EQ(old["actions_compared"].get<size_t>(), 0u);
  ASSERT_EQ(old["skipped_channels"].size(), 1u);
  EXPECT_NE(old["skipped_channels"][0].get<std::string>().find("/robot1/pose_cells/action"), std::string::npos);
  EXPECT_EQ(old["experiences"], json["experiences"]);

  // A bad key is named; a robot the recording does not hold is an error.
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"eval", "map", path, "--set", "experience_map.no_such_key=1"},
        std::vector<std::string>{"eval", "map", path, "--robot", "robot9"}}) {
    try {
      RunRslam(args);
      FAIL() << "accepted " << args.back();
    } catch (const CLI::RuntimeError& e) {
      EXPECT_EQ(e.get_exit_code(), 1);
    }
  }
  try {
    RunRslam({"eval", "map", path, "--set", "experience_map.no_such_key=1"});
  } catch (const CLI::RuntimeError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_key"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir_);
}

}  // namespace
}  // namespace rslam::eval
