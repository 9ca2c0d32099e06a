#pragma once
// What the explorer reads: a borrowed occupancy grid in the ROS nav_msgs/OccupancyGrid convention
// (-1 unknown, 0..100 percent occupied, row-major from the lower-left cell at origin), plus the
// thresholds that classify a cell. A cell seen but between the thresholds is uncertain: a wall
// seen once, or a cell a map correction keeps moving a wall across.

#include <cmath>
#include <cstdint>
#include <span>
#include <stdexcept>

#include "common/math/pose2d.h"

namespace rslam::explorer {

// kUncertain: seen, neither free nor occupied enough (a coarse cell: one that holds such cells and
// is not a goal, see ExplorerConfig::uncertain_cells_are_goals).
enum class CellClass : uint8_t { kFree = 0, kOccupied = 1, kUnknown = 2, kUncertain = 3 };

struct GridView {
  int width = 0;
  int height = 0;
  double resolution_m = 0.0;
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
  std::span<const int8_t> cells;
  int free_max_percent = 19;      // 0..free_max is free (map_server free_thresh 0.196)
  int occupied_min_percent = 65;  // occupied_min..100 is occupied; between is uncertain

  CellClass Classify(int8_t v) const {
    if (v < 0) return CellClass::kUnknown;
    if (v >= occupied_min_percent) return CellClass::kOccupied;
    if (v <= free_max_percent) return CellClass::kFree;
    return CellClass::kUncertain;
  }
  CellClass ClassAt(int x, int y) const { return Classify(cells[static_cast<size_t>(y) * width + x]); }
  // An occupied cell, or one past the map's edge: what the robot must keep its radius from.
  bool Blocks(int x, int y) const {
    return x < 0 || y < 0 || x >= width || y >= height || ClassAt(x, y) == CellClass::kOccupied;
  }

  // Throws std::invalid_argument naming the problem.
  void Validate() const {
    if (width <= 0 || height <= 0) throw std::invalid_argument("grid view has no cells");
    if (cells.size() != static_cast<size_t>(width) * height)
      throw std::invalid_argument("grid view cell count does not match width x height");
    if (!std::isfinite(resolution_m) || resolution_m <= 0)
      throw std::invalid_argument("grid view resolution must be positive");
    if (!std::isfinite(origin_x_m) || !std::isfinite(origin_y_m))
      throw std::invalid_argument("grid view origin is not finite");
    if (free_max_percent < 0 || occupied_min_percent > 100 || free_max_percent >= occupied_min_percent)
      throw std::invalid_argument("grid view thresholds must satisfy 0 <= free_max < occupied_min <= 100");
  }
};

}  // namespace rslam::explorer
