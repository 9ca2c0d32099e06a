#pragma once
// A planar pose (metres, radians; theta counter-clockwise from +x) and its two compositions: the
// one pose type of the services and tools (saved as common/math/pose2d.proto).

#include <cmath>

#include "common/math/angle.h"

namespace rslam {

struct Pose2D {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

// a ⊕ b: b expressed in a's frame, returned in the frame a is expressed in.
inline Pose2D Compose(const Pose2D& a, const Pose2D& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, WrapAngle(a.theta + b.theta)};
}

// a⁻¹ ⊕ b: b expressed in a's frame.
inline Pose2D Between(const Pose2D& a, const Pose2D& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  const double dx = b.x - a.x, dy = b.y - a.y;
  return {c * dx + s * dy, -s * dx + c * dy, WrapAngle(b.theta - a.theta)};
}

inline bool IsFinite(const Pose2D& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}

}  // namespace rslam
