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

// Walls as segments (x0, y0, x1, y1), world frame, metres.
struct Wall {
  double x0, y0, x1, y1;
};

// What a robot at (x, y) facing theta sees of the walls: the nearest along each degree's ray.
inline std::vector<Eigen::Vector2f> ScanOfWalls(const std::vector<Wall>& walls, double x, double y, double theta) {
  std::vector<Eigen::Vector2f> points;
  for (int deg = -30; deg <= 30; ++deg) {
    const double b = deg * std::numbers::pi / 180.0, dx = std::cos(theta + b), dy = std::sin(theta + b);
    double r = 3.0;
    for (const Wall& w : walls) {
      // x + t d = p0 + u (p1 - p0), t > 0, 0 <= u <= 1.
      const double ex = w.x1 - w.x0, ey = w.y1 - w.y0, den = dx * ey - dy * ex;
      if (std::abs(den) < 1e-12) continue;
      const double t = ((w.x0 - x) * ey - (w.y0 - y) * ex) / den;
      const double u = ((w.x0 - x) * dy - (w.y0 - y) * dx) / den;
      if (t > 0 && u >= 0 && u <= 1) r = std::min(r, t);
    }
    if (r < 3.0) points.emplace_back(static_cast<float>(r * std::cos(b)), static_cast<float>(r * std::sin(b)));
  }
  return points;
}

}  // namespace rslam::testing
