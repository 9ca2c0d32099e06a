// Test-only stand-in for the `rslam` binary: just the eval subcommands.
#include <CLI/CLI.hpp>

#include "tools/eval/eval_command.h"

int main(int argc, char** argv) {
  CLI::App app{"rslam (eval only, for tests)"};
  app.require_subcommand(1);
  rslam::eval::RegisterEvalCommand(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
