// ReplayOdometry and `rslam eval odometry` on a short path the simulator drives in the shipped
// world with the demo's config (deploy/config/demo.yaml).
#include "tools/eval/odometry_replay.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "common/bus/typed_cdr.h"
#include "common/config/config_loader.h"
#include "common/mcap/mcap_writer.h"
#include "services/odometry/camera_odometry.h"
#include "tests/support/child_process.h"
#include "tests/unit/eval/eval_test_files.h"
#include "tools/eval/eval_command.h"
#include "tools/sim/camera_renderer.h"
#include "tools/sim/robot_motion.h"
#include "tools/sim/sim_node.h"

namespace rslam::eval {
namespace {

using testing::RunRslam;

constexpr const char* kDemoConfig = RSLAM_SOURCE_DIR "/deploy/config/demo.yaml";

class OdometryReplayTest : public ::testing::Test {
 protected:
  OdometryReplayTest()
      : demo_(LoadYamlFile(kDemoConfig)),
        sim_(Section<sim::SimNodeConfig>("sim")),
        odometry_(Section<odometry::OdometryNodeConfig>("odometry")),
        world_(sim::WorldMap::LoadFromYaml(sim::ResolveWorldPath(sim_.sim.world_yaml))) {
    // From the demo's start: ahead, a quarter turn left, on, a half turn, back.
    sim::RobotMotion motion(world_, sim_.sim.motion, sim::StartPoseOf(sim_, world_));
    const double dt = sim_.sim.motion.time_step_s;
    frames_.push_back({0, 0, motion.pose(), {}, {}});
    for (const sim::MotionCommand& command :
         {sim::MotionCommand::Move(1.0), sim::MotionCommand::Rotate(M_PI / 2), sim::MotionCommand::Move(0.6),
          sim::MotionCommand::Rotate(-M_PI), sim::MotionCommand::Move(0.5)}) {
      motion.Command(command);
      for (bool idle = false; !idle;) {
        const sim::StepResult step = motion.Step(dt);
        const auto seq = static_cast<uint64_t>(frames_.size());
        const auto stamp_ns = static_cast<int64_t>(std::llround(static_cast<double>(seq) * dt * 1e9));
        frames_.push_back({seq, stamp_ns, step.pose, {}, {}});
        idle = step.idle;
      }
    }
  }
  template <class T>
  T Section(const char* name) const {
    T config;
    LoadConfigSection(demo_, name, config);
    return config;
  }
  // The velocities the odometry service would publish for the frames.
  void RecordVelocities() {
    sim::CameraRenderer renderer(world_, sim_.sim.scene, sim_.sim.camera);
    odometry::CameraOdometry odometry(odometry_.visual, odometry_.floor);
    for (size_t i = 0; i < frames_.size(); ++i) {
      const double dt = i == 0 ? 0.0 : static_cast<double>(frames_[i].stamp_ns - frames_[i - 1].stamp_ns) * 1e-9;
      const odometry::Velocity& v = odometry.Update(renderer.Render(frames_[i].truth, frames_[i].frame_seq), dt).velocity;
      frames_[i].recorded_vtrans_mps = v.vtrans;
      frames_[i].recorded_vrot_radps = v.vrot;
    }
  }

