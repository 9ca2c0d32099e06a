#include "tools/run/service_messages.h"

#include <cmath>

namespace rslam::run {

double PublishedRelativeAngle(double relative_angle_rad) {
  return std::isfinite(relative_angle_rad) ? relative_angle_rad : 0.0;
}

}  // namespace rslam::run
