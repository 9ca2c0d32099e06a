#pragma once
// The check every service makes of a frame's floor boundary (odometry/velocity's, carried on in
// pose_cells/action) before using it: a message failing it is counted, logged and dropped.

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "rslam/msg/odometry.h"

namespace rslam {

// One floor-boundary point per degree is 360; more than this is not a boundary.
inline constexpr std::size_t kMaxFloorBoundaryPoints = 4096;

// "" when the boundary is sound, else what is wrong with it.
inline std::string FloorBoundaryProblem(bool measured, const std::vector<msg::FloorPoint>& boundary) {
  if (boundary.size() > kMaxFloorBoundaryPoints)
    return "floor boundary of " + std::to_string(boundary.size()) + " points (at most " +
           std::to_string(kMaxFloorBoundaryPoints) + ")";
  if (!measured && !boundary.empty()) return "floor boundary points but boundary_measured is false";
  for (const msg::FloorPoint& p : boundary)
    if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m)) return "floor boundary has a non-finite point";
  return "";
}

}  // namespace rslam
