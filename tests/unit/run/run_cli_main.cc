// Test-only stand-in for the `rslam` binary: just the run subcommand.
#include <CLI/CLI.hpp>

#include "tools/run/run_command.h"

int main(int argc, char** argv) {
  CLI::App app{"rslam (run only, for tests)"};
  app.require_subcommand(1);
  rslam::run::RegisterRunCommand(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
