// Point-to-line registration of floor-boundary scans (services/odometry/boundary_scan.h) on exact
// geometry: a room corner seen from two poses.

#include "services/odometry/boundary_scan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace rslam::odometry {
namespace {

// A corner of two walls (x = 2 and y = 1.2) seen from (x, y, theta): one point per degree over
// 60 degrees, in the viewer's frame.
std::vector<Eigen::Vector2d> CornerView(double x, double y, double theta) {
  std::vector<Eigen::Vector2d> out;
  for (int i = -30; i < 30; ++i) {
    const double bearing = (i + 0.5) * M_PI / 180.0, a = theta + bearing;
    const double c = std::cos(a), s = std::sin(a);
    double t = 1e9;
    if (c > 1e-9) t = std::min(t, (2.0 - x) / c);
    if (s > 1e-9) t = std::min(t, (1.2 - y) / s);
    out.emplace_back(t * std::cos(bearing), t * std::sin(bearing));
  }
  return out;
}

TEST(BoundaryScanTest, NormalsAreThoseOfTheWalls) {
  const BoundaryScan scan = BoundaryScan::FromPoints(CornerView(0.0, 0.0, 0.5));
  ASSERT_EQ(scan.normals.size(), scan.points.size());
  for (size_t i = 1; i + 1 < scan.points.size(); ++i) {
    const Eigen::Vector2d& p = scan.points[i];
    const Eigen::Vector2d& n = scan.normals[i];
    EXPECT_NEAR(n.norm(), 1.0, 1e-9);
    // On the x = 2 wall the normal is along x, on the y = 1.2 wall along y (rotated by -0.5
    // into the viewer's frame); the two points beside the corner mix both.
    const Eigen::Vector2d world_normal(std::cos(0.5) * n.x() - std::sin(0.5) * n.y(),
                                       std::sin(0.5) * n.x() + std::cos(0.5) * n.y());
    const Eigen::Vector2d world_point(std::cos(0.5) * p.x() - std::sin(0.5) * p.y(),
                                      std::sin(0.5) * p.x() + std::cos(0.5) * p.y());
    const bool near_corner = (world_point - Eigen::Vector2d(2.0, 1.2)).norm() < 0.12;
    if (near_corner) continue;
    const bool on_x_wall = std::abs(world_point.x() - 2.0) < 1e-9;
    EXPECT_NEAR(std::abs(on_x_wall ? world_normal.x() : world_normal.y()), 1.0, 1e-6) << i;
  }
}

TEST(BoundaryScanTest, MarksTheEndsOfEachLineAndLonePoints) {
  // A line of five points, a lone point, a line of three (neighbours within 0.12 m).
  const std::vector<Eigen::Vector2d> points = {{1.0, -0.1}, {1.0, -0.05}, {1.0, 0.0}, {1.0, 0.05}, {1.0, 0.1},
                                               {1.5, 0.6},  {2.0, 1.5},   {2.05, 1.5}, {2.1, 1.5}};
  const BoundaryScan scan = BoundaryScan::FromPoints(points);
  const std::vector<bool> ends = {true, false, false, false, true, true, true, false, true};
  EXPECT_EQ(scan.ends_line, ends);
  EXPECT_EQ(scan.normals[5], Eigen::Vector2d::Zero());  // the lone point has no line
  EXPECT_NEAR(std::abs(scan.normals[0].x()), 1.0, 1e-9);  // an end keeps its line's normal
  EXPECT_NEAR(std::abs(scan.normals[8].y()), 1.0, 1e-9);
}

// Driving 0.3 m towards a short wall (x = 2, |y| <= 0.3) with a far wall to the left (y = 1.2)
// sampled sparsely (0.2 m apart: a far boundary's image rows), where the reference view ends at
// range 2.6 m and the view from 0.3 m ahead reaches 0.3 m farther along the far wall.
std::vector<Eigen::Vector2d> ShortWallAndFarSamples(double x, double sample_phase) {
  std::vector<Eigen::Vector2d> out;
  for (double y = -0.3; y <= 0.3 + 1e-9; y += 0.02) out.emplace_back(2.0 - x, y);
  for (double wx = 1.4 + sample_phase; (Eigen::Vector2d(wx - x, 1.2)).norm() <= 2.6; wx += 0.2)
    out.emplace_back(wx - x, 1.2);
  return out;
}

TEST(BoundaryScanTest, PointsSeenBeyondTheReferencesLastOneDoNotPullTheMoveShort) {
  const BoundaryScan reference = BoundaryScan::FromPoints(ShortWallAndFarSamples(0.0, 0.0));
  const std::vector<Eigen::Vector2d> points = ShortWallAndFarSamples(0.3, 0.1);
  AlignmentOptions options;
  options.min_pairs = 6;
  options.iterations = 30;
  options.lateral_prior = 10.0;
  const Eigen::Vector3d prior(0.25, 0.0, 0.0);
  const Alignment a = AlignToScan(reference, points, prior, prior, options);
  ASSERT_TRUE(a.ok);
  EXPECT_NEAR(a.pose.x(), 0.3, 1e-3);
  EXPECT_NEAR(a.pose.y(), 0.0, 1e-3);
}

TEST(BoundaryScanTest, AlignsAShiftedAndTurnedViewOfACorner) {
  const BoundaryScan reference = BoundaryScan::FromPoints(CornerView(0.0, 0.0, 0.5));
  const Eigen::Vector3d truth(0.06, -0.03, 0.05);  // the second view's pose in the first's frame
  // Poses compose: world pose of the second view = (0, 0, 0.5) + R(0.5) truth.
  const double c = std::cos(0.5), s = std::sin(0.5);
  const std::vector<Eigen::Vector2d> points =
      CornerView(c * truth.x() - s * truth.y(), s * truth.x() + c * truth.y(), 0.5 + truth.z());
  AlignmentOptions options;
  options.max_pair_distance_m = 0.2;
  options.iterations = 30;
  const Alignment a = AlignToScan(reference, points, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), options);
  ASSERT_TRUE(a.ok);
  EXPECT_NEAR(a.pose.x(), truth.x(), 2e-3);
  EXPECT_NEAR(a.pose.y(), truth.y(), 2e-3);
  EXPECT_NEAR(a.pose.z(), truth.z(), 2e-3);
  EXPECT_LT(a.mean_residual2, 1e-4);
}

