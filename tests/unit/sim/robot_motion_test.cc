#include "tools/sim/robot_motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/unit/sim/test_worlds.h"

namespace rslam::sim {
namespace {

using testing::BoxRoom;

// Runs the command to its end (bounded), returning the last step.
StepResult RunToEnd(RobotMotion& motion, int max_steps = 10000) {
  StepResult r;
  for (int i = 0; i < max_steps; ++i) {
    r = motion.Step();
    if (r.command_finished) return r;
  }
  ADD_FAILURE() << "command did not finish";
  return r;
}

TEST(RobotMotionTest, MoveIntoAWallStopsShortAndReportsBlocked) {
  const WorldMap world = BoxRoom(50, 50);  // free interior x in [0.04, 1.96]
  MotionConfig config;
  RobotMotion motion(world, config, Pose2D{1.0, 1.0, 0.0});
  motion.Command(MotionCommand::Move(5.0));
  const StepResult r = RunToEnd(motion);
  EXPECT_TRUE(r.blocked);
  EXPECT_TRUE(r.idle);
  // Stopped with the robot's edge at the wall face x = 1.96.
  EXPECT_NEAR(motion.pose().x, 1.96 - config.robot_radius_m, 1e-3);
  EXPECT_LE(motion.pose().x, 1.96 - config.robot_radius_m);
  EXPECT_NEAR(motion.pose().y, 1.0, 1e-12);
  EXPECT_TRUE(world.IsDiscFree(Eigen::Vector2d(motion.pose().x, motion.pose().y), config.robot_radius_m));
  // A further move into the wall goes nowhere.
  motion.Command(MotionCommand::Move(0.5));
  const StepResult again = motion.Step();
  EXPECT_TRUE(again.blocked);
  EXPECT_NEAR(again.distance_m, 0.0, 1e-3);
}

TEST(RobotMotionTest, FreeMoveCoversTheDistanceAtTheConfiguredSpeed) {
  const WorldMap world = BoxRoom(100, 100);
  MotionConfig config;
  config.linear_speed_mps = 0.25;
  config.time_step_s = 0.1;
  RobotMotion motion(world, config, Pose2D{1.0, 1.0, M_PI / 2});
  motion.Command(MotionCommand::Move(1.0));
  double driven = 0;
  int steps = 0;
  StepResult r;
  do {
    r = motion.Step();
    driven += r.distance_m;
    ++steps;
    EXPECT_LE(r.distance_m, 0.025 + 1e-12);
  } while (!r.command_finished && steps < 1000);
  EXPECT_EQ(steps, 40);
  EXPECT_FALSE(r.blocked);
  EXPECT_NEAR(driven, 1.0, 1e-9);
  EXPECT_NEAR(motion.pose().y, 2.0, 1e-9);
  EXPECT_NEAR(motion.pose().x, 1.0, 1e-9);
  EXPECT_NEAR(motion.time_s(), 4.0, 1e-9);
}

TEST(RobotMotionTest, PirouetteTakesTwelveTurnsPausesAndReturnsToTheStartHeading) {
  const WorldMap world = BoxRoom(50, 50);
  MotionConfig config;
  const double start_heading = 0.7;
  RobotMotion motion(world, config, Pose2D{1.0, 1.0, start_heading});
  motion.Command(MotionCommand::Pirouette());
  int turns_seen = 0, pause_frames = 0, steps = 0;
  double turned = 0;
  StepResult r;
  int last_done = 0;
  do {
    r = motion.Step();
    ++steps;
    turned += r.rotation_rad;
    if (r.pirouette_turns_done > last_done) {
      EXPECT_EQ(r.pirouette_turns_done, last_done + 1) << "one turn per step at most";
      ++turns_seen;
      last_done = r.pirouette_turns_done;
    }
    if (r.pirouette_pausing && r.rotation_rad == 0.0) ++pause_frames;
    EXPECT_EQ(r.distance_m, 0.0);
  } while (!r.command_finished && steps < 10000);
  EXPECT_EQ(turns_seen, 12);
  EXPECT_EQ(r.pirouette_turns_done, 12);
  EXPECT_GE(pause_frames, 11);  // a still frame at (almost) every stop
  EXPECT_NEAR(turned, 2 * M_PI, 1e-9);
  EXPECT_NEAR(WrapAngle(motion.pose().theta - start_heading), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(motion.pose().x, 1.0);
  EXPECT_TRUE(r.idle);
}

TEST(RobotMotionTest, RotateLandsOnTheTargetHeading) {
  const WorldMap world = BoxRoom(50, 50);
  MotionConfig config;
  RobotMotion motion(world, config, Pose2D{1.0, 1.0, 3.0});
  motion.Command(MotionCommand::Rotate(-1.0));
  const StepResult r = RunToEnd(motion);
  EXPECT_FALSE(r.blocked);
  EXPECT_NEAR(motion.pose().theta, 2.0, 1e-12);
  motion.Command(MotionCommand::Rotate(2.0));  // wraps past pi
  RunToEnd(motion);
  EXPECT_NEAR(motion.pose().theta, WrapAngle(4.0), 1e-12);
}

TEST(RobotMotionTest, StopEndsTheCommandAtOnce) {
  const WorldMap world = BoxRoom(100, 100);
  MotionConfig config;
  RobotMotion motion(world, config, Pose2D{1.0, 1.0, 0.0});
  motion.Command(MotionCommand::Move(1.0));
  motion.Step();
  const double x = motion.pose().x;
  motion.Command(MotionCommand::Stop());
  EXPECT_FALSE(motion.busy());
  const StepResult r = motion.Step();
  EXPECT_TRUE(r.idle);
  EXPECT_EQ(motion.pose().x, x);
  EXPECT_EQ(r.distance_m, 0.0);
}

TEST(RobotMotionTest, RefusesAStartInsideAWallAndBadInput) {
  const WorldMap world = BoxRoom(50, 50);
  MotionConfig config;
  EXPECT_THROW(RobotMotion(world, config, Pose2D{0.1, 1.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(RobotMotion(world, config, Pose2D{NAN, 1.0, 0.0}), std::invalid_argument);
  RobotMotion motion(world, config, Pose2D{1.0, 1.0, 0.0});
  EXPECT_THROW(motion.Command(MotionCommand::Move(INFINITY)), std::invalid_argument);
  EXPECT_THROW(motion.Step(-0.1), std::invalid_argument);
  config.robot_radius_m = -1;
  EXPECT_THROW(RobotMotion(world, config, Pose2D{1.0, 1.0, 0.0}), ConfigError);
}

}  // namespace
}  // namespace rslam::sim

namespace rslam::sim {
namespace {

TEST(RobotMotionTest, SavedStateResumesTheSameTrajectory) {
  const WorldMap world = testing::BoxRoom(80, 80);
  MotionConfig config;
  RobotMotion motion(world, config, Pose2D{1.2, 1.0, 0.3});
  motion.Command(MotionCommand::Pirouette());
  for (int i = 0; i < 17; ++i) motion.Step();
  const proto::RobotMotionState saved = motion.SaveState();
  std::vector<Pose2D> expected;
  for (int i = 0; i < 80; ++i) expected.push_back(motion.Step().pose);

  RobotMotion restored(world, config, Pose2D{1.0, 1.0, 0.0});
  restored.LoadState(saved);
  EXPECT_TRUE(restored.busy());
  for (int i = 0; i < 80; ++i) {
    const Pose2D p = restored.Step().pose;
    ASSERT_EQ(p.x, expected[i].x);
    ASSERT_EQ(p.theta, expected[i].theta) << "step " << i;
  }
  proto::RobotMotionState bad = saved;
  bad.set_x(NAN);
  EXPECT_THROW(restored.LoadState(bad), std::invalid_argument);
  bad = saved;
  bad.set_x(0.01);  // inside the wall
  EXPECT_THROW(restored.LoadState(bad), std::invalid_argument);
  bad = saved;
  bad.set_format_version(2);
  EXPECT_THROW(restored.LoadState(bad), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::sim
