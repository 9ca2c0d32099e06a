#pragma once
// A simulated run's odometry read again: each frame rendered anew where the robot truly stood
// (the simulator's renderer, the frame's own noise pattern) and read by CameraOdometry exactly as
// the odometry service reads it, then dead-reckoned and compared with the truth. Replaying a
// recorded demo run with its own config gives back its recorded odometry/velocity frame for frame
// (frames_differing_from_recorded 0); with changed odometry keys it measures what they change on
// the same path, with no live run's other randomness (the explorer's path, the map).
//
// Pure and deterministic: the caller reads the recording and the config.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "common/math/pose2d.h"
#include "rslam/msg/all_messages.h"
#include "services/odometry/odometry_node_config.h"
#include "tools/sim/sim_config.h"
#include "tools/sim/world_map.h"

namespace rslam::eval {

struct ReplayedFrame {
  uint64_t frame_seq = 0;  // selects the rendered noise pattern, as in the simulator
  int64_t stamp_ns = 0;    // strictly increasing
  Pose2D truth;
  // What the odometry service published for the frame, when recorded (vtrans m/s, vrot rad/s).
  std::optional<double> recorded_vtrans_mps, recorded_vrot_radps;
};

struct OdometryReplayResult {
  std::size_t frames = 0;
  double ate_m = 0.0;            // dead reckoning against the truth after a 2-D similarity alignment
  double scale = 1.0;            // of that alignment
  double heading_rms_rad = 0.0;  // dead-reckoned heading against the truth (both from the start)
  double final_heading_error_rad = 0.0;
  // Frames turning more than 0.01 rad whose turn read more than 0.03 rad wrong.
  std::size_t turn_frames_misread = 0;
  // Frames turning at most 0.01 rad whose turn read more than 0.03 rad: turns read where none was.
  std::size_t straight_frames_misread = 0;
  double turn_error_sum_rad = 0.0;  // sum over all frames of |turn read - true turn|
  // Frames whose velocity differs from the recorded one (by more than 1e-9), of those recorded.
  std::size_t frames_recorded = 0;
  std::size_t frames_differing_from_recorded = 0;
};

// Throws std::invalid_argument for fewer than two frames, stamps that do not increase, or a pose
// the renderer cannot use; ConfigError for a bad config. messages, if given, receives each frame's
// odometry/velocity as the odometry service would publish it (header: frame_seq and stamp).
OdometryReplayResult ReplayOdometry(const sim::WorldMap& world, const sim::SimConfig& sim,
                                    const odometry::OdometryNodeConfig& config, std::span<const ReplayedFrame> frames,
                                    std::vector<msg::Velocity>* messages = nullptr);

}  // namespace rslam::eval
