// rslam-sim: the simulated robot on the bus (camera, ground truth, wheel odometry, motion).
#include "tools/sim/sim_node.h"

#include "common/node/service_main.h"

int main(int argc, char** argv) {
  return rslam::RunService<rslam::sim::SimNode>(
      "sim", "rslam-sim: a simulated robot (camera, wheels, ground truth) exploring a world map", argc, argv);
}
