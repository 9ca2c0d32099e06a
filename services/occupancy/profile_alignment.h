#pragma once
// Aligning a profile with the grid before it joins it (scan-to-map registration). Where the
// experience map is locally off, a place seen again is drawn a second time beside the first: a wall
// twice, the floor in front of the old wall under the new one. Such a profile's obstacle points,
// placed at its map pose, fall on floor the grid has seen free several times over, away from any
// obstacle. When at least min_misplaced_share of its points do, AlignProfile searches poses within
// window_m and window_rad of the map pose for the one whose points lie closest to the grid's
// obstacles (each point scores exp(-d^2 / 2 cell^2) for its distance d to the nearest occupied
// cell) and returns it if it scores min_gain_points more than the map pose.
//
// Only misplaced points open the search: a profile seeing a place for the first time has its
// points on unknown cells and is never moved onto walls seen before, and a point on a wall's edge
// (a cell a neighbouring ray saw free) is not misplaced. Rebuilt on the true poses of a demo run,
// the search moves 1-5% of the profiles and the grid's precision stays at 0.998-1.0.
//
// AnchoredProfileMap's rebuild aligns each profile against the profiles before it, all placed on
// the corrected map; aligning a profile as it arrives, against a grid a later correction will
// move, would move it twice (tools/demo/MEASUREMENTS.md).

#include <optional>

#include "common/config/config_error.h"
#include "common/math/pose2d.h"
#include "services/occupancy/occupancy_grid.h"
#include "services/occupancy/radial_obstacle_profile.h"

namespace rslam::occupancy {

struct ProfileAlignmentConfig {
  double window_m = 0.0;               // how far the search moves the pose each way (m); 0: off
  double window_rad = 0.1;             // how far it turns it each way (rad)
  double match_range_m = 1.5;          // obstacle points farther than this are not used (m)
  double min_misplaced_share = 0.1;    // share of the points on seen-free floor that opens a search
  double min_gain_points = 4.0;        // how much better the found pose must score (points' worth)

  template <class V>
  void VisitFields(V& v) {
    v("window_m", window_m, "search this far each way around a misplaced profile's map pose (m; 0: off)");
    v("window_rad", window_rad, "... and turn it this far each way (rad)");
    v("match_range_m", match_range_m, "obstacle points beyond this range are not matched (m)");
    v("min_misplaced_share", min_misplaced_share,
      "share of a profile's obstacle points on floor seen free (away from obstacles) that opens a search");
    v("min_gain_points", min_gain_points,
      "the found pose is taken when its points score this much more than at the map pose (points)");
  }
  void Validate() const {
    Require(std::isfinite(window_m) && window_m >= 0 && window_m <= 2, "window_m", "must be in [0, 2]");
    Require(std::isfinite(window_rad) && window_rad >= 0 && window_rad <= 1, "window_rad", "must be in [0, 1]");
    Require(std::isfinite(match_range_m) && match_range_m > 0, "match_range_m", "must be > 0");
    Require(std::isfinite(min_misplaced_share) && min_misplaced_share > 0 && min_misplaced_share <= 1,
            "min_misplaced_share", "must be in (0, 1]");
    Require(std::isfinite(min_gain_points) && min_gain_points >= 0, "min_gain_points", "must be >= 0");
  }
};

// True when min_misplaced_share of the profile's obstacle points at `pose` lie on floor the grid has
// seen free, away from any obstacle (and it has enough points to tell).
bool IsMisplaced(const OccupancyGrid& grid, const RadialObstacleProfile& profile, const Pose2D& pose,
                 const ProfileAlignmentConfig& config);

// The pose at which `profile` agrees better with `grid`, or nullopt to keep `pose` (search off, too
// few points, too few misplaced, or nothing better by min_gain_points).
std::optional<Pose2D> AlignProfile(const OccupancyGrid& grid, const RadialObstacleProfile& profile,
                                   const Pose2D& pose, const ProfileAlignmentConfig& config);

}  // namespace rslam::occupancy
