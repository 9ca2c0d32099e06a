#include "services/explorer/configuration_space.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace rslam::explorer {

double Clearance(const GridView& occupancy, double x, double y, double radius_m, double* away_x, double* away_y) {
  const double r = radius_m, res = occupancy.resolution_m;
  const int cx0 = static_cast<int>(std::floor((x - r - occupancy.origin_x_m) / res));
  const int cy0 = static_cast<int>(std::floor((y - r - occupancy.origin_y_m) / res));
  const int span = static_cast<int>(std::ceil(2 * r / res)) + 1;
  double nearest = r;
  for (int cy = cy0; cy <= cy0 + span; ++cy)
    for (int cx = cx0; cx <= cx0 + span; ++cx) {
      if (!occupancy.Blocks(cx, cy)) continue;
      const double dx = x - (occupancy.origin_x_m + (cx + 0.5) * res);
      const double dy = y - (occupancy.origin_y_m + (cy + 0.5) * res);
      const double d = std::hypot(dx, dy);
      if (d >= r) continue;
      nearest = std::min(nearest, d);
      if (away_x && away_y && d > 1e-9) {
        *away_x += (r - d) * dx / d;
        *away_y += (r - d) * dy / d;
      }
    }
  return nearest;
}

CoarseGrid BuildConfigurationSpace(const GridView& occupancy, const ExplorerConfig& config) {
  occupancy.Validate();
  const int w = occupancy.width, h = occupancy.height;
  // unknown: 1 for a cell never seen, 2 for an uncertain one.
  cv::Mat occupied(h, w, CV_8U), unknown(h, w, CV_8U);
  for (int y = 0; y < h; ++y) {
    uchar* occ = occupied.ptr<uchar>(y);
    uchar* unk = unknown.ptr<uchar>(y);
    const int8_t* row = occupancy.cells.data() + static_cast<size_t>(y) * w;
    for (int x = 0; x < w; ++x) {
      const CellClass c = occupancy.Classify(row[x]);
      occ[x] = c == CellClass::kOccupied ? 1 : 0;
      unk[x] = c == CellClass::kUnknown ? 1 : (c == CellClass::kUncertain ? 2 : 0);
    }
  }
  // One extra cell absorbs quantisation: any point of a free cell is then at least the robot radius
  // from every occupied cell centre, which is what ExplorationPlanner::IsPathClear checks.
  const int radius_cells = static_cast<int>(std::ceil(config.robot_radius_m / occupancy.resolution_m)) + 1;
  const cv::Mat raw_occupied = occupied.clone();
  {
    const cv::Mat disc = cv::getStructuringElement(
        cv::MORPH_ELLIPSE, cv::Size(2 * radius_cells + 1, 2 * radius_cells + 1));
    cv::dilate(occupied, occupied, disc);
  }
  const int f = config.coarse_cell_factor;
  const double spare_radius = config.robot_radius_m + config.margin_goal_spare_m;  // margin goals'
  CoarseGrid grid;
  grid.width = (w + f - 1) / f;
  grid.height = (h + f - 1) / f;
  grid.cell_size_m = occupancy.resolution_m * f;
  grid.origin_x_m = occupancy.origin_x_m;
  grid.origin_y_m = occupancy.origin_y_m;
  grid.cells.assign(static_cast<size_t>(grid.width) * grid.height, CellClass::kFree);
  grid.obstacle.assign(grid.cells.size(), 0);
  grid.unseen.assign(grid.cells.size(), 0);
  grid.margin_goal.assign(grid.cells.size(), 0);
  // Cells past the map edge count as occupied: the robot never plans to leave the map.
  for (int cy = 0; cy < grid.height; ++cy) {
    for (int cx = 0; cx < grid.width; ++cx) {
      int occ = 0, unseen = 0, uncertain = 0, raw = 0;
      for (int y = cy * f; y < cy * f + f; ++y) {
        if (y >= h) { occ += f; raw += f; continue; }
        const uchar* o = occupied.ptr<uchar>(y);
        const uchar* r = raw_occupied.ptr<uchar>(y);
        const uchar* u = unknown.ptr<uchar>(y);
        for (int x = cx * f; x < cx * f + f; ++x) {
          if (x >= w) { ++occ; ++raw; continue; }
          occ += o[x];
          raw += r[x];
          unseen += u[x] == 1;
          uncertain += u[x] == 2;
        }
      }
      grid.obstacle[static_cast<size_t>(cy) * grid.width + cx] = raw > 0;
      const int goal_cells = config.uncertain_cells_are_goals ? unseen + uncertain : unseen;
      CellClass& cell = grid.cells[static_cast<size_t>(cy) * grid.width + cx];
      if (occ > 0) cell = CellClass::kOccupied;
      else if (goal_cells >= config.min_unknown_cells_for_goal) cell = CellClass::kUnknown;
      else if (unseen + uncertain >= config.min_unknown_cells_for_goal) cell = CellClass::kUncertain;
      grid.unseen[static_cast<size_t>(cy) * grid.width + cx] = unseen + uncertain > 0;
      grid.margin_goal[static_cast<size_t>(cy) * grid.width + cx] =
          occ > 0 && raw == 0 && goal_cells >= config.min_unknown_cells_for_goal &&
          Clearance(occupancy, grid.CentreX(cx), grid.CentreY(cy), spare_radius) >= spare_radius;
    }
  }
  return grid;
}

}  // namespace rslam::explorer
