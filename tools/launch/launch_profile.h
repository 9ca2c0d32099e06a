#pragma once
// A launch profile (deploy/launch/*.yaml): which processes to start on this machine.
//
//   config: ../config/robot.yaml      # optional, passed to every service as --config (relative to the profile)
//   restart: {backoff_initial_s: 0.5, backoff_max_s: 10, max_restarts: 5}
//   processes:
//     - name: odometry                # runs rslam-odometry from the binary folder
//     - name: templates
//       dds: fastdds                  # this one on the other vendor
//       args: [--set, templates.mode=patch]
//     - name: recorder                # any rslam subcommand
//       command: [rslam, record, -o, base.mcap, --robot, "*"]

#include <map>
#include <string>
#include <vector>

#include "tools/launch/process_supervisor.h"

namespace rslam::launch {

struct LaunchEntry {
  std::string name;
  std::vector<std::string> command;  // empty = the service binary rslam-<name>
  std::vector<std::string> args;
  std::string dds;                   // empty = the launch's vendor
};

struct LaunchProfile {
  std::string path;
  std::string config;                // absolute path or ""
  RestartPolicy restart;
  std::vector<LaunchEntry> processes;
};

// A profile name ("robot", looked up in deploy/launch/ beside the binaries' source tree) or a
// path to a YAML file. Throws ConfigError naming the file and key.
LaunchProfile LoadLaunchProfile(const std::string& name_or_path, const std::string& launch_dir);

// The binary of a service: "pose_cells" -> "<bin_dir>/rslam-pose-cells".
std::string ServiceBinary(const std::string& bin_dir, const std::string& service);

struct LaunchOptions {
  std::string bin_dir;     // where rslam and rslam-* live
  std::string robot;       // --robot for every service
  std::string dds;         // --dds for every service (entries may override)
  int domain = -1;         // --domain for every service
  std::string config;      // overrides the profile's config
  std::string log_dir;     // per-process log files; empty = inherit the terminal
  std::string state_dir;   // --state-dir for every service
  std::vector<std::string> extra_args;  // appended to every service's arguments
};

std::vector<ProcessSpec> BuildProcessSpecs(const LaunchProfile& profile, const LaunchOptions& options);

}  // namespace rslam::launch