TEST(BoundaryScanTest, TheTurnPriorHoldsAtThePriorNotAtTheStartingGuess) {
  const BoundaryScan reference = BoundaryScan::FromPoints(CornerView(0.0, 0.0, 0.5));
  const std::vector<Eigen::Vector2d> points = CornerView(0.0, 0.0, 0.55);  // turned 0.05 in place
  AlignmentOptions options;
  options.max_pair_distance_m = 0.2;
  options.iterations = 30;
  options.rotation_prior = 1e6;  // the prior's turn is all that counts
  const Eigen::Vector3d guess(0.0, 0.0, 0.08), prior(0.0, 0.0, 0.03);
  const Alignment a = AlignToScan(reference, points, guess, prior, options);
  ASSERT_TRUE(a.ok);
  EXPECT_NEAR(a.pose.z(), 0.03, 1e-4);
}

TEST(BoundaryScanTest, TooFewPointsIsNotAnAlignment) {
  const BoundaryScan reference = BoundaryScan::FromPoints(CornerView(0.0, 0.0, 0.5));
  std::vector<Eigen::Vector2d> points = CornerView(0.0, 0.0, 0.5);
  points.resize(5);
  AlignmentOptions options;  // min_pairs 12
  EXPECT_FALSE(AlignToScan(reference, points, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), options).ok);
}

TEST(BoundaryScanTest, OneStraightWallLeavesTheForwardAxisToTheCheck) {
  // Looking along a wall (y = 1.2 only, facing +x): nothing constrains motion along x.
  std::vector<Eigen::Vector2d> wall;
  for (int i = 0; i < 40; ++i) wall.emplace_back(0.5 + 0.05 * i, 1.2);
  const BoundaryScan reference = BoundaryScan::FromPoints(wall);
  AlignmentOptions options;
  options.min_forward_constraint = 0.02;
  EXPECT_FALSE(AlignToScan(reference, wall, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), options).ok);
}

}  // namespace
}  // namespace rslam::odometry
