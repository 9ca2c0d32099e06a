// RegisterBoundaries (boundary_match.h) on floor-boundary scans cast in a small room.

#include "services/pose_cells/boundary_match.h"

#include <gtest/gtest.h>

#include <algorithm>
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

// Two long parallel walls 1.2 m apart along x, as a floor boundary thinned to a few centimetres
// shows them: points every `spacing` metres from x0 to x1, starting `phase` in, each up to 2 cm
// off its wall (a fixed pattern per `seed`), in the frame of a robot standing at x = at.
std::vector<Eigen::Vector2f> PlainCorridor(double at, double x0, double x1, double spacing, double phase, unsigned seed) {
  std::vector<Eigen::Vector2f> points;
  unsigned state = seed;
  auto jitter = [&] {
    state = state * 1103515245u + 12345u;
    return 0.02 * (static_cast<double>((state >> 16) % 2001) / 1000.0 - 1.0);
  };
  for (const double wall : {-0.6, 0.6})
    for (double x = x0 + phase; x <= x1; x += spacing)
      points.emplace_back(static_cast<float>(x - at), static_cast<float>(wall + jitter()));
  return points;
}

TEST(RegisterBoundaries, AlongAPlainCorridorTheEndsStayApartAtResidualsAlike) {
  // Nothing but the two walls, the old visit's 8 m of them and 4 m seen now from 0.3 m further
  // along: the new points register about as well wherever along the corridor a start put them,
  // so the ends stay apart and only a guess from elsewhere (the views) says which is right.
  const auto stored = PlainCorridor(0.0, -4.0, 4.0, 0.03, 0.0, 1);
  const auto current = PlainCorridor(0.3, -1.7, 2.3, 0.03, 0.013, 2);
  const BoundaryMatch m = RegisterBoundaries(stored, current);
  double low = m.ends.front().pose.x(), high = low;
  for (const BoundaryMatch::End& end : m.ends) {
    EXPECT_LT(end.median_residual_m, 1.35 * m.median_residual_m);
    EXPECT_NEAR(end.pose.y(), 0.0, 0.02);  // across the corridor the walls fix it
    low = std::min(low, end.pose.x());
    high = std::max(high, end.pose.x());
  }
  EXPECT_GT(high - low, 1.0);
  EXPECT_NEAR(m.NearestAlike({0.3, 0.0}, 1.35).x(), 0.3, 0.15);
  EXPECT_NEAR(m.NearestAlike({-0.7, 0.0}, 1.35).x(), -0.7, 0.15);
  EXPECT_EQ(m.NearestAlike({-0.7, 0.0}, 0.0), m.pose.head<2>());  // below 1: the best
}

TEST(RegisterBoundaries, WhereTheWallsFixThePlaceTheNearestAlikeEndIsTheBest) {
  // The corridor's end and its door in view: the starts that do not reach the motion end with
  // a larger residual, and a guess 0.5 m off does not move the offset.
  const auto stored = Scan(kCorridor, {2.2, 0.0, 0.0});
  const auto current = Scan(kCorridor, {2.5, 0.05, 0.0});
  const BoundaryMatch m = RegisterBoundaries(stored, current);
  EXPECT_NEAR(m.pose.x(), 0.3, 0.05);
  for (const Eigen::Vector2d& guess : {Eigen::Vector2d(0.8, 0.0), Eigen::Vector2d(-0.2, 0.0)})
    EXPECT_NEAR((m.NearestAlike(guess, 1.35) - m.pose.head<2>()).norm(), 0.0, 0.05) << guess.transpose();
}

TEST(RegisterBoundaries, RefusesAnEmptyScan) {
  const auto stored = Scan(kCorridor, {1.0, 0.0, 0.0});
  EXPECT_THROW(RegisterBoundaries(stored, {}), std::invalid_argument);
  EXPECT_THROW(RegisterBoundaries({}, stored), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::pose_cells
