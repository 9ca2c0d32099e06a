#include "tools/sim/robot_motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rslam::sim {

namespace {
constexpr double kTimeEpsilon = 1e-12;

const MotionConfig& Validated(const MotionConfig& config) {
  config.Validate();
  return config;
}
}  // namespace

RobotMotion::RobotMotion(const WorldMap& world, const MotionConfig& config, const Pose2D& start)
    : world_(world), config_(Validated(config)), pose_(start) {
  if (!IsFinite(start)) throw std::invalid_argument("RobotMotion: start pose must be finite");
  if (!world_.IsDiscFree(Eigen::Vector2d(start.x, start.y), config_.robot_radius_m)) {
    throw std::invalid_argument("RobotMotion: the robot overlaps a wall at the start pose");
  }
  pose_.theta = WrapAngle(start.theta);
}

void RobotMotion::Command(const MotionCommand& command) {
  if (!std::isfinite(command.amount)) throw std::invalid_argument("RobotMotion::Command: non-finite amount");
  command_ = command;
  pirouette_turns_done_ = 0;
  pause_remaining_s_ = 0.0;
  switch (command.kind) {
    case MotionCommand::Kind::kStop:
      remaining_ = 0.0;
      break;
    case MotionCommand::Kind::kRotate:
      remaining_ = command.amount;
      target_heading_ = pose_.theta + command.amount;
      break;
    case MotionCommand::Kind::kMove:
      remaining_ = command.amount;
      break;
    case MotionCommand::Kind::kPirouette:
      remaining_ = config_.pirouette_turn_rad;
      target_heading_ = pose_.theta + config_.pirouette_turn_rad;
      break;
  }
}

StepResult RobotMotion::Step() { return Step(config_.time_step_s); }

double RobotMotion::Turn(double budget, double* remaining, StepResult* result) {
  const double needed = std::abs(*remaining) / config_.angular_speed_radps;
  if (needed <= budget) {
    const double delta = WrapAngle(target_heading_ - pose_.theta);
    pose_.theta = WrapAngle(target_heading_);  // land exactly on the target heading
    result->rotation_rad += delta;
    *remaining = 0.0;
    return needed;
  }
  const double delta = std::copysign(config_.angular_speed_radps * budget, *remaining);
  pose_.theta = WrapAngle(pose_.theta + delta);
  result->rotation_rad += delta;
  *remaining -= delta;
  return budget;
}

double RobotMotion::Drive(double budget, StepResult* result) {
  const double step = std::min(std::abs(remaining_), config_.linear_speed_mps * budget);
  const double sign = remaining_ >= 0 ? 1.0 : -1.0;
  const Eigen::Vector2d start(pose_.x, pose_.y);
  const Eigen::Vector2d dir(sign * std::cos(pose_.theta), sign * std::sin(pose_.theta));
  // Sub-steps of a quarter cell so no wall cell is jumped over.
  const int sub_steps = std::max(1, static_cast<int>(std::ceil(step / (0.25 * world_.resolution()))));
  double safe = 0.0;
  bool blocked = false;
  for (int i = 1; i <= sub_steps; ++i) {
    const double d = step * i / sub_steps;
    if (!world_.IsDiscFree(start + d * dir, config_.robot_radius_m)) {
      // Refine the contact between the last safe and the first colliding sub-step.
      double lo = safe, hi = d;
      for (int k = 0; k < 20; ++k) {
        const double mid = 0.5 * (lo + hi);
        (world_.IsDiscFree(start + mid * dir, config_.robot_radius_m) ? lo : hi) = mid;
      }
      safe = lo;
      blocked = true;
      break;
    }
    safe = d;
  }
  const Eigen::Vector2d end = start + safe * dir;
  pose_.x = end.x();
  pose_.y = end.y();
  result->distance_m += sign * safe;
  if (blocked) {
    result->blocked = true;
    remaining_ = 0.0;
    return budget;  // the robot pushes against the wall for the rest of the step
  }
  remaining_ -= sign * safe;
  if (std::abs(remaining_) < 1e-12) remaining_ = 0.0;
  return step >= config_.linear_speed_mps * budget - kTimeEpsilon ? budget
                                                                  : step / config_.linear_speed_mps;
}

