#include "tools/eval/trajectory_alignment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace rslam::eval {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

std::vector<StampedPose2D> Lissajous(int count) {
  std::vector<StampedPose2D> poses;
  for (int k = 0; k < count; ++k) {
    const double t = 0.1 * k;
    poses.push_back({k * kSecond / 10, 3.0 * std::sin(t), 2.0 * std::sin(2 * t + 0.3), std::fmod(0.2 * t, 1.0)});
  }
  return poses;
}

// truth = s R(angle) p + t, theta + angle.
std::vector<StampedPose2D> Transformed(const std::vector<StampedPose2D>& poses, double s, double angle, double tx,
                                       double ty) {
  std::vector<StampedPose2D> out;
  for (const auto& p : poses) {
    out.push_back({p.stamp_ns, s * (std::cos(angle) * p.x - std::sin(angle) * p.y) + tx,
                   s * (std::sin(angle) * p.x + std::cos(angle) * p.y) + ty, *p.theta + angle});
  }
  return out;
}

TEST(TrajectoryAlignment, RecoversAKnownSimilarityTransformExactly) {
  const auto estimate = Lissajous(100);
  const auto truth = Transformed(estimate, 2.5, 0.7, -4.0, 10.0);
  const TrajectoryError error = AlignAndCompare(estimate, truth, true);
  EXPECT_EQ(error.pairs, 100u);
  EXPECT_NEAR(error.ate_m, 0.0, 1e-9);
  EXPECT_NEAR(error.scale, 2.5, 1e-12);
  EXPECT_NEAR(error.rotation_rad, 0.7, 1e-12);
  EXPECT_NEAR(error.translation_x, -4.0, 1e-9);
  EXPECT_NEAR(error.translation_y, 10.0, 1e-9);
  ASSERT_TRUE(error.heading_rms_rad.has_value());
  EXPECT_NEAR(*error.heading_rms_rad, 0.0, 1e-9);
}

TEST(TrajectoryAlignment, WithoutScaleAScaledEstimateKeepsItsError) {
  const auto estimate = Lissajous(100);
  const auto truth = Transformed(estimate, 2.0, -1.2, 1.0, 1.0);
  const TrajectoryError rigid = AlignAndCompare(estimate, truth, false);
  EXPECT_DOUBLE_EQ(rigid.scale, 1.0);
  EXPECT_NEAR(rigid.rotation_rad, -1.2, 1e-9);
  EXPECT_GT(rigid.ate_m, 0.5);
  EXPECT_NEAR(AlignAndCompare(truth, truth, false).ate_m, 0.0, 1e-12);
}

TEST(TrajectoryAlignment, OffsetNoiseGivesItsRms) {
  // Truth = estimate plus 0.1 m across a straight line in the pattern +,-,-,+: the offsets cancel
  // in the mean and in their correlation with x, so the best alignment is the identity and
  // ATE = 0.1 exactly.
  std::vector<StampedPose2D> estimate, truth;
  for (int k = 0; k < 200; ++k) {
    estimate.push_back({k * kSecond, 0.5 * k, 0.0, std::nullopt});
    truth.push_back({k * kSecond, 0.5 * k, (k % 4 == 0 || k % 4 == 3 ? 0.1 : -0.1), std::nullopt});
  }
  const TrajectoryError error = AlignAndCompare(estimate, truth, false);
  EXPECT_NEAR(error.ate_m, 0.1, 1e-9);
  EXPECT_NEAR(error.max_error_m, 0.1, 1e-9);
  EXPECT_FALSE(error.heading_rms_rad.has_value());
}

TEST(TrajectoryAlignment, AssociatesByNearestStampWithinTheGap) {
  const auto truth = Lissajous(50);
  std::vector<StampedPose2D> estimate = truth;
  for (auto& p : estimate) p.stamp_ns += 3'000'000;  // 3 ms late
  estimate.push_back({truth.back().stamp_ns + kSecond, 0, 0, 0.0});  // nothing near it
  const TrajectoryError error = AlignAndCompare(estimate, truth, true, std::chrono::milliseconds(5));
  EXPECT_EQ(error.pairs, 50u);
  EXPECT_EQ(error.unmatched, 1u);
  EXPECT_NEAR(error.ate_m, 0.0, 1e-9);
  EXPECT_THROW(AlignAndCompare(estimate, truth, true, Duration(0)), std::invalid_argument);
}

TEST(TrajectoryAlignment, RejectsBadTrajectories) {
  auto poses = Lissajous(10);
  auto unordered = poses;
  std::swap(unordered[3], unordered[4]);
  EXPECT_THROW(AlignAndCompare(unordered, poses, true), std::invalid_argument);
  auto with_nan = poses;
  with_nan[2].x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(AlignAndCompare(poses, with_nan, true), std::invalid_argument);
  std::vector<StampedPose2D> one_point;
  for (const auto& p : poses) one_point.push_back({p.stamp_ns, 1.0, 1.0, std::nullopt});
  EXPECT_THROW(AlignAndCompare(one_point, poses, true), std::invalid_argument);
  EXPECT_THROW(AlignAndCompare(std::span<const StampedPose2D>(poses).first(1), poses, true), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::eval
