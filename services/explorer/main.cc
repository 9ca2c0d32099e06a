#include "common/node/service_main.h"
#include "services/explorer/explorer_node.h"

int main(int argc, char** argv) {
  return rslam::RunService<rslam::explorer::ExplorerNode>(
      "explorer", "Autonomous exploration by the distance transform, one motion command at a time (paper 003)",
      argc, argv);
}