StepResult RobotMotion::Step(double dt_s) {
  if (!std::isfinite(dt_s) || dt_s < 0) throw std::invalid_argument("RobotMotion::Step: dt must be finite and >= 0");
  StepResult result;
  double budget = dt_s;
  while (budget > kTimeEpsilon && busy()) {
    switch (command_.kind) {
      case MotionCommand::Kind::kStop:
        break;
      case MotionCommand::Kind::kRotate:
        budget -= Turn(budget, &remaining_, &result);
        if (remaining_ == 0.0) {
          command_ = MotionCommand::Stop();
          result.command_finished = true;
        }
        break;
      case MotionCommand::Kind::kMove:
        budget -= Drive(budget, &result);
        if (remaining_ == 0.0) {
          command_ = MotionCommand::Stop();
          result.command_finished = true;
        }
        break;
      case MotionCommand::Kind::kPirouette:
        if (pause_remaining_s_ > 0) {
          const double used = std::min(budget, pause_remaining_s_);
          pause_remaining_s_ -= used;
          budget -= used;
          result.pirouette_pausing = true;
          if (pause_remaining_s_ <= kTimeEpsilon) {
            pause_remaining_s_ = 0.0;
            if (pirouette_turns_done_ >= config_.pirouette_turns) {
              command_ = MotionCommand::Stop();
              result.command_finished = true;
            } else {
              remaining_ = config_.pirouette_turn_rad;
              target_heading_ = pose_.theta + config_.pirouette_turn_rad;
            }
          }
          break;
        }
        budget -= Turn(budget, &remaining_, &result);
        if (remaining_ == 0.0) {
          ++pirouette_turns_done_;
          pause_remaining_s_ = config_.pirouette_pause_s;
          if (pause_remaining_s_ <= 0) {
            if (pirouette_turns_done_ >= config_.pirouette_turns) {
              command_ = MotionCommand::Stop();
              result.command_finished = true;
            } else {
              remaining_ = config_.pirouette_turn_rad;
              target_heading_ = pose_.theta + config_.pirouette_turn_rad;
            }
          }
        }
        break;
    }
  }
  result.pirouette_turns_done = pirouette_turns_done_;
  time_s_ += dt_s;
  result.time_s = time_s_;
  result.pose = pose_;
  result.idle = !busy();
  return result;
}

proto::RobotMotionState RobotMotion::SaveState() const {
  proto::RobotMotionState state;
  state.set_format_version(1);
  state.set_x(pose_.x);
  state.set_y(pose_.y);
  state.set_theta(pose_.theta);
  state.set_time_s(time_s_);
  state.set_command_kind(static_cast<proto::RobotMotionState::CommandKind>(command_.kind));
  state.set_command_amount(command_.amount);
  state.set_remaining(remaining_);
  state.set_target_heading(target_heading_);
  state.set_pirouette_turns_done(pirouette_turns_done_);
  state.set_pause_remaining_s(pause_remaining_s_);
  return state;
}

void RobotMotion::LoadState(const proto::RobotMotionState& state) {
  if (state.format_version() != 1) {
    throw std::invalid_argument("RobotMotion::LoadState: unknown format_version " +
                                std::to_string(state.format_version()));
  }
  for (double v : {state.x(), state.y(), state.theta(), state.time_s(), state.command_amount(), state.remaining(),
                   state.target_heading(), state.pause_remaining_s()}) {
    if (!std::isfinite(v)) throw std::invalid_argument("RobotMotion::LoadState: non-finite value");
  }
  if (state.pirouette_turns_done() < 0 || state.pause_remaining_s() < 0 || state.time_s() < 0) {
    throw std::invalid_argument("RobotMotion::LoadState: negative turns, pause or time");
  }
  if (!proto::RobotMotionState::CommandKind_IsValid(state.command_kind())) {
    throw std::invalid_argument("RobotMotion::LoadState: unknown command kind");
  }
  if (!world_.IsDiscFree(Eigen::Vector2d(state.x(), state.y()), config_.robot_radius_m)) {
    throw std::invalid_argument("RobotMotion::LoadState: the robot overlaps a wall at the saved pose");
  }
  pose_ = Pose2D{state.x(), state.y(), WrapAngle(state.theta())};
  time_s_ = state.time_s();
  command_ = MotionCommand{static_cast<MotionCommand::Kind>(state.command_kind()), state.command_amount()};
  remaining_ = state.remaining();
  target_heading_ = state.target_heading();
  pirouette_turns_done_ = state.pirouette_turns_done();
  pause_remaining_s_ = state.pause_remaining_s();
}

}  // namespace rslam::sim
