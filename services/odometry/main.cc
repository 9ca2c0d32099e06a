#include "common/node/service_main.h"
#include "services/odometry/odometry_node.h"

int main(int argc, char** argv) {
  return rslam::RunService<rslam::odometry::OdometryNode>(
      "odometry", "Visual odometry from camera/image (or wheel odometry) on odometry/velocity", argc, argv);
}
