#pragma once
// Worlds shared by the simulator tests.

#include <string>

#include "tools/sim/world_map.h"

namespace rslam::sim::testing {

// The repo's default world.
std::string UwbRoomYamlPath();
const WorldMap& UwbRoom();

// A rectangular room of width x height cells (resolution 0.04 m, origin (0, 0)) whose border
// cells are occupied; everything else free.
WorldMap BoxRoom(int width, int height);

}  // namespace rslam::sim::testing
