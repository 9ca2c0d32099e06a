#pragma once
// `rslam launch PROFILE` (start and supervise a set of services), `rslam status` (the live
// services of every robot, from their heartbeats) and `rslam ping` (a heartbeat of its own, to
// check a deployment's connectivity).

#include <CLI/CLI.hpp>

#include <string>

namespace rslam::launch {

void RegisterLaunchCommand(CLI::App& rslam);
void RegisterStatusCommand(CLI::App& rslam);
void RegisterPingCommand(CLI::App& rslam);

// The folder holding this executable (where rslam-* binaries are).
std::string ExecutableDir();
// deploy/ of the source tree (or $RSLAM_DEPLOY_DIR).
std::string DeployDir();

}  // namespace rslam::launch
