#pragma once
// The files `rslam demo` leaves behind besides summary.json: the occupancy grid as a map_server
// map (grid.pgm + grid.yaml), and two pictures: the experience map aligned over the ground-truth
// path (as paper 000 fig. 10), the occupancy grid with the robot's path, and the grid judged against
// the world cell by cell (where coverage and precision are lost).

#include <opencv2/core.hpp>

#include <filesystem>
#include <span>

#include "rslam/msg/all_messages.h"
#include "tools/demo/demo_monitor.h"
#include "tools/eval/trajectory_alignment.h"
#include "common/math/pose2d.h"
#include "tools/sim/world_map.h"

namespace rslam::demo {

// <base>.pgm (254 free, 0 occupied, 205 unknown, first row = top) and <base>.yaml. Throws
// std::runtime_error when a file cannot be written.
void WriteMapServerGrid(const msg::OccupancyGrid& grid, const std::filesystem::path& base);

// World map in the background, the true path (grey), the experiences moved by the alignment
// (blue), their links (green; loop closures red).
cv::Mat RenderExperienceMap(const sim::WorldMap& world, std::span<const FramePose> truth,
                            const msg::ExperienceMap* map, const eval::TrajectoryError* alignment);

// One row per experience of the final map: its id and pose in the map (as `rslam run`'s
// experiences.csv), the frame it was first current and the true pose then (world), its pose moved
// into the world by `alignment` (the ATE's similarity fit) and its distance from the truth there:
// where the map is off, and by how much. Truth and aligned columns are empty where unknown. Throws
// std::runtime_error when the file cannot be written.
void WriteExperiencesCsv(const msg::ExperienceMap& map, const DemoObservations& seen,
                         const eval::TrajectoryError* alignment, const std::filesystem::path& path);

// The grid (map_server shades) cropped to its known part, with the map-frame path in red.
cv::Mat RenderOccupancy(const msg::OccupancyGrid& grid, std::span<const FramePose> map_path);

// The world's cells coloured by what the grid (placed in the world by `map_origin`, the map frame's
// pose there) says of them, cropped to the reachable cells with a margin, as CompareGridWithWorld
// counts them: reachable cells the grid marks free white, unknown orange, uncertain yellow,
// occupied red; walls the grid marks free with no free world cell within `tolerance_m` blue;
// other free cells the grid marks occupied with no wall within it magenta; walls grey (black where
// the grid marks them occupied); other free cells light grey. One world cell is one or more
// pixels (at most 1000 a side, under a 40-pixel legend). Empty reachable set: the whole world.
cv::Mat RenderGridComparison(const sim::WorldMap& world, std::span<const Eigen::Vector2i> reachable,
                             const Pose2D& map_origin, const msg::OccupancyGrid& grid, double tolerance_m);

}  // namespace rslam::demo
