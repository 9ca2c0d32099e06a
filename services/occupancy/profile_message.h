#pragma once
// The occupancy/profile message of a Radial Obstacle Profile and back, bin for bin: a consumer
// (a tool rebuilding the grid from a recording, another mapper) inserts exactly what the service
// inserted. The service publishes with ProfileToMessage; no service reads the topic today, so
// ProfileFromMessage is for such consumers (its test shows their grid is the service's).
// GridToMessage is the occupancy/grid message of a grid, as the service publishes it.

#include "rslam/msg/all_messages.h"
#include "services/occupancy/anchored_profile_map.h"

namespace rslam::occupancy {

// The profile anchored to its experience; max_range_m is the sensor model's reliable range (the
// grid trusts no range beyond it; bins may reach farther).
msg::ObstacleProfile ProfileToMessage(const msg::Header& header, const AnchoredProfile& anchored, float max_range_m);

// The profile of a message. Throws std::invalid_argument naming the problem (non-finite or
// non-positive bearing step or reliable range, a negative or non-finite range, an unknown status:
// the bus's decoder already refuses one on the wire, a message built in process may hold one).
RadialObstacleProfile ProfileFromMessage(const msg::ObstacleProfile& message);

// The part of a grid a message carries: the seen window (OccupancyGrid::SeenWindow) widened by
// kGridMessageMarginM of unknown cells, its edges rounded out to multiples of
// kGridMessageBlockCells from the grid's corner, clipped to the grid; the whole grid before
// anything was seen. A demo run's 40 m x 40 m grid (1,600 x 1,600 cells, 2.6 MB) is published ten
// times a simulated second to three readers; the room it maps is about a quarter of that. As the
// seen area grows, the window's origin moves by whole blocks, so a reader's cells (the explorer's
// 8-cell exploration cells) keep lining up with the grid's.
inline constexpr double kGridMessageMarginM = 1.0;
inline constexpr int kGridMessageBlockCells = 64;
CellWindow GridMessageWindow(const OccupancyGrid& grid);

// The occupancy/grid message: geometry and ROS cells (OccupancyGrid::ToRosCells) of
// GridMessageWindow; header and map_version are the caller's.
msg::OccupancyGrid GridToMessage(const OccupancyGrid& grid);

}  // namespace rslam::occupancy
