// rslam: the command line. Each subcommand lives with its tool; this file only gathers them.

#include <CLI/CLI.hpp>

#include "tools/demo/demo_command.h"
#include "tools/eval/eval_command.h"
#include "tools/launch/launch_command.h"
#include "tools/record/record_command.h"
#include "tools/run/run_command.h"

int main(int argc, char** argv) {
  CLI::App app{"rslam: vision-only SLAM (RatSLAM) and camera-based occupancy mapping as DDS services", "rslam"};
  app.require_subcommand(1);
  rslam::demo::RegisterDemoCommand(app);
  rslam::launch::RegisterLaunchCommand(app);
  rslam::launch::RegisterStatusCommand(app);
  rslam::launch::RegisterPingCommand(app);
  rslam::run::RegisterRunCommand(app);
  rslam::record::RegisterRecordCommands(app);
  rslam::eval::RegisterEvalCommand(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
