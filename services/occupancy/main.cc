#include "common/node/service_main.h"
#include "services/occupancy/occupancy_node.h"

int main(int argc, char** argv) {
  return rslam::RunService<rslam::occupancy::OccupancyNode>(
      "occupancy", "Occupancy mapping from the floor camera, anchored to the experience map (paper 003)", argc, argv);
}
