#pragma once
// `rslam launch PROFILE` (start and supervise a set of services) and `rslam status` (the live
// services of every robot, from their heartbeats).

#include <CLI/CLI.hpp>

#include <string>

namespace rslam::launch {

void RegisterLaunchCommand(CLI::App& rslam);
void RegisterStatusCommand(CLI::App& rslam);

// The folder holding this executable (where rslam-* binaries are).
std::string ExecutableDir();
// deploy/ of the source tree (or $RSLAM_DEPLOY_DIR).
std::string DeployDir();

}  // namespace rslam::launch
