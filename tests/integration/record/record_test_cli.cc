// rslam-record-testcli: the record, play and info subcommands alone, for the integration tests
// (the same registration tools/rslam/main.cc uses; the tests prefer build/bin/rslam when it has
// them).
#include <CLI/CLI.hpp>

#include "tools/record/record_command.h"

int main(int argc, char** argv) {
  CLI::App app{"rslam record/play/info (test build)", "rslam"};
  app.require_subcommand(1);
  rslam::record::RegisterRecordCommands(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
