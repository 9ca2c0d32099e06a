#pragma once
// Configuration of the odometry service (YAML section `odometry`): the visual odometry keys
// (VisualOdometryConfig, so deploy/presets/*.yaml work as they are) plus the node's own.

#include <cmath>
#include <cstdint>

#include "common/config/config_error.h"
#include "services/odometry/visual_odometry_config.h"

namespace rslam::odometry {

struct OdometryNodeConfig {
  VisualOdometryConfig visual;
  bool use_wheel_odometry = false;  // republish robot/wheel_odometry instead of visual odometry
  double max_frame_gap_s = 5.0;     // a larger stamp gap restarts the visual odometry
  int64_t max_pixels = 16'000'000;  // larger images are rejected

  template <class V>
  void VisitFields(V& v) {
    visual.VisitFields(v);
    v("use_wheel_odometry", use_wheel_odometry,
      "publish robot/wheel_odometry (header kept) as odometry/velocity instead of visual odometry");
    v("max_frame_gap_s", max_frame_gap_s,
      "a frame more than this after the previous one restarts the visual odometry (zero velocity, dt 0)");
    v("max_pixels", max_pixels, "images with more pixels are rejected");
  }

  void Validate() const {
    visual.Validate();
    Require(std::isfinite(max_frame_gap_s) && max_frame_gap_s > 0, "max_frame_gap_s", "must be positive");
    Require(max_pixels >= 1, "max_pixels", "must be >= 1");
  }
};

}  // namespace rslam::odometry
