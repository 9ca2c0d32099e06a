#pragma once
// Registers two floor-boundary scans of what is claimed to be one place (a view the pose cells
// are about to link to an old experience, and the view that experience was made at) and says
// whether they show the same walls from nearby: the check of exp_boundary_check
// (pose_cell_config.h).
//
// Point-to-point ICP in the plane (x forward, y left): each point of the current scan pairs
// with the nearest stored point; pairs within max(2.5 x the median pair distance, 5 cm) give the
// closed-form rigid update. It starts from five offsets along the robot's forward axis (-0.8 to
// 0.8 m: two views of one place are mostly taken driving the same corridor, at different points
// of it) and keeps the one that ends with the smallest median pair distance; all five ends are kept.
//
// Why this and not the views alone: sixteen recorded demo runs' views and odometry replayed
// through the pose cells (session 14): the wrong links look like right ones to the views and the
// pose cells (template difference 0.0329 vs 0.0312, pose-cell distance alike), while "median
// residual under 0.05 m at an offset under 0.7 m" kept 1,218 of 1,379 right links to places
// more than 500 frames old and 8 of 45 wrong ones.
//
// Pure and deterministic; about 60 x 60 x 20 x 5 distance evaluations for two 60-point scans.

#include <Eigen/Core>

#include <array>
#include <span>

namespace rslam::pose_cells {

struct BoundaryMatch {
  double median_residual_m = 0.0;  // median distance of the current points to their nearest stored one
  Eigen::Vector3d pose = Eigen::Vector3d::Zero();  // the current scan's frame in the stored one's (x, y, theta)
  // Where each start ended, with its median residual. Walls along the robot's way (a corridor)
  // do not fix the place along them: each start then ends about where it began, at residuals
  // alike, and the best of them is the one whose few openings happen to fit.
  struct End {
    Eigen::Vector3d pose = Eigen::Vector3d::Zero();
    double median_residual_m = 0.0;
  };
  std::array<End, 5> ends{};
  double offset_m() const { return pose.head<2>().norm(); }
  // Of the ends whose median residual is at most `alike` times the best's, the position nearest
  // `guess` (the best's when `alike` is below 1).
  Eigen::Vector2d NearestAlike(const Eigen::Vector2d& guess, double alike) const;
};

// Requires both scans non-empty (std::invalid_argument otherwise).
BoundaryMatch RegisterBoundaries(std::span<const Eigen::Vector2f> stored, std::span<const Eigen::Vector2f> current);

}  // namespace rslam::pose_cells
