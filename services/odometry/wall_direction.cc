#include "services/odometry/wall_direction.h"

#include <cmath>

#include "common/math/angle.h"
#include "services/odometry/boundary_scan.h"

namespace rslam::odometry {

std::optional<double> WallDirection(std::span<const Eigen::Vector2d> boundary, const WallDirectionConfig& config) {
  const size_t k = static_cast<size_t>(config.baseline_points);
  QuarterTurnMean mean;
  double length = 0.0;
  for (size_t i = 0; i + k < boundary.size(); ++i) {
    if (boundary[i].norm() > config.max_range_m || boundary[i + k].norm() > config.max_range_m) continue;
    bool one_line = true;
    for (size_t j = i; j < i + k && one_line; ++j)
      one_line = (boundary[j + 1] - boundary[j]).norm() <= kBoundaryNeighbourMaxDistanceM;
    if (!one_line) continue;
    const Eigen::Vector2d d = boundary[i + k] - boundary[i];
    const double l = d.norm();
    if (l <= 0.0) continue;
    mean.Add(std::atan2(d.y(), d.x()), l);
    length += l;
  }
  // Overlapping pairs k bins apart count each stretch of wall k times.
  if (length / static_cast<double>(k) < config.min_wall_m || mean.Agreement() < config.min_agreement * length)
    return std::nullopt;
  return mean.Mean();
}

}  // namespace rslam::odometry
