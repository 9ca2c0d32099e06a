#include "tools/sim/simulated_robot.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/unit/sim/test_worlds.h"

namespace rslam::sim {
namespace {

using testing::UwbRoom;

TEST(SimulatedRobotTest, TicksGiveGroundTruthImagesAndOdometryOfEachStep) {
  const WorldMap& world = UwbRoom();
  SimConfig config;
  config.wheel_odometry.rotation_noise_per_rad = 0.0;  // exact rotation readings for this test
  config.wheel_odometry.rotation_noise_per_m = 0.0;
  SimulatedRobot robot(world, config, world.DefaultStartPose());
  robot.Command(MotionCommand::Rotate(M_PI / 2));
  double heading = robot.pose().theta;
  for (int i = 0; i < 5; ++i) {
    const SimFrame frame = robot.Tick();
    EXPECT_EQ(frame.index, static_cast<uint64_t>(i));
    EXPECT_NEAR(frame.time_s, 0.1 * (i + 1), 1e-12);
    EXPECT_EQ(frame.image.type(), CV_8UC3);
    EXPECT_EQ(frame.image.cols, config.camera.width);
    EXPECT_NEAR(WrapAngle(frame.ground_truth.theta - heading), frame.motion.rotation_rad, 1e-12);
    EXPECT_NEAR(frame.wheel_odometry.vrot_radps * frame.wheel_odometry.dt_s, frame.motion.rotation_rad, 1e-12);
    EXPECT_EQ(frame.wheel_odometry.vtrans_mps, 0.0);
    heading = frame.ground_truth.theta;
  }
}

TEST(SimulatedRobotTest, SavedStateReplaysTheSameFrames) {
  const WorldMap& world = UwbRoom();
  SimConfig config;
  SimulatedRobot robot(world, config, world.DefaultStartPose());
  robot.Command(MotionCommand::Move(0.8));
  for (int i = 0; i < 7; ++i) robot.Tick();
  const proto::SimulatedRobotState saved = robot.SaveState();
  std::vector<SimFrame> expected;
  for (int i = 0; i < 10; ++i) expected.push_back(robot.Tick());

  SimulatedRobot restored(world, config, world.DefaultStartPose());
  restored.LoadState(saved);
  for (int i = 0; i < 10; ++i) {
    const SimFrame frame = restored.Tick();
    EXPECT_EQ(frame.index, expected[i].index);
    EXPECT_EQ(frame.ground_truth.x, expected[i].ground_truth.x);
    EXPECT_EQ(frame.wheel_odometry.vtrans_mps, expected[i].wheel_odometry.vtrans_mps);
    EXPECT_EQ(cv::norm(frame.image, expected[i].image, cv::NORM_L1), 0.0) << "frame " << i;
  }
  proto::SimulatedRobotState bad = saved;
  bad.clear_motion();
  EXPECT_THROW(restored.LoadState(bad), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::sim
