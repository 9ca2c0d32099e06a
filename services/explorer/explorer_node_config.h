#pragma once
// Configuration of the explorer service (YAML section `explorer`). The planner's keys sit at the
// top of the section. The robot radius default covers the simulator's robot (0.18 m) with a margin.

#include <cmath>
#include <cstdint>
#include <string>

#include "common/config/config_error.h"
#include "services/explorer/explorer_config.h"

namespace rslam::explorer {

inline ExplorerConfig SimulatorMatchedPlannerConfig() {
  ExplorerConfig c;
  c.robot_radius_m = 0.2;
  return c;
}

struct ExplorerNodeConfig {
  ExplorerConfig planner = SimulatorMatchedPlannerConfig();
  double feedback_timeout_s = 60.0;     // a command without DONE/BLOCKED for this long is given up
  double fresh_grid_timeout_s = 5.0;    // after a pirouette or a block, wait this long for a new grid
  int free_max_percent = 19;            // grid cells 0..free_max are free (map_server free_thresh)
  int occupied_min_percent = 65;        // occupied_min..100 are occupied; between = unknown
  int64_t max_grid_cells = 16'000'000;  // larger grids are rejected

  template <class V>
  void VisitFields(V& v) {
    planner.VisitFields(v);
    v("feedback_timeout_s", feedback_timeout_s,
      "seconds to wait for a command's DONE/BLOCKED (EXECUTING restarts the wait) before replanning");
    v("fresh_grid_timeout_s", fresh_grid_timeout_s,
      "seconds to wait for a grid newer than the last pirouette or blocked move before planning anyway");
    v("free_max_percent", free_max_percent, "grid cells up to this occupancy (%) are free");
    v("occupied_min_percent", occupied_min_percent, "grid cells from this occupancy (%) are occupied");
    v("max_grid_cells", max_grid_cells, "largest occupancy grid accepted (cells)");
  }

  void Validate() const {
    planner.Validate();
    Require(std::isfinite(feedback_timeout_s) && feedback_timeout_s > 0, "feedback_timeout_s", "must be positive");
    Require(std::isfinite(fresh_grid_timeout_s) && fresh_grid_timeout_s >= 0, "fresh_grid_timeout_s",
            "must be >= 0");
    Require(free_max_percent >= 0 && free_max_percent < 100, "free_max_percent", "must be 0..99");
    Require(occupied_min_percent > free_max_percent && occupied_min_percent <= 100, "occupied_min_percent",
            "must be above free_max_percent and at most 100");
    Require(max_grid_cells >= 1, "max_grid_cells", "must be >= 1");
  }
};

}  // namespace rslam::explorer
