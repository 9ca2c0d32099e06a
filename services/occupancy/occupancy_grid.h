#pragma once
// Occupancy grid updated by Bayes' rule in log-odds form (Moravec and Elfes, paper 003 ref. [11])
// with paper 003's vision sensor model (section 3.1, Fig. 4): along each bearing of a Radial
// Obstacle Profile, cells up to the measured range are free (a "miss"), the cell at the range is
// occupied (a "hit"), and nothing beyond the reliable range (40 cm for the paper's camera) is
// used. When an obstacle fills the view (a "blind" bearing), the blind area between the robot and
// the nearest visible floor is set to a probability halfway between unknown and occupied, unless
// the cell already holds evidence. Log-odds are clamped to [log_odds_min, log_odds_max] so the
// map can change again when the world does.
//
// The floor under the robot is free whatever the camera made of it: cells within
// footprint_radius_m of a pose a profile was taken at are read as min_probability, however many
// hits they hold (a costmap's footprint clearing). Without it a corrected map can lay a wall seen
// from elsewhere across the way the robot came in, and the explorer finds itself walled in: a demo
// run called exploration complete at coverage 0.28 that way, the robot's own path crossing the
// wall. The price: an obstacle put where the robot once stood is not mapped, and where the map is
// off (a pass laid over a wall seen from elsewhere) the footprint cuts a door into the wall that
// the explorer then drives into (demo runs with 0.18 m: 98-167 bumps each against 38-42 without),
// so it is off by default.
//
// As in Cartographer's ProbabilityGrid, a cell holds a 15-bit quantised log-odds (0 = never
// observed) and every update is one lookup in a table built once per sensor model; an update
// marker makes each profile update a cell at most once even where rays overlap.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "common/config/config_error.h"
#include "common/math/pose2d.h"
#include "services/occupancy/radial_obstacle_profile.h"

namespace rslam::occupancy {

struct GridConfig {
  double resolution_m = 0.01;
  int width = 1000;    // cells along x
  int height = 1000;   // cells along y
  double origin_x_m = -5.0;  // world position of the lower-left corner of cell (0, 0)
  double origin_y_m = -5.0;

  template <class V>
  void VisitFields(V& v) {
    v("resolution_m", resolution_m, "cell size (m)");
    v("width", width, "cells along x");
    v("height", height, "cells along y");
    v("origin_x_m", origin_x_m, "x of the lower-left corner of the grid (m)");
    v("origin_y_m", origin_y_m, "y of the lower-left corner of the grid (m)");
  }
  void Validate() const;
};

struct SensorModelConfig {
  double hit_probability = 0.7;
  double miss_probability = 0.4;
  double blind_probability = 0.75;  // halfway between unknown (0.5) and occupied (1.0)
  double min_probability = 0.12;    // clamps, so the map can change again
  double max_probability = 0.97;
  double reliable_range_m = 0.40;   // paper 003: +-1 px is under 0.5 cm up to about 40 cm
  double footprint_radius_m = 0.0;  // the floor under the robot is free (see above); 0: off

  template <class V>
  void VisitFields(V& v) {
    v("hit_probability", hit_probability, "P(occupied | obstacle seen in the cell)");
    v("miss_probability", miss_probability, "P(occupied | floor seen through the cell)");
    v("blind_probability", blind_probability, "probability given to the unknown blind area");
    v("min_probability", min_probability, "lower clamp of a cell's probability");
    v("max_probability", max_probability, "upper clamp of a cell's probability");
    v("reliable_range_m", reliable_range_m, "ranges beyond this are ignored (m)");
    v("footprint_radius_m", footprint_radius_m,
      "cells this close to a pose a profile was taken at are free, whatever was seen there (m; 0: off)");
  }
  void Validate() const;
};

struct CellIndex {
  int x = 0;
  int y = 0;
  bool operator==(const CellIndex&) const = default;
};

// The cells x0 <= x < x0 + width, y0 <= y < y0 + height.
struct CellWindow {
  int x0 = 0;
  int y0 = 0;
  int width = 0;
  int height = 0;
  bool operator==(const CellWindow&) const = default;
};

class OccupancyGrid {
 public:
  static constexpr uint16_t kUnknownValue = 0;
  static constexpr uint16_t kMaxValue = 32767;
  static constexpr uint16_t kUpdateMarker = 1u << 15;

