#include "services/pose_cells/pose_cells_node.h"

#include "common/node/service_main.h"

int main(int argc, char** argv) {
  return rslam::RunService<rslam::pose_cells::PoseCellsNode>(
      "pose_cells", "RatSLAM pose cells: odometry + views -> experience actions", argc, argv);
}
