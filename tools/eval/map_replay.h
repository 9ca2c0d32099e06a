#pragma once
// A recorded run's map built again: each frame's recorded odometry/velocity (with its floor boundary
// and wall direction) and templates/view through the pose-cell network, its action through the
// experience map, and its recorded occupancy/profile anchored to the replayed map and drawn into a
// grid once the map is final, every step the call the service makes (pose_cell_action_message.h,
// experience_action_message.h, anchored_profile_map.h). With the run's own config the pose cells
// give back every recorded pose_cells/action (actions_differing 0) and the map is the run's; with
// changed pose_cells or experience_map keys it shows what they change on the same route, free of a
// live run's other chances (the explorer goes where the map sends it, so a live run with a change
// also drives elsewhere).
//
// The grid differs from the run's by its rebuild history alone: the service rebuilds the grid on
// another thread as corrections come, each rebuild aligning only the profiles whose placement
// moved (profile_alignment.h); here the profiles are drawn and aligned once, on the final map.
//
// Pure and deterministic: the caller reads the recording and the config.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <vector>

#include "services/experience_map/experience_map.h"
#include "services/experience_map/experience_map_node_config.h"
#include "services/occupancy/occupancy_node_config.h"
#include "services/pose_cells/pose_cells_node_config.h"
#include "tools/demo/demo_monitor.h"
#include "tools/eval/recorded_run.h"

namespace rslam::eval {

struct MapReplayConfig {
  pose_cells::PoseCellsNodeConfig pose_cells;
  experience_map::ExperienceMapNodeConfig experience_map;
  occupancy::OccupancyNodeConfig occupancy;
  // Apply the recorded pose_cells/action messages instead of running the pose cells (for a
  // recording without velocities or views, or to replay only the map's keys).
  bool recorded_actions = false;
};

struct MapReplayResult {
  // What `rslam demo` would have seen: ground truth, the replayed map's pose at every frame and the
  // frame each experience was first current, the odometry, the final map and grid, the templates.
  demo::DemoObservations seen;
  std::size_t actions_compared = 0;   // replayed actions with a recorded one for their frame
  std::size_t actions_differing = 0;  // ... that differ from it (kind, ids, offsets, angle, odometry)
  std::size_t profiles_kept = 0;      // drawn into the grid (the others added nothing new)
  // experience_map.exp_manhattan: the frame whose wall direction fixed the walls' axes, and the
  // axes (rad, modulo pi/2, in the map frame); none if they were never fixed.
  struct AxesFixed {
    uint64_t frame = 0;
    double rad = 0.0;
  };
  std::optional<AxesFixed> axes_fixed;
  // experience_map.exp_manhattan_recapture_frames: each heading recapture, its frame and the
  // heading it took out (rad).
  struct Recapture {
    uint64_t frame = 0;
    double taken_rad = 0.0;
  };
  std::vector<Recapture> heading_recaptures;
  // experience_map.exp_scan_links: registrations tried, and the links kept (the newer
  // experience's pose in the older's, as measured).
  std::size_t scan_registrations = 0;
  std::vector<experience_map::ScanLink> scan_links;
};

// A scan link judged against the truth: its measurement against the true pose of its newer
// experience in its older's frame (ExperienceGroundTruth).
struct ScanLinkError {
  uint32_t from_id = 0, to_id = 0;
  double position_m = 0.0, heading_rad = 0.0;
};
// The links whose two ends have a ground-truth pose, in the map's order.
std::vector<ScanLinkError> JudgeScanLinks(std::span<const experience_map::ScanLink> links,
                                          const std::map<uint32_t, Pose2D>& experience_truth);

// A heading recapture judged against the truth: the robot's heading error in the map (placed in
// the world at map_origin, demo::MapOrigin) on the replayed frame before it and on its own frame.
struct RecaptureError {
  uint64_t frame = 0;
  double taken_rad = 0.0;
  double error_before_rad = 0.0, error_after_rad = 0.0;
  // It took the heading toward the truth: the error after is the smaller.
  bool TowardTruth() const { return std::abs(error_after_rad) < std::abs(error_before_rad); }
};
// The recaptures whose two frames have a map pose and a ground-truth pose, in order.
std::vector<RecaptureError> JudgeRecaptures(std::span<const MapReplayResult::Recapture> recaptures,
                                            const demo::DemoObservations& seen, const Pose2D& map_origin);

// Throws std::invalid_argument when the run has no frame to replay (no velocity or view, or with
// recorded_actions no action) or a frame's message is one the service would refuse.
MapReplayResult ReplayMap(const RecordedRun& run, const MapReplayConfig& config);

}  // namespace rslam::eval
