#pragma once
// Configuration space on the coarse exploration grid (paper 003 section 4, Fig. 5): occupied
// cells of the occupancy grid are dilated by the robot radius, then each coarse cell (a block of
// factor x factor occupancy cells) is occupied if any of its cells is (dilated) occupied, unknown
// (a goal) if at least min_unknown of its cells are unknown (with uncertain_cells_are_goals:
// unknown or uncertain), uncertain if it is no goal only because its uncertain cells do not count,
// and free otherwise; only free cells are driven through. A coarse cell bigger than
// the occupancy cell keeps paths away from walls ("too close" paths, Zelinsky) and cuts the
// number of moves.

#include <cstdint>
#include <vector>

#include "services/explorer/explorer_config.h"
#include "services/explorer/grid_view.h"

namespace rslam::explorer {

struct CoarseGrid {
  int width = 0;
  int height = 0;
  double cell_size_m = 0.0;
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
  std::vector<CellClass> cells;  // row-major from the lower-left cell
  // 1 where the block itself holds an occupied occupancy cell (or lies past the map edge): the
  // cells a robot that finds itself inside the dilation margin must not cross to get out.
  std::vector<uint8_t> obstacle;
  // 1 where the block holds an unknown or uncertain occupancy cell (whatever its class).
  std::vector<uint8_t> unseen;
  // 1 where a block of the margin (occupied by dilation, no obstacle of its own) holds what would
  // make it a goal and its centre is clear of obstacles by the robot radius plus
  // margin_goal_spare_m.
  std::vector<uint8_t> margin_goal;

  CellClass At(int x, int y) const { return cells[static_cast<size_t>(y) * width + x]; }
  bool Contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  double CentreX(int x) const { return origin_x_m + (x + 0.5) * cell_size_m; }
  double CentreY(int y) const { return origin_y_m + (y + 0.5) * cell_size_m; }
  int CellX(double x_m) const { return static_cast<int>(std::floor((x_m - origin_x_m) / cell_size_m)); }
  int CellY(double y_m) const { return static_cast<int>(std::floor((y_m - origin_y_m) / cell_size_m)); }
};

// Distance from (x, y) to the nearest centre of a cell that GridView::Blocks, at most radius_m.
// With away_x and away_y, adds to them for each such cell closer than radius_m the unit vector
// from it to (x, y), weighted by how far inside the radius it lies.
double Clearance(const GridView& occupancy, double x, double y, double radius_m, double* away_x = nullptr,
                 double* away_y = nullptr);

// Throws std::invalid_argument for an invalid view.
CoarseGrid BuildConfigurationSpace(const GridView& occupancy, const ExplorerConfig& config);

}  // namespace rslam::explorer
