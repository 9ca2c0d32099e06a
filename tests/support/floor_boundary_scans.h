#pragma once
// Floor boundaries as the odometry sends them (odometry/velocity's boundary): one point per
// degree over the camera's 60 degrees, the nearest wall within 3 m, robot frame (x forward,
// y left), metres. For the pose cells' floor-boundary check in tests.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace rslam::testing {

// A corner: a wall across 1.5 m ahead and one 0.8 m to the left, seen from forward_m along the
// way to it.
inline std::vector<Eigen::Vector2f> CornerScan(double forward_m = 0.0) {
  std::vector<Eigen::Vector2f> points;
  for (int deg = -30; deg <= 30; ++deg) {
    const double b = deg * std::numbers::pi / 180.0, c = std::cos(b), s = std::sin(b);
    double r = std::min(3.0, (1.5 - forward_m) / c);
    if (s > 0) r = std::min(r, 0.8 / s);
    if (r < 3.0) points.emplace_back(static_cast<float>(r * c), static_cast<float>(r * s));
  }
  return points;
}

// A corridor 1.2 m wide: walls 0.6 m either side, nothing across within 3 m.
inline std::vector<Eigen::Vector2f> CorridorScan() {
  std::vector<Eigen::Vector2f> points;
  for (int deg = -30; deg <= 30; ++deg) {
    const double b = deg * std::numbers::pi / 180.0;
    if (deg == 0) continue;
    const double r = 0.6 / std::abs(std::sin(b));
    if (r < 3.0) points.emplace_back(static_cast<float>(r * std::cos(b)), static_cast<float>(r * std::sin(b)));
  }
  return points;
}

}  // namespace rslam::testing
