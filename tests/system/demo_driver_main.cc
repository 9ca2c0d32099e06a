// rslam-demo-driver demo [options]: `rslam demo` alone (the system test's fallback when the rslam
// command line does not have the demo subcommand).
#include <CLI/CLI.hpp>

#include "tools/demo/demo_command.h"

int main(int argc, char** argv) {
  CLI::App app{"rslam demo, standalone", "rslam-demo-driver"};
  app.require_subcommand(1);
  rslam::demo::RegisterDemoCommand(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
