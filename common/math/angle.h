#pragma once
// Angles in radians wrapped to (-pi, pi]: the one helper the services, the simulator and the
// evaluation share. Angles already in range come back bit for bit (the experience map's sweeps
// rely on that to skip recomputing the trigonometry of settled links).

#include <cmath>
#include <numbers>

namespace rslam {

inline double WrapAngle(double a) {
  constexpr double kPi = std::numbers::pi;
  if (a > kPi || a <= -kPi) {
    a = std::remainder(a, 2.0 * kPi);
    if (a <= -kPi) a += 2.0 * kPi;
  }
  return a;
}

}  // namespace rslam
