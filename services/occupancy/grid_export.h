#pragma once
// Writes an occupancy grid as a ROS map_server map (PGM + YAML: 254 free, 0 occupied, 205
// unknown, first image row = top of the map, origin = lower-left corner) or as a PNG with the
// same shades. File writing lives here so OccupancyGrid stays pure.

#include <filesystem>
#include <opencv2/core.hpp>

#include "services/occupancy/occupancy_grid.h"

namespace rslam::occupancy {

struct MapExportThresholds {
  double free_below = 0.196;     // map_server free_thresh
  double occupied_above = 0.65;  // map_server occupied_thresh
};

// The map_server image (CV_8U, row 0 = largest y).
cv::Mat RenderMapImage(const OccupancyGrid& grid, const MapExportThresholds& thresholds = {});

// Writes <base>.pgm and <base>.yaml. Throws std::runtime_error when a file cannot be written.
void WriteRosMap(const OccupancyGrid& grid, const std::filesystem::path& base,
                 const MapExportThresholds& thresholds = {});
void WritePng(const OccupancyGrid& grid, const std::filesystem::path& png_path,
              const MapExportThresholds& thresholds = {});

}  // namespace rslam::occupancy
