#pragma once
// A floor-boundary scan (the points where the floor meets obstacles, in a robot frame, in
// bearing order) and point-to-line ICP of another scan onto it, in the plane (x forward, y left,
// theta counter-clockwise).
//
// The floor odometry (floor_odometry.h) registers each frame to a key frame with it.
//
// Each point of the aligned scan pairs with the nearest reference point within
// max_pair_distance_m, the error is its distance to the line through that point and its bearing
// neighbours, and Gauss-Newton solves for (x, y, theta), pairs weighted by 1 / (r_a r_b)^2 (a
// camera row's floor footprint grows with r^2; relative to a point 1 m away). A pair whose
// reference point ends its line (or stands alone) is left out, as Turk & Levoy (1994) leave out
// pairs with a mesh's boundary: two views of a room overlap only in part, and a point the other
// view sees beyond the reference's last one (past its range, its field of view, a far wall's
// sparse samples) pairs with that last point although they are different places, pulling the
// motion short. Four recorded demo paths rendered again through the floor odometry: distance
// 0.892-0.922 -> 0.935-0.963 of the truth; the maps their pose cells made, replayed on it (see
// deploy/config/demo.yaml), are larger and closer to the truth. Priors, each
// scaled by the sum of pair weights so they mean the same for few or many points, hold the
// solution near a prior pose where the points say little: sideways (its left axis) and in turn.
//
// Pure and deterministic.

#include <Eigen/Core>

#include <span>
#include <vector>

namespace rslam::odometry {

// Floor-boundary points (bearing order) farther apart than this are not neighbours on one
// boundary line: the floor odometry's normals and the wall directions both split lines there.
constexpr double kBoundaryNeighbourMaxDistanceM = 0.12;

// Reference points with the unit normal of the boundary line at each.
struct BoundaryScan {
  std::vector<Eigen::Vector2d> points;
  std::vector<Eigen::Vector2d> normals;  // zero at a lone point
  std::vector<bool> ends_line;           // no neighbour on one side, or none at all: not paired

  // Normals and line ends from each point's bearing neighbours closer than
  // neighbour_max_distance_m.
  static BoundaryScan FromPoints(std::vector<Eigen::Vector2d> points,
                                 double neighbour_max_distance_m = kBoundaryNeighbourMaxDistanceM);
};

struct AlignmentOptions {
  double max_pair_distance_m = 0.10;
  int iterations = 12;
  int min_pairs = 12;
  double lateral_prior = 0.0;   // per unit pair weight, on the offset along the prior's left axis
  double rotation_prior = 0.0;  // per unit pair weight, on the turn away from the prior's
  // The alignment fails when the points constrain the prior's forward axis less than this per
  // unit pair weight (a corridor's parallel walls say nothing about motion along them); 0 = no check.
  double min_forward_constraint = 0.0;
};

struct Alignment {
  bool ok = false;
  Eigen::Vector3d pose = Eigen::Vector3d::Zero();  // the aligned scan's frame in the reference's
  int pairs = 0;                // of the last iteration
  double mean_residual2 = 0.0;  // weighted mean squared point-to-line distance (m^2)
};

// Aligns points (in their own frame) onto reference, starting from guess (their frame's pose in
// the reference frame), with the priors held at prior (which may differ from the starting guess:
// a constant-velocity seed starts the search, the measured turn holds it). Not ok when fewer than
// min_pairs pairs are found, the forward constraint is too weak, or the solve fails; pose then
// holds the last estimate.
Alignment AlignToScan(const BoundaryScan& reference, std::span<const Eigen::Vector2d> points,
                      const Eigen::Vector3d& guess, const Eigen::Vector3d& prior, const AlignmentOptions& options);

}  // namespace rslam::odometry
