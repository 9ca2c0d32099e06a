#pragma once
// A planar pose in the world frame: metres and radians, theta counter-clockwise from +x.

#include <cmath>

namespace rslam::sim {

struct Pose2D {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  bool IsFinite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(theta); }
};

// Wraps an angle to (-pi, pi].
inline double WrapAngle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

}  // namespace rslam::sim
