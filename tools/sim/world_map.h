#pragma once
// The simulated world: a 2-D occupancy map in ROS map_server format (YAML + PGM), seen as a
// building whose occupied and unknown cells are walls (unknown is outside the building).
//
// Cells are indexed (ix, iy) with iy = 0 the BOTTOM row: cell (0, 0) is the lower-left pixel of
// the image, whose lower-left corner is the YAML `origin`. The image's row 0 is the top, i.e.
// iy = height - 1.

#include <Eigen/Core>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/math/pose2d.h"

namespace rslam::sim {

enum class CellClass : uint8_t { kFree = 0, kOccupied = 1, kUnknown = 2 };

// A world file that cannot be used; the message names the file and the problem.
class WorldFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The first wall hit by a horizontal ray.
struct RayHit {
  double distance = 0.0;        // metres from the ray origin to the wall face
  Eigen::Vector2d point{0, 0};  // world position of the hit on the face
  Eigen::Vector2i cell{0, 0};   // the wall cell hit (may be just outside the map)
  // Which face was hit, by the direction its outward normal points:
  // 0 = -x (west), 1 = +x (east), 2 = -y (south), 3 = +y (north).
  int face = 0;
};

class WorldMap {
 public:
  // cells: width * height classes, row-major with iy = 0 the bottom row.
  WorldMap(int width, int height, double resolution, Eigen::Vector2d origin, std::vector<CellClass> cells);

  // Loads a map_server YAML (image, resolution, origin, negate, occupied_thresh, free_thresh,
  // optional mode: trinary) and its binary PGM (P5, 8-bit). Throws WorldFileError.
  static WorldMap LoadFromYaml(const std::string& yaml_path);

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  const Eigen::Vector2d& origin() const { return origin_; }

  bool InBounds(const Eigen::Vector2i& cell) const {
    return cell.x() >= 0 && cell.y() >= 0 && cell.x() < width_ && cell.y() < height_;
  }
  // Outside the map is unknown.
  CellClass Classify(const Eigen::Vector2i& cell) const;
  // Occupied and unknown cells (and everything outside the map) block the robot and the camera.
  bool IsWall(const Eigen::Vector2i& cell) const {
    return !InBounds(cell) || walls_[static_cast<size_t>(cell.y() + 1) * padded_width_ + (cell.x() + 1)] != 0;
  }

  // The cell containing a world point (floor of the continuous grid coordinate).
  Eigen::Vector2i WorldToCell(const Eigen::Vector2d& p) const;
  // The world position of a cell's centre.
  Eigen::Vector2d CellCenter(const Eigen::Vector2i& cell) const;
  // Continuous grid coordinates: cell (ix, iy) spans [ix, ix+1) x [iy, iy+1).
  Eigen::Vector2d WorldToGrid(const Eigen::Vector2d& p) const { return (p - origin_) / resolution_; }

  // Casts a horizontal ray through the grid (DDA over exact cell boundaries) to the first wall.
  // A ray starting inside a wall hits at distance 0. Throws std::invalid_argument on non-finite
  // input. The map's border acts as a wall, so every ray ends.
  RayHit CastRay(const Eigen::Vector2d& from, double angle) const;
  // Same, with a precomputed unit direction (hot path of the renderer).
  RayHit CastRay(const Eigen::Vector2d& from, const Eigen::Vector2d& unit_direction) const;

  // Whether a disc of the given radius at p overlaps no wall cell.
  bool IsDiscFree(const Eigen::Vector2d& p, double radius) const;

  // Free cells reachable from the start point by 4-connected steps through free cells (flood
  // fill), sorted by (iy, ix). Empty when the start is not in a free cell. With a robot radius,
  // only cells where the robot's disc fits (centred on the cell) are entered: the places the robot
  // itself can reach, not squeezing through gaps narrower than the robot.
  std::vector<Eigen::Vector2i> ReachableFreeCells(const Eigen::Vector2d& start, double robot_radius_m = 0.0) const;

  // A deterministic sensible start: the free cell farthest from any wall within the largest
  // 4-connected free region (ties: nearest the region's centroid, then lowest iy, ix), heading 0.
  Pose2D DefaultStartPose() const;

  // Per-cell distance (m) to the nearest wall cell centre; row-major, iy = 0 bottom.
  std::vector<float> DistanceToWalls() const;

 private:
  const int width_;
  const int height_;
  const double resolution_;
  const Eigen::Vector2d origin_;
  const std::vector<CellClass> cells_;
  // Wall flags with a one-cell wall border, so ray casting needs no bounds checks.
  const int padded_width_;
  const std::vector<uint8_t> walls_;
};

}  // namespace rslam::sim
