#pragma once
// Simulated wheel odometry: the true motion of a step, measured with Gaussian noise whose
// standard deviation is proportional to the motion (a robot standing still reads exactly zero):
//   sigma_distance = translation_noise_per_m * |d|
//   sigma_rotation = rotation_noise_per_rad * |r| + rotation_noise_per_m * |d|
// Reported as the velocities the odometry topic carries (vtrans, vrot over dt). Deterministic
// for a seed; the generator state can be saved and restored.

#include <cstdint>

#include "tools/sim/deterministic_random.h"
#include "tools/sim/proto/sim_state.pb.h"
#include "tools/sim/sim_config.h"

namespace rslam::sim {

struct WheelOdometryReading {
  double vtrans_mps = 0.0;
  double vrot_radps = 0.0;
  double dt_s = 0.0;
};

class WheelOdometry {
 public:
  explicit WheelOdometry(const WheelOdometryConfig& config);

  // true_distance_m and true_rotation_rad: the ground-truth motion during dt_s (> 0).
  // Throws std::invalid_argument on non-finite input or dt_s <= 0.
  WheelOdometryReading Measure(double true_distance_m, double true_rotation_rad, double dt_s);

  uint64_t rng_state() const { return random_.state(); }
  void set_rng_state(uint64_t state) { random_.set_state(state); }

  proto::WheelOdometryState SaveState() const;
  // Throws std::invalid_argument on an unknown format_version.
  void LoadState(const proto::WheelOdometryState& state);

 private:
  const WheelOdometryConfig config_;
  DeterministicRandom random_;
};

}  // namespace rslam::sim
