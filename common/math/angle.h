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

// The mean of directions taken modulo pi/2 (a building's two wall axes): each counts as four times
// its angle on the circle, weighted. Mean() is in (-pi/4, pi/4]; Agreement() is the weight when
// every direction agrees and falls towards 0 as they scatter.
struct QuarterTurnMean {
  double sum_cos = 0.0;
  double sum_sin = 0.0;
  void Add(double angle, double weight = 1.0) {
    sum_cos += weight * std::cos(4.0 * angle);
    sum_sin += weight * std::sin(4.0 * angle);
  }
  double Mean() const { return std::atan2(sum_sin, sum_cos) / 4.0; }
  double Agreement() const { return std::hypot(sum_cos, sum_sin); }
};

}  // namespace rslam
