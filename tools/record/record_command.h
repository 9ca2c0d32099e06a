#pragma once
// `rslam record` (DDS topics into MCAP), `rslam play` (MCAP back onto the bus) and `rslam info`
// (what a recording holds; --recover repairs one left by a killed recorder).

#include <CLI/CLI.hpp>

namespace rslam::record {

// Adds the record, play and info subcommands.
void RegisterRecordCommands(CLI::App& rslam);

}  // namespace rslam::record