  const YAML::Node demo_;
  const sim::SimNodeConfig sim_;
  const odometry::OdometryNodeConfig odometry_;
  const sim::WorldMap world_;
  std::vector<ReplayedFrame> frames_;
};

TEST_F(OdometryReplayTest, DeadReckonsTheDemoOdometryOnFramesRenderedAtTheTruth) {
  ASSERT_GT(frames_.size(), 100u);
  const OdometryReplayResult r = ReplayOdometry(world_, sim_.sim, odometry_, frames_);
  EXPECT_EQ(r.frames, frames_.size());
  EXPECT_LT(r.ate_m, 0.1);
  EXPECT_NEAR(r.scale, 1.0, 0.2);
  EXPECT_LT(std::abs(r.final_heading_error_rad), 0.1);
  EXPECT_LE(r.turn_frames_misread, 2u);
  EXPECT_LE(r.straight_frames_misread, 2u);
  EXPECT_EQ(r.frames_recorded, 0u);
  // The same frames replayed give the same result: rendering and reading are deterministic.
  EXPECT_EQ(ReplayOdometry(world_, sim_.sim, odometry_, frames_).ate_m, r.ate_m);
}

TEST_F(OdometryReplayTest, GivesBackTheRecordedVelocitiesAndCountsThoseItDoesNot) {
  RecordVelocities();
  std::vector<msg::Velocity> messages;
  EXPECT_EQ(ReplayOdometry(world_, sim_.sim, odometry_, frames_, &messages).frames_differing_from_recorded, 0u);
  // ... and the messages the service would publish for them (rslam eval map --odometry-again).
  ASSERT_EQ(messages.size(), frames_.size());
  size_t walls = 0;
  for (size_t i = 0; i < frames_.size(); ++i) {
    EXPECT_EQ(messages[i].header.frame_seq, frames_[i].frame_seq);
    EXPECT_EQ(messages[i].header.stamp_ns, frames_[i].stamp_ns);
    EXPECT_EQ(messages[i].vtrans_mps, *frames_[i].recorded_vtrans_mps);
    EXPECT_EQ(messages[i].vrot_radps, *frames_[i].recorded_vrot_radps);
    EXPECT_TRUE(messages[i].boundary_measured);
    walls += messages[i].wall_seen;
  }
  EXPECT_EQ(messages[0].dt_s, 0.0);
  EXPECT_NEAR(messages[1].dt_s, sim_.sim.motion.time_step_s, 1e-9);
  EXPECT_GT(walls, 0u);
  frames_[40].recorded_vrot_radps = *frames_[40].recorded_vrot_radps + 0.01;
  const OdometryReplayResult r = ReplayOdometry(world_, sim_.sim, odometry_, frames_);
  EXPECT_EQ(r.frames_recorded, frames_.size());
  EXPECT_EQ(r.frames_differing_from_recorded, 1u);
  // Stamps that do not increase are refused.
  frames_[10].stamp_ns = frames_[9].stamp_ns;
  EXPECT_THROW(ReplayOdometry(world_, sim_.sim, odometry_, frames_), std::invalid_argument);
}

TEST_F(OdometryReplayTest, EvalOdometryReplaysARecording) {
  RecordVelocities();
  const auto dir = rslam::testing::ScratchFolderForTest();
  const std::string path = (dir / "run.mcap").string();
  {
    mcap::McapWriter writer;
    writer.Open(path);
    const uint16_t truth_schema = writer.AddSchema("rslam::msg::GroundTruthPose", "omgidl",
                                                   bus::MessageTraits<msg::GroundTruthPose>::kIdl);
    const uint16_t velocity_schema =
        writer.AddSchema("rslam::msg::Velocity", "omgidl", bus::MessageTraits<msg::Velocity>::kIdl);
    const uint16_t truth = writer.AddChannel(truth_schema, "/robot1/sim/ground_truth", "cdr", {});
    const uint16_t velocity = writer.AddChannel(velocity_schema, "/robot1/odometry/velocity", "cdr", {});
    const auto write = [&writer](uint16_t channel, uint32_t seq, uint64_t time, const std::vector<uint8_t>& cdr) {
      writer.Write(channel, seq, time, time, std::as_bytes(std::span(cdr)));
    };
    for (const ReplayedFrame& f : frames_) {
      msg::Header header;
      header.robot_id = "robot1";
      header.frame_seq = f.frame_seq;
      header.stamp_ns = f.stamp_ns;
      msg::GroundTruthPose t;
      t.header = header;
      t.x_m = f.truth.x;
      t.y_m = f.truth.y;
      t.theta_rad = f.truth.theta;
      msg::Velocity v;
      v.header = header;
      v.vtrans_mps = *f.recorded_vtrans_mps;
      v.vrot_radps = *f.recorded_vrot_radps;
      const auto seq = static_cast<uint32_t>(f.frame_seq);
      write(truth, seq, static_cast<uint64_t>(f.stamp_ns), bus::ToCdr(t));
      write(velocity, seq, static_cast<uint64_t>(f.stamp_ns) + 1, bus::ToCdr(v));
    }
    writer.Close();
  }
  const auto json = nlohmann::json::parse(RunRslam({"eval", "odometry", path, "--json"}));
  EXPECT_EQ(json["robot"], "robot1");
  EXPECT_EQ(json["frames"].get<size_t>(), frames_.size());
  EXPECT_EQ(json["frames_recorded"].get<size_t>(), frames_.size());
  EXPECT_EQ(json["frames_differing_from_recorded"].get<size_t>(), 0u);
  EXPECT_LT(json["ate_m"].get<double>(), 0.1);
  // Another odometry gives other velocities (the column profiles' unscaled speed alone).
  const auto other = nlohmann::json::parse(
      RunRslam({"eval", "odometry", path, "--set", "odometry.floor_odometry.enabled=false", "--json"}));
  EXPECT_GT(other["frames_differing_from_recorded"].get<size_t>(), frames_.size() / 2);
  // A bad key is named.
  try {
    RunRslam({"eval", "odometry", path, "--set", "odometry.no_such_key=1"});
    FAIL() << "accepted an unknown key";
  } catch (const CLI::RuntimeError& e) {
    EXPECT_EQ(e.get_exit_code(), 1);
    EXPECT_NE(std::string(e.what()).find("no_such_key"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rslam::eval
