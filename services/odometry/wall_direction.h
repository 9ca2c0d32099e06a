#pragma once
// The direction of the walls a frame shows, modulo 90 degrees. Most walls of a building run along
// two perpendicular directions (the Manhattan-world assumption), so each frame that sees a
// straight wall says where the building's axes lie relative to the robot; the experience map
// holds the robot's heading to them (exp_manhattan, ExperienceMap::HoldHeading). Visual
// odometry's heading drifts (1-2 rad over a demo run of 350-560 m, its sign changing from run to
// run), and that drift, not the distance, makes most of the map's error.
//
// The floor boundary's points (robot frame, bearing order) within max_range_m give wall
// directions from point pairs baseline_points apart on one boundary line (no gap between them
// wider than 12 cm); their length-weighted mean direction, taken modulo 90 degrees (on 4 x angle),
// is the frame's wall direction if the segments add up to min_wall_m and agree (the mean's
// resultant length at least min_agreement: a round table, a corner of odd angle or a wall seen
// too far away for its rows to say much do not). On frames the simulator renders in the shipped
// world, nine in ten of the frames that give a direction give the building's axes within 0.05 rad
// (wall_direction_test.cc); a building whose walls meet at other angles gets no benefit.

#include <Eigen/Core>

#include <cmath>
#include <optional>
#include <span>

#include "common/config/config_error.h"

namespace rslam::odometry {

struct WallDirectionConfig {
  double max_range_m = 1.5;    // farther boundary points are too coarse (image rows) for a direction
  int baseline_points = 3;     // a wall direction from points this many bins apart
  double min_wall_m = 0.1;     // wall seen per frame
  double min_agreement = 0.9;  // resultant length of the wall directions (modulo 90 degrees)

  template <class V>
  void VisitFields(V& v) {
    v("max_range_m", max_range_m, "boundary points farther away are not used for wall directions (m)");
    v("baseline_points", baseline_points, "a wall direction from boundary points this many bearing bins apart");
    v("min_wall_m", min_wall_m, "length of wall a frame must see to give a direction (m)");
    v("min_agreement", min_agreement,
      "the frame's wall directions, modulo 90 degrees, must agree this well (resultant length 0..1)");
  }
  void Validate() const {
    Require(std::isfinite(max_range_m) && max_range_m > 0, "max_range_m", "must be positive");
    Require(baseline_points >= 1 && baseline_points <= 50, "baseline_points", "must be 1..50");
    Require(std::isfinite(min_wall_m) && min_wall_m > 0, "min_wall_m", "must be positive");
    Require(std::isfinite(min_agreement) && min_agreement > 0 && min_agreement <= 1, "min_agreement",
            "must be in (0, 1]");
  }
};

// The wall direction of one frame in the robot frame, in (-pi/4, pi/4], if it has one.
std::optional<double> WallDirection(std::span<const Eigen::Vector2d> boundary, const WallDirectionConfig& config);

}  // namespace rslam::odometry
