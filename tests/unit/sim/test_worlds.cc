#include "tests/unit/sim/test_worlds.h"

#include <vector>

namespace rslam::sim::testing {

std::string UwbRoomYamlPath() { return std::string(RSLAM_SOURCE_DIR) + "/deploy/worlds/uwb-room.yaml"; }

const WorldMap& UwbRoom() {
  static const WorldMap world = WorldMap::LoadFromYaml(UwbRoomYamlPath());
  return world;
}

WorldMap BoxRoom(int width, int height) {
  std::vector<CellClass> cells(static_cast<size_t>(width) * height, CellClass::kFree);
  for (int iy = 0; iy < height; ++iy) {
    for (int ix = 0; ix < width; ++ix) {
      if (ix == 0 || iy == 0 || ix == width - 1 || iy == height - 1) {
        cells[static_cast<size_t>(iy) * width + ix] = CellClass::kOccupied;
      }
    }
  }
  return WorldMap(width, height, 0.04, Eigen::Vector2d(0, 0), std::move(cells));
}

}  // namespace rslam::sim::testing
