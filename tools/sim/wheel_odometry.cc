#include "tools/sim/wheel_odometry.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rslam::sim {

namespace {
const WheelOdometryConfig& Validated(const WheelOdometryConfig& config) {
  config.Validate();
  return config;
}
}  // namespace

WheelOdometry::WheelOdometry(const WheelOdometryConfig& config)
    : config_(Validated(config)), random_(SplitMix64(config.seed)) {}

WheelOdometryReading WheelOdometry::Measure(double true_distance_m, double true_rotation_rad, double dt_s) {
  if (!std::isfinite(true_distance_m) || !std::isfinite(true_rotation_rad) || !std::isfinite(dt_s)) {
    throw std::invalid_argument("WheelOdometry::Measure: non-finite input");
  }
  if (dt_s <= 0) throw std::invalid_argument("WheelOdometry::Measure: dt must be positive");
  const double sigma_distance = config_.translation_noise_per_m * std::abs(true_distance_m);
  const double sigma_rotation = config_.rotation_noise_per_rad * std::abs(true_rotation_rad) +
                                config_.rotation_noise_per_m * std::abs(true_distance_m);
  // Always draw both numbers so the noise sequence does not depend on which motions were zero.
  const double distance = true_distance_m + sigma_distance * random_.Gaussian();
  const double rotation = true_rotation_rad + sigma_rotation * random_.Gaussian();
  return WheelOdometryReading{distance / dt_s, rotation / dt_s, dt_s};
}

proto::WheelOdometryState WheelOdometry::SaveState() const {
  proto::WheelOdometryState state;
  state.set_format_version(1);
  state.set_rng_state(random_.state());
  return state;
}

void WheelOdometry::LoadState(const proto::WheelOdometryState& state) {
  if (state.format_version() != 1) {
    throw std::invalid_argument("WheelOdometry::LoadState: unknown format_version " +
                                std::to_string(state.format_version()));
  }
  random_.set_state(state.rng_state());
}

}  // namespace rslam::sim
