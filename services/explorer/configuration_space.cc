#include "services/explorer/configuration_space.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace rslam::explorer {

namespace {

// True when no occupied cell's centre (or cell past the map's edge) lies within radius_m of (x, y).
bool ClearOfObstacles(const cv::Mat& occupied, const GridView& occupancy, double x, double y, double radius_m) {
  const double cx = (x - occupancy.origin_x_m) / occupancy.resolution_m - 0.5;
  const double cy = (y - occupancy.origin_y_m) / occupancy.resolution_m - 0.5;
  const double r = radius_m / occupancy.resolution_m;
  for (int gy = static_cast<int>(std::floor(cy - r)); gy <= static_cast<int>(std::ceil(cy + r)); ++gy)
    for (int gx = static_cast<int>(std::floor(cx - r)); gx <= static_cast<int>(std::ceil(cx + r)); ++gx) {
      if (std::hypot(gx - cx, gy - cy) > r) continue;
      if (gx < 0 || gy < 0 || gx >= occupancy.width || gy >= occupancy.height || occupied.at<uchar>(gy, gx))
        return false;
    }
  return true;
}

}  // namespace

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
          ClearOfObstacles(raw_occupied, occupancy, grid.CentreX(cx), grid.CentreY(cy),
                           config.robot_radius_m + config.margin_goal_spare_m);
    }
  }
  return grid;
}

}  // namespace rslam::explorer
