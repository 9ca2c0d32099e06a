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

// The grid's geometry and ROS cells (OccupancyGrid::ToRosCells); header and map_version are the
// caller's.
msg::OccupancyGrid GridToMessage(const OccupancyGrid& grid);

}  // namespace rslam::occupancy
