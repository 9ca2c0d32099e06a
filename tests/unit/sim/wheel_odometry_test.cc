#include "tools/sim/wheel_odometry.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rslam::sim {
namespace {

TEST(WheelOdometryTest, NoiseIsGaussianWithTheConfiguredSpread) {
  WheelOdometryConfig config;
  config.translation_noise_per_m = 0.05;
  config.rotation_noise_per_rad = 0.1;
  config.rotation_noise_per_m = 0.02;
  WheelOdometry odometry(config);
  const double d = 0.2, r = 0.05, dt = 0.1;
  const int n = 20000;
  double sum_d = 0, sum_d2 = 0, sum_r = 0, sum_r2 = 0;
  int within_one_sigma = 0;
  const double sigma_d = 0.05 * d, sigma_r = 0.1 * r + 0.02 * d;
  for (int i = 0; i < n; ++i) {
    const WheelOdometryReading reading = odometry.Measure(d, r, dt);
    EXPECT_EQ(reading.dt_s, dt);
    const double ed = reading.vtrans_mps * dt - d, er = reading.vrot_radps * dt - r;
    sum_d += ed;
    sum_d2 += ed * ed;
    sum_r += er;
    sum_r2 += er * er;
    within_one_sigma += std::abs(ed) < sigma_d;
  }
  EXPECT_NEAR(sum_d / n, 0.0, 4 * sigma_d / std::sqrt(n));
  EXPECT_NEAR(sum_r / n, 0.0, 4 * sigma_r / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sum_d2 / n), sigma_d, 0.03 * sigma_d);
  EXPECT_NEAR(std::sqrt(sum_r2 / n), sigma_r, 0.03 * sigma_r);
  EXPECT_NEAR(static_cast<double>(within_one_sigma) / n, 0.6827, 0.015);  // Gaussian, not uniform
}

TEST(WheelOdometryTest, StandingStillReadsExactlyZero) {
  WheelOdometry odometry(WheelOdometryConfig{});
  for (int i = 0; i < 100; ++i) {
    const WheelOdometryReading reading = odometry.Measure(0.0, 0.0, 0.1);
    EXPECT_EQ(reading.vtrans_mps, 0.0);
    EXPECT_EQ(reading.vrot_radps, 0.0);
  }
}

TEST(WheelOdometryTest, SameSeedGivesTheSameReadingsAndStateRestores) {
  WheelOdometryConfig config;
  WheelOdometry a(config), b(config);
  config.seed += 1;
  WheelOdometry other(config);
  bool any_differs = false;
  for (int i = 0; i < 50; ++i) {
    const auto ra = a.Measure(0.1, 0.02, 0.1), rb = b.Measure(0.1, 0.02, 0.1), ro = other.Measure(0.1, 0.02, 0.1);
    EXPECT_EQ(ra.vtrans_mps, rb.vtrans_mps);
    EXPECT_EQ(ra.vrot_radps, rb.vrot_radps);
    any_differs |= ra.vtrans_mps != ro.vtrans_mps;
  }
  EXPECT_TRUE(any_differs);
  const uint64_t saved = a.rng_state();
  const auto next = a.Measure(0.1, 0.0, 0.1);
  a.set_rng_state(saved);
  EXPECT_EQ(a.Measure(0.1, 0.0, 0.1).vtrans_mps, next.vtrans_mps);
}

TEST(WheelOdometryTest, RefusesBadInput) {
  WheelOdometry odometry(WheelOdometryConfig{});
  EXPECT_THROW(odometry.Measure(NAN, 0, 0.1), std::invalid_argument);
  EXPECT_THROW(odometry.Measure(0, INFINITY, 0.1), std::invalid_argument);
  EXPECT_THROW(odometry.Measure(0, 0, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::sim

namespace rslam::sim {
namespace {

TEST(WheelOdometryTest, SavedStateContinuesTheSameNoise) {
  WheelOdometry a{WheelOdometryConfig{}};
  a.Measure(0.1, 0.1, 0.1);
  const proto::WheelOdometryState saved = a.SaveState();
  const double next = a.Measure(0.1, 0.1, 0.1).vrot_radps;
  WheelOdometry b{WheelOdometryConfig{}};
  b.LoadState(saved);
  EXPECT_EQ(b.Measure(0.1, 0.1, 0.1).vrot_radps, next);
  proto::WheelOdometryState bad = saved;
  bad.set_format_version(0);
  EXPECT_THROW(b.LoadState(bad), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::sim
