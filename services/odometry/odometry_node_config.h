#pragma once
// Configuration of the odometry service (YAML section `odometry`): the visual odometry keys
// (VisualOdometryConfig, so deploy/presets/*.yaml work as they are) plus the node's own.

#include <cmath>
#include <cstdint>
#include <cstdio>

#include "common/config/config_error.h"
#include "services/occupancy/obstacle_profile_pipeline.h"
#include "services/odometry/floor_odometry.h"
#include "services/odometry/wall_direction.h"
#include "services/odometry/visual_odometry_config.h"

namespace rslam::odometry {

// Metric translation (and rotation) from the floor boundary (floor_odometry.h). The camera and
// floor keys are those of the occupancy service's section, so one YAML anchor can serve both.
struct FloorOdometryNodeConfig {
  bool enabled = false;
  // A frame the column profiles call a turn on the spot (|vrot| >= turn_in_place_vrot_radps)
  // keeps their motion: replayed along a 1,900 s demo path, the registration summed turns 0.6%
  // short (-5.0 rad over 794 rad turned) and 51 m of forward motion in place, the profiles
  // -0.36 rad and none.
  bool turns_from_profiles = true;
  // A frame whose speed profile differs from the previous one's by more than this (the
  // speed_difference of visual_odometry.h) shows a moving camera even when the difference is
  // below the speed's noise floor (vtrans 0): the floor odometry then takes it as moving
  // (FloorOdometry::Update's camera_moves). 0 = only a speed says the camera moves.
  double moving_difference = 0.0;
  // Hysteresis: a frame right after one taken as moving stays moving while its difference is
  // above this lower threshold (0 = moving_difference alone). Driving past a plain wall, single
  // frames' differences dip under moving_difference (on four demo paths 74-89 moving frames a run,
  // 1.7-2.1 m, most of them between two moving frames), while a standing camera's stay under it
  // (99.9% of 6,900 standing frames under 0.00059).
  double moving_difference_hold = 0.0;
  occupancy::ObstacleProfileConfig boundary;
  FloorOdometryConfig registration;
  WallDirectionConfig wall_direction;

  template <class V>
  void VisitFields(V& v) {
    v("enabled", enabled, "register floor-boundary points for metric motion (needs bgr8 images)");
    v("turns_from_profiles", turns_from_profiles,
      "frames the column profiles call a turn on the spot keep the profiles' motion");
    v("moving_difference", moving_difference,
      "speed-profile difference above which a frame with no readable speed is taken as moving (0 = off)");
    v("moving_difference_hold", moving_difference_hold,
      "lower difference that keeps a frame right after a moving one moving (0 = moving_difference alone)");
    boundary.VisitFields(v);
    registration.VisitFields(v);
    v("wall_direction", wall_direction,
      "each frame's wall direction modulo 90 degrees, published for the experience map (wall_direction.h)");
  }
  void Validate() const {
    if (!enabled) return;
    Require(moving_difference >= 0, "moving_difference", "must be >= 0");
    Require(moving_difference_hold >= 0 && moving_difference_hold <= moving_difference, "moving_difference_hold",
            "must be >= 0 and at most moving_difference");
    boundary.Validate();
    registration.Validate();
    ValidateNested(wall_direction, "wall_direction");
  }
};

struct OdometryNodeConfig {
  VisualOdometryConfig visual;
  bool use_wheel_odometry = false;  // republish robot/wheel_odometry instead of visual odometry
  double max_frame_gap_s = 5.0;     // a larger stamp gap restarts the visual odometry
  int64_t max_pixels = 16'000'000;  // larger images are rejected
  FloorOdometryNodeConfig floor;

  template <class V>
  void VisitFields(V& v) {
    visual.VisitFields(v);
    v("use_wheel_odometry", use_wheel_odometry,
      "publish robot/wheel_odometry (header kept) as odometry/velocity instead of visual odometry");
    v("max_frame_gap_s", max_frame_gap_s,
      "a frame more than this after the previous one restarts the visual odometry (zero velocity, dt 0)");
    v("max_pixels", max_pixels, "images with more pixels are rejected");
    v("floor_odometry", floor, "metric odometry from the floor boundary (camera of known height over a flat floor)");
  }

  void Validate() const {
    visual.Validate();
    Require(std::isfinite(max_frame_gap_s) && max_frame_gap_s > 0, "max_frame_gap_s", "must be positive");
    Require(max_pixels >= 1, "max_pixels", "must be >= 1");
    ValidateNested(floor, "floor_odometry");
    // One camera: with the floor odometry on, the column profiles turn pixels into radians over the
    // field of view the floor camera's intrinsics give, and the two must not disagree.
    if (floor.enabled) {
      const double fov = floor.boundary.camera.HorizontalFovDeg();
      char reason[160];
      std::snprintf(reason, sizeof reason,
                    "must be floor_odometry.camera's horizontal field of view (%.2f degrees from its width, cx and fx) "
                    "within 0.5 degrees",
                    fov);
      Require(std::abs(visual.camera_fov_deg - fov) <= 0.5, "camera_fov_deg", reason);
    }
  }
};

// The column profiles' config as the odometry runs it: their pinhole camera (equal_angle_columns)
// tilted as floor_odometry.camera says, the one place the config gives the camera's pose. The
// odometry service (CameraOdometry) and the in-process runner both build theirs with it.
inline VisualOdometryConfig WithFloorCameraTilt(VisualOdometryConfig visual, const FloorOdometryNodeConfig& floor) {
  visual.camera_tilt_rad = floor.boundary.camera.tilt_rad;
  return visual;
}

}  // namespace rslam::odometry
