#include "tools/sim/simulated_robot.h"

#include <stdexcept>
#include <string>

namespace rslam::sim {

namespace {
const SimConfig& Validated(const SimConfig& config) {
  config.Validate();
  return config;
}
}  // namespace

SimulatedRobot::SimulatedRobot(const WorldMap& world, const SimConfig& config, const Pose2D& start)
    : config_(Validated(config)),
      motion_(world, config_.motion, start),
      renderer_(world, config_.scene, config_.camera),
      wheel_odometry_(config_.wheel_odometry) {}

void SimulatedRobot::Tick(SimFrame* frame) {
  const double dt = config_.motion.time_step_s;
  frame->motion = motion_.Step(dt);
  frame->index = next_frame_index_++;
  frame->time_s = frame->motion.time_s;
  frame->ground_truth = frame->motion.pose;
  frame->wheel_odometry = wheel_odometry_.Measure(frame->motion.distance_m, frame->motion.rotation_rad, dt);
  renderer_.Render(frame->ground_truth, frame->index, frame->image);
}

SimFrame SimulatedRobot::Tick() {
  SimFrame frame;
  Tick(&frame);
  return frame;
}

proto::SimulatedRobotState SimulatedRobot::SaveState() const {
  proto::SimulatedRobotState state;
  state.set_format_version(1);
  *state.mutable_motion() = motion_.SaveState();
  *state.mutable_wheel_odometry() = wheel_odometry_.SaveState();
  state.set_next_frame_index(next_frame_index_);
  return state;
}

void SimulatedRobot::LoadState(const proto::SimulatedRobotState& state) {
  if (state.format_version() != 1) {
    throw std::invalid_argument("SimulatedRobot::LoadState: unknown format_version " +
                                std::to_string(state.format_version()));
  }
  if (!state.has_motion() || !state.has_wheel_odometry()) {
    throw std::invalid_argument("SimulatedRobot::LoadState: motion or wheel_odometry state missing");
  }
  // Load into copies first so a bad part leaves this robot unchanged.
  const proto::RobotMotionState previous_motion = motion_.SaveState();
  motion_.LoadState(state.motion());
  try {
    wheel_odometry_.LoadState(state.wheel_odometry());
  } catch (...) {
    motion_.LoadState(previous_motion);
    throw;
  }
  next_frame_index_ = state.next_frame_index();
}

}  // namespace rslam::sim