  OccupancyGrid(GridConfig grid, SensorModelConfig sensor);
  OccupancyGrid(const OccupancyGrid&) = default;
  OccupancyGrid& operator=(const OccupancyGrid&) = default;
  OccupancyGrid(OccupancyGrid&&) = default;
  OccupancyGrid& operator=(OccupancyGrid&&) = default;

  // Inserts a profile taken at robot_pose (world frame). Returns the number of cell updates made.
  // Throws std::invalid_argument for a non-finite pose or a malformed profile.
  int64_t InsertProfile(const RadialObstacleProfile& profile, const Pose2D& robot_pose);
  void Clear();
  // Where along its ray an obstacle seen at range_m takes its hit: half a cell past the wall's
  // face, so of the two cells the face straddles the one holding more wall than floor is hit (the
  // face's own cell, when the face lies in its far half, is mostly floor).
  double HitRange(double range_m) const { return range_m + 0.5 * grid_.resolution_m; }

  const GridConfig& grid_config() const { return grid_; }
  const SensorModelConfig& sensor_config() const { return sensor_; }
  int width() const { return grid_.width; }
  int height() const { return grid_.height; }
  bool Contains(CellIndex c) const { return c.x >= 0 && c.y >= 0 && c.x < grid_.width && c.y < grid_.height; }
  CellIndex CellOf(double x_m, double y_m) const;
  bool IsKnown(CellIndex c) const { return Value(c) != kUnknownValue; }
  double LogOdds(CellIndex c) const { return ValueToLogOdds(Value(c)); }
  double Probability(CellIndex c) const;  // 0.5 for unknown cells; min_probability under a footprint
  // The stored log-odds value, footprints not applied.
  uint16_t Value(CellIndex c) const { return values_[static_cast<size_t>(c.y) * grid_.width + c.x]; }
  bool UnderFootprint(CellIndex c) const {
    return !footprint_.empty() && footprint_[static_cast<size_t>(c.y) * grid_.width + c.x] != 0;
  }

  // Quantisation between log-odds and stored values (kUnknownValue maps to log-odds 0).
  double ValueToLogOdds(uint16_t value) const;
  uint16_t LogOddsToValue(double log_odds) const;

  // The smallest window holding every cell a profile updated (or a footprint marked) since the
  // grid was made or cleared; none before the first.
  std::optional<CellWindow> SeenWindow() const;

  // ROS nav_msgs/OccupancyGrid convention: -1 unknown, else round(100 * p); row-major from the
  // window's lower-left cell (the whole grid's without one). Throws std::invalid_argument for a
  // window that is empty or not inside the grid.
  std::vector<int8_t> ToRosCells(const CellWindow& window) const;
  std::vector<int8_t> ToRosCells() const { return ToRosCells({0, 0, grid_.width, grid_.height}); }
  std::span<const uint16_t> values() const { return values_; }

 private:
  void ApplyRay(double x0, double y0, double x1, double y1, bool end_is_hit, const uint16_t* miss_table);
  void ApplyTable(size_t index, const uint16_t* table);

  GridConfig grid_;
  SensorModelConfig sensor_;
  double log_odds_min_ = 0.0, log_odds_max_ = 0.0;
  std::vector<uint16_t> hit_table_, miss_table_, blind_table_;
  std::vector<int8_t> percent_table_;  // stored value -> ROS cell (ToRosCells)
  void MarkFootprint(double gx, double gy);
  std::vector<uint16_t> values_;
  std::vector<uint8_t> footprint_;  // 1: a cell within footprint_radius_m of a profile's pose (empty when off)
  std::vector<size_t> updated_;  // cells carrying the update marker during one insertion
  void WidenSeen(int x0, int y0, int x1, int y1);
  int seen_x0_ = 0, seen_y0_ = 0, seen_x1_ = -1, seen_y1_ = -1;  // SeenWindow, inclusive; x1 < x0: none
  int64_t updates_in_profile_ = 0;
};

double LogOddsFromProbability(double p);
double ProbabilityFromLogOdds(double l);

}  // namespace rslam::occupancy
