#pragma once
// Heading held by the building's walls. Most walls of a building run along two perpendicular
// directions (the Manhattan-world assumption); the floor boundary shows the walls in view, so the
// heading the odometry has integrated can be compared, modulo 90 degrees, with the direction of
// the walls it saw at the start, and the difference (drift, if the wall is one of those) taken out
// a little at a time. Visual odometry's heading drifts (1-2 rad over a demo run of 350-560 m, its
// sign changing from run to run), and that drift, not the distance, makes most of the map's error.
//
// Per frame: the boundary points (robot frame, bearing order) within max_range_m give wall
// directions from point pairs baseline_points apart on one boundary line (no gap between them
// wider than 12 cm); their length-weighted mean direction, taken modulo 90 degrees (on 4 x angle),
// is this frame's wall direction if the segments add up to min_wall_m and agree (the mean's
// resultant length at least min_agreement: a round table, a corner of odd angle or a wall seen
// too far away for its rows to say much do not). The first reference_frames wall directions
// (in the integrated heading's frame) fix the axes, if they agree as well (else the next ones
// are tried). After that a wall direction within max_offset_rad of an axis moves the heading
// gain of the way onto it; one farther off is some other wall and is ignored.
//
// Seven recorded demo paths (visual odometry, 11,000-50,000 frames) rendered again with it:
// dead-reckoning ATE 2.32 / 0.93 / 3.04 / 4.10 -> 1.23 / 0.51 / 1.68 / 3.62 m, but 3.72 / 2.49 /
// 3.03 -> 4.52 / 3.31 / 3.13 m. Nine frames in ten of those that give a wall direction give the
// building's axes within 0.05 rad; what fails is holding to them: the axes are fixed from the
// first frames, whose heading has already drifted (0.19 rad on one path), and a drift past
// max_offset_rad between walls loses them. So it is off unless configured (the demo's too). A
// building whose walls meet at other angles gets no benefit; walls a little off its axes pull wrong.

#include <Eigen/Core>

#include <optional>
#include <span>

#include "common/config/config_error.h"

namespace rslam::odometry {

struct ManhattanHeadingConfig {
  bool enabled = false;
  double max_range_m = 1.5;       // farther boundary points are too coarse (image rows) for a direction
  int baseline_points = 3;        // a wall direction from points this many bins apart
  double min_wall_m = 0.1;        // wall seen per frame
  double min_agreement = 0.9;     // resultant length of the wall directions (modulo 90 degrees)
  int reference_frames = 50;      // frames with a wall direction that fix the axes
  double max_offset_rad = 0.25;   // a wall farther off an axis is not one of the building's axes
  double gain = 0.2;              // share of the offset taken out per frame

  template <class V>
  void VisitFields(V& v) {
    v("enabled", enabled, "hold the heading to the walls' two perpendicular directions (Manhattan world)");
    v("max_range_m", max_range_m, "boundary points farther away are not used for wall directions (m)");
    v("baseline_points", baseline_points, "a wall direction from boundary points this many bearing bins apart");
    v("min_wall_m", min_wall_m, "length of wall a frame must see to give a direction (m)");
    v("min_agreement", min_agreement,
      "the frame's wall directions, modulo 90 degrees, must agree this well (resultant length 0..1)");
    v("reference_frames", reference_frames, "frames with a wall direction that fix the axes at the start");
    v("max_offset_rad", max_offset_rad, "a wall direction farther than this from an axis is ignored (rad)");
    v("gain", gain, "share of a wall direction's offset from its axis taken out of the heading per frame");
  }
  void Validate() const {
    Require(std::isfinite(max_range_m) && max_range_m > 0, "max_range_m", "must be positive");
    Require(baseline_points >= 1 && baseline_points <= 50, "baseline_points", "must be 1..50");
    Require(std::isfinite(min_wall_m) && min_wall_m > 0, "min_wall_m", "must be positive");
    Require(std::isfinite(min_agreement) && min_agreement > 0 && min_agreement <= 1, "min_agreement",
            "must be in (0, 1]");
    Require(reference_frames >= 1, "reference_frames", "must be >= 1");
    Require(std::isfinite(max_offset_rad) && max_offset_rad > 0 && max_offset_rad < 0.785, "max_offset_rad",
            "must be in (0, pi/4)");
    Require(std::isfinite(gain) && gain > 0 && gain <= 1, "gain", "must be in (0, 1]");
  }
};

class ManhattanHeading {
 public:
  explicit ManhattanHeading(ManhattanHeadingConfig config);  // throws ConfigError on a bad config

  // boundary: this frame's floor-boundary points in the robot frame, bearing order; heading: the
  // odometry's integrated heading at this frame (rad). Returns the correction to add to it.
  double Update(std::span<const Eigen::Vector2d> boundary, double heading);

  // The wall direction of one frame in the robot frame, in (-pi/4, pi/4], if it has one.
  std::optional<double> WallDirection(std::span<const Eigen::Vector2d> boundary) const;
  // The axes (one direction modulo pi/2) in the integrated heading's frame, once fixed.
  std::optional<double> axes() const { return axes_; }

 private:
  const ManhattanHeadingConfig config_;
  std::optional<double> axes_;
  double sum_cos_ = 0.0, sum_sin_ = 0.0;  // of 4 x the wall directions while fixing the axes
  int reference_count_ = 0;
};

}  // namespace rslam::odometry
