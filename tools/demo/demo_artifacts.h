#pragma once
// The files `rslam demo` leaves behind besides summary.json: the occupancy grid as a map_server
// map (grid.pgm + grid.yaml), and two pictures: the experience map aligned over the ground-truth
// path (as paper 000 fig. 10) and the occupancy grid with the robot's path.

#include <opencv2/core.hpp>

#include <filesystem>
#include <span>

#include "rslam/msg/all_messages.h"
#include "tools/demo/demo_monitor.h"
#include "tools/eval/trajectory_alignment.h"
#include "tools/sim/world_map.h"

namespace rslam::demo {

// <base>.pgm (254 free, 0 occupied, 205 unknown, first row = top) and <base>.yaml. Throws
// std::runtime_error when a file cannot be written.
void WriteMapServerGrid(const msg::OccupancyGrid& grid, const std::filesystem::path& base);

// World map in the background, the true path (grey), the experiences moved by the alignment
// (blue), their links (green; loop closures red).
cv::Mat RenderExperienceMap(const sim::WorldMap& world, std::span<const FramePose> truth,
                            const msg::ExperienceMap* map, const eval::TrajectoryError* alignment);

// The grid (map_server shades) cropped to its known part, with the map-frame path in red.
cv::Mat RenderOccupancy(const msg::OccupancyGrid& grid, std::span<const FramePose> map_path);

}  // namespace rslam::demo
