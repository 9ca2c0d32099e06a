#pragma once
// Registers two sets of floor-boundary points (where the floor meets the walls, paper 003) from a
// guess of their relative pose: the measurement of a scan link (experience_map.h,
// exp_scan_links), which ties two stretches of the map that see the same walls.
//
// Point-to-line ICP (Censi, "An ICP variant using a point-to-line metric", ICRA 2008, without
// its closed form): each source point pairs with the nearest target point within the pairing
// distance, whose line is the target's local direction (principal axis of its neighbours within
// 2 x cell); Gauss-Newton on (x, y, theta) minimises the pairs' distances along the line normals.
// The pairing distance starts at max_pair_m and shrinks to three times the pairs' median distance
// (at least min_pair_m), so the far pairs of a first guess pull only while they must.
//
// What the pairs measure of the pose is `information`: sum of J^T J / pairs at the last step, J
// the derivative of a pair's distance along its normal n by (x, y, theta), in the target frame.
// A wall seen alone fixes the position across it, not along it: the position block (`walls()`,
// the scatter of the normals; eigenvalues summing to 1) is diag(0, 1) for one straight wall along
// x, I / 2 when the walls face every way. The turn entries are lever arms (m, m^2): the arc of a
// round table registers as well turned about its centre, and leaves that motion, a turn with the
// position that goes with it, unmeasured (the matrix singular along it), where a corner fixes it.
//
// Pure and deterministic.

#include <Eigen/Core>

#include <optional>
#include <span>

#include "common/math/pose2d.h"

namespace rslam::experience_map {

struct ScanRegistrationOptions {
  double cell_m = 0.03;      // the points' spacing (they are thinned to one per cell of this size)
  double max_pair_m = 0.3;   // pairing distance of the first step
  double min_pair_m = 0.06;  // ... never below this
  int iterations = 20;
};

struct ScanRegistration {
  Pose2D pose;                     // the source frame in the target frame
  int pairs = 0;                   // at the last step
  double median_distance_m = 0.0;  // of the pairs' points at the last step
  double inlier_share = 0.0;       // source points within 2 x cell_m of a target point
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();  // see above
  Eigen::Matrix2d walls() const { return information.topLeftCorner<2, 2>(); }
  double weak_share() const;       // the smaller eigenvalue of walls(): 0 (one wall) to 0.5
};

// nullopt when either set has fewer than 3 points or no step finds 3 pairs.
std::optional<ScanRegistration> RegisterScans(std::span<const Eigen::Vector2f> target,
                                              std::span<const Eigen::Vector2f> source, const Pose2D& initial,
                                              const ScanRegistrationOptions& options = {});

}  // namespace rslam::experience_map
