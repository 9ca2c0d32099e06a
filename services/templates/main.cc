#include "common/node/service_main.h"
#include "services/templates/templates_node.h"

int main(int argc, char** argv) {
  return rslam::RunService<rslam::templates::TemplatesNode>(
      "templates", "Local view: matches camera/image against learnt templates, publishes templates/view", argc,
      argv);
}
