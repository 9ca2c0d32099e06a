#include "services/experience_map/experience_map_node.h"

#include "common/node/service_main.h"

int main(int argc, char** argv) {
  return rslam::RunService<rslam::experience_map::ExperienceMapNode>(
      "experience_map", "RatSLAM experience map: pose-cell actions -> map, pose and snapshots", argc, argv);
}
