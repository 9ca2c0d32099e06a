#pragma once
// A planar pose in the world frame: metres and radians, theta counter-clockwise from +x.

#include <cmath>

#include "common/math/angle.h"

namespace rslam::sim {

struct Pose2D {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  bool IsFinite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(theta); }
};

}  // namespace rslam::sim
