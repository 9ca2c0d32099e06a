#pragma once
// One robot's frames of a recording (`rslam demo`'s recording.mcap, or any `rslam record` file),
// each frame's messages decoded and joined by frame number: what the replays of `rslam eval`
// (odometry_replay.h, map_replay.h) run the services' libraries on.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/math/pose2d.h"
#include "rslam/msg/all_messages.h"

namespace rslam::eval {

struct RecordedFrame {
  uint64_t frame_seq = 0;
  int64_t stamp_ns = 0;                      // sim/ground_truth's stamp, else the first message's read
  std::optional<Pose2D> truth;               // sim/ground_truth
  std::optional<msg::Velocity> velocity;     // odometry/velocity
  std::optional<msg::ViewTemplate> view;     // templates/view
  std::optional<msg::PoseCellAction> action; // pose_cells/action
  std::optional<msg::ObstacleProfile> profile;  // occupancy/profile
};

struct RecordedRun {
  std::string robot;
  std::vector<RecordedFrame> frames;  // by frame number
  // "topic: why" of the channels left out: recorded by a build whose message definition differs
  // from this build's (they would not decode).
  std::vector<std::string> skipped;
};

// The frames of `robot` (empty: the first robot whose frame message is read). Throws
// std::runtime_error for a file that is not a readable MCAP recording, and
// std::invalid_argument (naming the topic and frame) for a message that does not decode.
RecordedRun ReadRecordedRun(const std::string& path, const std::string& robot = "");

}  // namespace rslam::eval
