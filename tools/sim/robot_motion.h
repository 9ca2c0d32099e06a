#pragma once
// The simulated robot's body: executes piece-wise linear motion commands (turns on the spot,
// straight moves, pirouettes of 12 x 30 degree turns as in paper 003) in fixed time steps,
// against the world map with a disc-shaped robot. A move that would hit a wall stops at the
// last collision-free pose and reports `blocked`. Turns on the spot never collide (a disc).

#include <cstdint>

#include "common/math/pose2d.h"
#include "tools/sim/proto/sim_state.pb.h"
#include "tools/sim/sim_config.h"
#include "tools/sim/world_map.h"

namespace rslam::sim {

struct MotionCommand {
  enum class Kind { kStop = 0, kRotate = 1, kMove = 2, kPirouette = 3 };  // as proto CommandKind
  Kind kind = Kind::kStop;
  double amount = 0.0;  // kRotate: radians (left positive); kMove: metres (negative = backwards)

  static MotionCommand Stop() { return {Kind::kStop, 0.0}; }
  static MotionCommand Rotate(double angle_rad) { return {Kind::kRotate, angle_rad}; }
  static MotionCommand Move(double distance_m) { return {Kind::kMove, distance_m}; }
  static MotionCommand Pirouette() { return {Kind::kPirouette, 0.0}; }
};

struct StepResult {
  Pose2D pose;                    // ground truth after the step
  double time_s = 0.0;            // simulated time after the step
  double distance_m = 0.0;        // signed distance driven in this step
  double rotation_rad = 0.0;      // rotation in this step (left positive)
  bool command_finished = false;  // the command ended in this step (done, or blocked)
  bool blocked = false;           // a move stopped short at a wall in this step
  bool idle = true;               // no command running after the step
  int pirouette_turns_done = 0;   // turns completed of the running (or just finished) pirouette
  bool pirouette_pausing = false; // standing still between pirouette turns: a frame to use
};

class RobotMotion {
 public:
  // The world must outlive this. Throws std::invalid_argument when the start pose is not finite
  // or the robot would overlap a wall there; ConfigError on a bad config.
  RobotMotion(const WorldMap& world, const MotionConfig& config, const Pose2D& start);
  RobotMotion(const RobotMotion&) = delete;
  RobotMotion& operator=(const RobotMotion&) = delete;

  // Replaces the running command (Stop ends it at once). Throws std::invalid_argument on a
  // non-finite amount.
  void Command(const MotionCommand& command);
  // Advances the simulation by dt seconds (default: the configured time step).
  StepResult Step();
  StepResult Step(double dt_s);

  const Pose2D& pose() const { return pose_; }
  double time_s() const { return time_s_; }
  bool busy() const { return command_.kind != MotionCommand::Kind::kStop; }
  const MotionConfig& config() const { return config_; }

  // The whole state (pose, time, running command), to save and restore.
  proto::RobotMotionState SaveState() const;
  // Throws std::invalid_argument (state unchanged) on an unknown version, non-finite numbers or
  // a pose where the robot overlaps a wall.
  void LoadState(const proto::RobotMotionState& state);

 private:
  // Turns toward target_heading_ for at most budget seconds; returns the time used.
  double Turn(double budget, double* remaining, StepResult* result);
  // Drives straight for at most budget seconds; returns the time used.
  double Drive(double budget, StepResult* result);

  const WorldMap& world_;
  const MotionConfig config_;
  Pose2D pose_;
  double time_s_ = 0.0;
  MotionCommand command_;
  double remaining_ = 0.0;        // of the running turn (rad, signed) or move (m, signed)
  double target_heading_ = 0.0;   // heading at the end of the running turn (no drift)
  int pirouette_turns_done_ = 0;
  double pause_remaining_s_ = 0.0;
};

}  // namespace rslam::sim
