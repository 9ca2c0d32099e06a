// RegisterBoundaries (boundary_match.h) on floor-boundary scans cast in a small room.

#include "services/pose_cells/boundary_match.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace rslam::pose_cells {
namespace {

constexpr double kPi = std::numbers::pi;

struct Wall {
  Eigen::Vector2d a, b;
};

// What the floor odometry sees from pose (x, y, theta): one point per degree over 60 degrees,
// the nearest wall within 3 m, in the robot frame.
std::vector<Eigen::Vector2f> Scan(const std::vector<Wall>& walls, const Eigen::Vector3d& pose) {
  std::vector<Eigen::Vector2f> points;
  for (int deg = -30; deg <= 30; ++deg) {
    const double b = pose.z() + deg * kPi / 180.0;
    const Eigen::Vector2d o = pose.head<2>(), d(std::cos(b), std::sin(b));
    double range = 3.0;
    for (const Wall& w : walls) {
      const Eigen::Vector2d e = w.b - w.a;
      const double den = d.x() * e.y() - d.y() * e.x();
      if (std::abs(den) < 1e-12) continue;
      const Eigen::Vector2d ao = w.a - o;
      const double t = (ao.x() * e.y() - ao.y() * e.x()) / den;  // along the ray
      const double u = (ao.x() * d.y() - ao.y() * d.x()) / den;  // along the wall
      if (t > 0 && u >= 0 && u <= 1) range = std::min(range, t);
    }
    if (range < 3.0) points.emplace_back(static_cast<float>(range * std::cos(deg * kPi / 180.0)),
                                         static_cast<float>(range * std::sin(deg * kPi / 180.0)));
  }
  return points;
}

// A corridor 1.2 m wide along x with a door-sized gap on the left at x 2-3 and its end wall at
// x 4: which part of it a view shows depends on where along it the robot is (two parallel walls
// alone would not say where along them it is: views are taken where the end is in range).
const std::vector<Wall> kCorridor = {
    {{0, -0.6}, {4, -0.6}}, {{0, 0.6}, {2, 0.6}}, {{3, 0.6}, {4, 0.6}}, {{4, -0.6}, {4, 0.6}}};

TEST(RegisterBoundaries, FindsTheMotionBetweenTwoViewsOfOnePlace) {
  const Eigen::Vector3d stored_pose(2.2, 0.0, 0.0);
  for (const Eigen::Vector3d& motion : {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.3, 0.05, 0.05),
                                        Eigen::Vector3d(-0.5, -0.1, -0.1), Eigen::Vector3d(0.6, 0.0, 0.0)}) {
    const auto stored = Scan(kCorridor, stored_pose);
    const auto current = Scan(kCorridor, stored_pose + motion);
    ASSERT_GE(stored.size(), 20u);
    const BoundaryMatch m = RegisterBoundaries(stored, current);
    // Points 1 degree apart never coincide: point-to-point pairs leave a centimetre or two.
    EXPECT_LT(m.median_residual_m, 0.02) << motion.transpose();
    EXPECT_NEAR(m.pose.x(), motion.x(), 0.05) << motion.transpose();
    EXPECT_NEAR(m.pose.y(), motion.y(), 0.05) << motion.transpose();
    EXPECT_NEAR(m.pose.z(), motion.z(), 0.04) << motion.transpose();
    EXPECT_NEAR(m.offset_m(), motion.head<2>().norm(), 0.05);
  }
}

TEST(RegisterBoundaries, ViewsOfDifferentPlacesLeaveALargeResidual) {
  // The corridor's end seen from 1 m before it, and a hall's long wall 2.5 m ahead.
  const std::vector<Wall> hall = {{{2.5, -3}, {2.5, 3}}};
  const auto stored = Scan(kCorridor, {3.0, 0.0, 0.0});
  const auto current = Scan(hall, {0.0, 0.0, 0.0});
  ASSERT_GE(current.size(), 20u);
  EXPECT_GT(RegisterBoundaries(stored, current).median_residual_m, 0.05);
}

TEST(RegisterBoundaries, RefusesAnEmptyScan) {
  const auto stored = Scan(kCorridor, {1.0, 0.0, 0.0});
  EXPECT_THROW(RegisterBoundaries(stored, {}), std::invalid_argument);
  EXPECT_THROW(RegisterBoundaries({}, stored), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::pose_cells
