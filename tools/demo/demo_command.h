#pragma once
// `rslam demo`: a simulated robot explores a world with the seven services as separate
// processes on the bus (rslam-sim + camera, odometry, templates, pose_cells, experience_map,
// occupancy, explorer, and a recorder), then reports how good the map is against ground truth.
//
//   rslam demo [--out DIR] [--world FILE.yaml] [--dds cyclone|fastdds] [--max-seconds N]
//              [--domain N] [--wheel-odometry]
//
// Writes into DIR (default ./demo-out): summary.json, report.txt, experience_map.png,
// occupancy.png, grid.pgm + grid.yaml, recording.mcap, logs/*.log, state/.

#include <CLI/CLI.hpp>

#include <string>

namespace rslam::demo {

struct DemoOptions {
  std::string out_dir = "demo-out";
  std::string world;          // empty = the config's (the shipped uwb-room)
  std::string dds;            // empty = env RSLAM_DDS, else cyclone
  int domain = -1;            // -1 = env RSLAM_DOMAIN, else 17
  double max_seconds = 280;
  bool wheel_odometry = false;
  bool record_images = false;
  std::string config;         // empty = deploy/config/demo.yaml
  std::string bin_dir;        // empty = beside this executable
  std::string robot = "robot1";
};

// Runs the demo; returns the process exit code (0 when the run finished and wrote its results,
// also when exploration did not complete in time: summary.json says so).
int RunDemo(const DemoOptions& options);

void RegisterDemoCommand(CLI::App& rslam);

}  // namespace rslam::demo
